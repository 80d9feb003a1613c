"""Strain-energy models: closed-form Neo-Hookean stresses against FE solutions, the small-load
limit of every model, and the tangent against finite differences of the residual.

The closed forms are derived by hand from thesis eq. 4.4 (φ = μ/2 (I1 - 3) - μ ln J + λ/2 (ln J)²):
``P = ∂φ/∂F = μ (F - F⁻ᵀ) + λ ln J F⁻ᵀ``, ``σ = P Fᵀ / J``.
"""
import numpy as np
import pytest
from scipy.optimize import brentq

from nonlinear_setup import cantilever, cantilever_mesh
from pacto_ng.mesh import Layout, Segment, netgen_mesh, structured_mesh
from pacto_ng.physics.loads import PointLoad
from pacto_ng.physics.materials import (first_piola_kirchhoff, jacobian, lame, linear_energy,
                                        neohookean_energy, plane_stress_stretch,
                                        second_piola_kirchhoff, svk_energy)
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings, newton_step_solve


pytestmark = pytest.mark.usefixtures("one_thread")


E_SQ, NU_SQ, T_SQ = 2.0e6, 0.4, 0.1  # the unit square's material and thickness
TIGHT = NewtonSettings(rtol=1e-12, initial_increment=0.25)


def square_mesh(kind):
    lay = Layout(1.0, 1.0, segments=(
        Segment("left", (0, 0), (0, 1)), Segment("right", (1, 0), (1, 1)),
        Segment("bottom", (0, 0), (1, 0)), Segment("top", (0, 1), (1, 1))))
    if kind == "quad":
        return structured_mesh(lay, 3, 3)
    return netgen_mesh(lay, 0.4)


def nh_pk1(F, E, nu, F33=1.0):
    """Hand-derived ``P = μ (F - F⁻ᵀ) + λ ln J F⁻ᵀ`` (in-plane block; J = F33 det F)."""
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    Fit = np.linalg.inv(F).T
    J = F33 * np.linalg.det(F)
    return mu * (F - Fit) + lam * np.log(J) * Fit


def reaction(mech, boundary, direction):
    """Resultant force on a boundary from the residual (internal forces) at the solution."""
    from ngsolve import CF, BND, GridFunction

    r = mech.gfu.vec.CreateVector()
    mech.residual(mech.gfu.vec, r, 0.0)
    w = GridFunction(mech.fes)
    w.Set(CF(tuple(direction)), BND, definedon=mech.mesh.Boundaries(boundary))
    return float(r.InnerProduct(w.vec))


def square_mech(mesh, order, plane, supports, loads=()):
    energy = lambda G, c: neohookean_energy(G, E_SQ, NU_SQ, plane)
    return Mechanics(mesh, order=order, energy=energy, supports=supports, loads=loads,
                     thickness=T_SQ, guard=lambda G, c: jacobian(G), newton=TIGHT)


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("kind,order", [("quad", 1), ("trig", 2)])
@pytest.mark.parametrize("stretch", [1.6, 0.6])
def test_neohookean_uniaxial_plane_strain(kind, order, stretch):
    """Laterally confined uniaxial stretch F = diag(λ1, 1): the FE body under the closed-form
    traction P11 stretches to λ1, and the confining reaction on the top equals P22 L t."""
    F = np.diag([stretch, 1.0])
    P = nh_pk1(F, E_SQ, NU_SQ)
    mesh = square_mesh(kind)
    mech = square_mech(mesh, order, "strain", Supports(fix_x=("left",), fix_y=("bottom", "top")),
                       loads=(PointLoad("right", (P[0, 0] * 1.0 * T_SQ, 0.0)),))
    mech.forward(np.ones(mesh.ne))
    for X, Y in [(1.0, 0.5), (0.5, 0.25), (0.3, 0.9)]:
        ux, uy = mech.gfu(mesh(X, Y))
        assert ux == pytest.approx((stretch - 1.0) * X, rel=1e-9, abs=1e-12)
        assert abs(uy) < 1e-10
    # P22 = λ ln λ1 from the FE stress (by Diff) and from the top reaction
    from ngsolve import Grad

    P_cf = first_piola_kirchhoff(lambda G: neohookean_energy(G, E_SQ, NU_SQ), Grad(mech.gfu))
    Pfe = np.array(P_cf(mesh(0.4, 0.6))).reshape(2, 2)
    assert np.allclose(Pfe, P, rtol=1e-9, atol=1e-9 * abs(P).max())
    assert reaction(mech, "top", (0.0, 1.0)) == pytest.approx(P[1, 1] * 1.0 * T_SQ, rel=1e-8)


@pytest.mark.parametrize("kind,order", [("quad", 1), ("quad", 2), ("trig", 1), ("trig", 2)])
def test_neohookean_simple_shear(kind, order):
    """Simple shear u = (κY, 0) prescribed on the whole boundary: Newton recovers it inside
    (from a perturbed start), the Cauchy stress is μ [[κ², κ], [κ, 0]] and the shear force on
    the top is μ κ L t."""
    from ngsolve import BND, CF, Grad, GridFunction, x, y

    kappa = 0.8
    mu = E_SQ / (2 * (1 + NU_SQ))
    mesh = square_mesh(kind)
    mech = square_mech(mesh, order, "strain", Supports(clamp=("left", "right", "bottom", "top")))
    mech.set_fields(np.ones(mesh.ne))
    bubble = 16.0 * x * (1.0 - x) * y * (1.0 - y)  # zero on the boundary
    mech.gfu.Set(CF((kappa * y + 0.05 * bubble, -0.05 * bubble)))  # start off the solution
    exact = GridFunction(mech.fes)
    exact.Set(CF((kappa * y, 0.0)), BND, definedon=mesh.Boundaries(".*"))
    fixed = ~mech.free
    mech.gfu.vec.FV().NumPy()[fixed] = exact.vec.FV().NumPy()[fixed]
    ok, its, why, res = newton_step_solve(mech, mech.gfu.vec, 0.0, mu * kappa * T_SQ, TIGHT)
    assert ok, why
    assert its >= 3  # the perturbation had to be removed by Newton
    F = np.array([[1.0, kappa], [0.0, 1.0]])
    sigma_exact = mu * np.array([[kappa ** 2, kappa], [kappa, 0.0]])
    phi = lambda G: neohookean_energy(G, E_SQ, NU_SQ)
    P = first_piola_kirchhoff(phi, Grad(mech.gfu))
    for X, Y in [(0.5, 0.5), (0.21, 0.77)]:
        Pfe = np.array(P(mesh(X, Y))).reshape(2, 2)
        sigma = Pfe @ F.T / np.linalg.det(F)
        assert np.allclose(sigma, sigma_exact, rtol=1e-9, atol=1e-9 * mu)
        assert np.allclose(Pfe, nh_pk1(F, E_SQ, NU_SQ), atol=1e-9 * mu)
    assert reaction(mech, "top", (1.0, 0.0)) == pytest.approx(mu * kappa * 1.0 * T_SQ, rel=1e-8)


@pytest.mark.parametrize("stretch", [1.8, 0.7])
def test_neohookean_uniaxial_plane_stress(stretch):
    """Plane-stress uniaxial stress: lateral and out-of-plane stretches λ2 = λ3 from P22 = 0
    (a scalar root, brentq), axial load P11; the FE body (free top, free thickness) reproduces
    λ1, λ2 and F33 = λ3."""
    mu, lam = lame(E_SQ, NU_SQ)
    l2 = brentq(lambda s: mu * (s * s - 1.0) + lam * np.log(stretch * s * s), 1e-3, 1e3, xtol=1e-15)
    F = np.diag([stretch, l2])
    P = nh_pk1(F, E_SQ, NU_SQ, F33=l2)
    assert abs(P[1, 1]) < 1e-9 * abs(P[0, 0])
    mesh = square_mesh("quad")
    mech = square_mech(mesh, 1, "stress", Supports(fix_x=("left",), fix_y=("bottom",)),
                       loads=(PointLoad("right", (P[0, 0] * 1.0 * T_SQ, 0.0)),))
    mech.forward(np.ones(mesh.ne))
    ux, uy = mech.gfu(mesh(1.0, 1.0))
    assert ux == pytest.approx(stretch - 1.0, rel=1e-9)
    assert uy == pytest.approx(l2 - 1.0, rel=1e-9)
    from ngsolve import Grad

    c = plane_stress_stretch(Grad(mech.gfu), NU_SQ)(mesh(0.5, 0.5))
    assert c == pytest.approx(l2, rel=1e-12)


def test_plane_stress_stretch_solves_s33_zero():
    """F33 from the CF iteration against a scalar root of S33 = 0 over extreme deformations."""
    from ngsolve import CF, VectorH1, GridFunction, Grad, x, y
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(nx=1, ny=1)
    gfu = GridFunction(VectorH1(mesh, order=1))
    mp = mesh(0.3, 0.6)
    for nu in (0.1, 0.3, 0.45, 0.499):
        mu, lam = lame(1.0, nu)
        for g in [(0.5, 0.2, -0.1, 0.3), (-0.6, 0.1, 0.05, -0.5), (9.0, 1.0, 0.0, 3.0),
                  (-0.999, 0.0, 0.0, -0.9)]:
            gfu.Set(CF((g[0] * x + g[1] * y, g[2] * x + g[3] * y)))
            J2 = (1 + g[0]) * (1 + g[3]) - g[1] * g[2]
            c_ref = brentq(lambda c: mu * (c * c - 1) + lam * np.log(J2 * c), 1e-8, 1e8,
                           xtol=1e-300, rtol=1e-15)
            assert plane_stress_stretch(Grad(gfu), nu)(mp) == pytest.approx(c_ref, rel=1e-13)


def test_pk2_of_neohookean_matches_closed_form():
    """S = F⁻¹ ∂φ/∂F (by Diff) equals the hand form μ (I - C⁻¹) + λ ln J C⁻¹ (plane strain)."""
    from ngsolve import CF, VectorH1, GridFunction, Grad, x, y
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(nx=1, ny=1)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((0.4 * x - 0.3 * y, 0.2 * x - 0.25 * y)))
    F = np.array([[1.4, -0.3], [0.2, 0.75]])
    mu, lam = lame(E_SQ, NU_SQ)
    Ci = np.linalg.inv(F.T @ F)
    S_exact = mu * (np.eye(2) - Ci) + lam * np.log(np.linalg.det(F)) * Ci
    S = second_piola_kirchhoff(lambda G: neohookean_energy(G, E_SQ, NU_SQ), Grad(gfu))
    assert np.allclose(np.array(S(mesh(0.5, 0.5))).reshape(2, 2), S_exact, rtol=1e-12, atol=1e-9)


def test_energy_signatures_and_errors():
    """The existing calls keep working; an unknown plane is a clear error."""
    from ngsolve import CF, VectorH1, GridFunction, Grad, Integrate, x
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(nx=2, ny=2)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((0.1 * x, 0.0)))
    G = Grad(gfu)
    a = Integrate(neohookean_energy(G, 1.0, 0.3), mesh)
    assert a == pytest.approx(Integrate(neohookean_energy(G, 1.0, 0.3, "strain"), mesh))
    # plane strain, F = diag(1.1, 1): closed form
    mu, lam = lame(1.0, 0.3)
    exact = 0.5 * mu * (1.21 - 1) - mu * np.log(1.1) + 0.5 * lam * np.log(1.1) ** 2
    assert a == pytest.approx(exact, rel=1e-12)
    for f in (linear_energy, svk_energy):
        assert np.isfinite(Integrate(f(G, 1.0, 0.3, "stress"), mesh))
    with pytest.raises(ValueError, match="plane"):
        neohookean_energy(G, 1.0, 0.3, "axisymmetric")


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("model,plane", [("gnl", "strain"), ("neohookean", "strain"),
                                         ("wang", "strain"), ("gnl", "stress"),
                                         ("neohookean", "stress")])
def test_models_agree_with_linear_at_vanishing_load(model, plane):
    """|u - u_linear| / |u_linear| -> 0 linearly with the load (ratio 10 per decade)."""
    mesh = cantilever_mesh("trig")
    rho = np.random.default_rng(3).uniform(0.5, 1.0, mesh.ne)
    diffs = []
    for load in (2e5, 2e4, 2e3, 2e2):
        u_lin = cantilever(mesh, "linear", 2, load=load, plane=plane).forward(rho)
        u = cantilever(mesh, model, 2, load=load, plane=plane).forward(rho)
        a, b = u.FV().NumPy(), u_lin.FV().NumPy()
        diffs.append(np.linalg.norm(a - b) / np.linalg.norm(b))
    diffs = np.array(diffs)
    assert diffs[0] > 1e-2  # 2e5 N is well inside the nonlinear range
    rates = diffs[1:] / diffs[:-1]
    assert np.all(np.abs(rates[1:] - 0.1) < 0.01), diffs  # first order in the load
    assert diffs[-1] < 1e-3


# --------------------------------------------------------------------------------------------
TANGENT_CASES = [("linear", "strain"), ("gnl", "strain"), ("neohookean", "strain"),
                 ("wang", "strain"), ("neohookean", "stress"), ("wang", "stress")]


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quad", 2)])
@pytest.mark.parametrize("model,plane", TANGENT_CASES)
def test_tangent_is_derivative_of_residual(model, plane, kind, order):
    """K(u) d equals (R(u + h d) - R(u - h d)) / 2h at a large-deformation state."""
    from ngsolve import CF, x, y

    mesh = cantilever_mesh(kind)
    rng = np.random.default_rng(7)
    mech = cantilever(mesh, model, order, plane=plane)
    rho = rng.uniform(0.05, 1.0, mesh.ne)  # γ of the Wang model spans (0, 1)
    mech.set_fields(rho)
    mech.gfu.Set(CF((0.05 * x * y, -0.3 * x * x)))  # 0.3 m tip deflection, rotations ~ 0.6
    u = mech.gfu.vec
    free = mech.free
    u.FV().NumPy()[free] += 1e-3 * rng.standard_normal(free.sum())
    assert mech.admissible(u)
    d = u.CreateVector()
    d.FV().NumPy()[:] = np.where(free, rng.standard_normal(len(free)), 0.0)
    mech.assemble_tangent(u, 1.0)
    Kd = d.CreateVector()
    Kd.data = mech.matrix * d
    h = 1e-7
    rp, rm, w = u.CreateVector(), u.CreateVector(), u.CreateVector()
    w.data = u + h * d
    mech.residual(w, rp, 1.0)
    w.data = u - h * d
    mech.residual(w, rm, 1.0)
    fd = (rp.FV().NumPy() - rm.FV().NumPy()) / (2 * h)
    kd = Kd.FV().NumPy()
    err = np.linalg.norm((fd - kd)[free]) / np.linalg.norm(kd[free])
    assert err < 1e-6, err
