"""The Darcy pressure as a follower load (docs/theory.md §4): ``r(u, v) = s cof(F) ∇_X p · v`` added to the
residual (the pulled-back spatial body force ``-J F⁻ᵀ ∇_X p``).

References are independent of the code under test: the cofactor written out component by
component, ``det(F) F⁻ᵀ`` from numpy for a homogeneous deformation, the deformation-independent
load of :func:`darcy_body`, and central differences of the residual.
"""
from __future__ import annotations

import numpy as np
import pytest

from small_cases import PA_H, PA_L, small_pa_mesh
from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_body, darcy_follower
from pacto_ng.physics.materials import jacobian, linear_energy, neohookean_energy
from pacto_ng.physics.mechanics import Field, Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.wang import wang_model

L, H, T = PA_L, PA_H, 1e-3  # the small pa-inverter of tests/small_cases.py


def _energy(model):
    modulus = lambda c: simp_cf(c["rho_bar"], 3e3, 3e8, 3.0)
    if model == "wang":
        energy, guard = wang_model(modulus, 0.4, "strain", "rho_bar", 3.0)
        return energy, guard, False
    if model == "linear":
        return (lambda G, c: linear_energy(G, modulus(c), 0.4)), None, True
    return (lambda G, c: neohookean_energy(G, modulus(c), 0.4)), (lambda G, c: jacobian(G)), False


def _pair(kind, model="neohookean", order=1, p_in=1.0, linear=None, rtol=1e-12):
    """Mechanics with the fixed and with the follower Darcy load on the same mesh, design and
    pressure field (Darcy at inlet pressure ``p_in``); returns (fixed, follower, rho, p)."""
    mesh = small_pa_mesh(kind)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=p_in, order=order)
    rho = np.random.default_rng(3).uniform(0.3, 1.0, mesh.ne)
    p = dar.forward(rho)
    energy, guard, lin = _energy(model)
    lin = lin if linear is None else linear
    kw = dict(order=order, energy=energy, thickness=T,
              supports=Supports(clamp=("fixed",), fix_y=("symmetry",)), guard=guard,
              linear=lin, newton=NewtonSettings(rtol=rtol))
    # one Field per block: Mechanics stores its own GridFunction in the Field it is given
    fixed = Mechanics(mesh, body=darcy_body("p"), fields=("rho_bar", dar.field()), **kw)
    follower = Mechanics(mesh, residual_density=darcy_follower("p"),
                         fields=("rho_bar", dar.field()), **kw)
    for m in (fixed, follower):
        m.set_fields(rho, p)
    return fixed, follower, rho, p


def _residual(mech, vec, load=1.0):
    out = vec.CreateVector()
    mech.residual(vec, out, load)
    return out.FV().NumPy().copy()


def _smooth(mech, scale):
    """A smooth displacement field ``scale * w`` (w ~ 1) on the block's space, Dirichlet dofs 0."""
    from ngsolve import CF, GridFunction, sin, x, y

    gf = GridFunction(mech.fes)
    gf.Set(CF((sin(3 * x / L) * y / H, x / L * (1 + sin(2 * y / H)))))
    v = gf.vec.FV().NumPy()
    v[~mech.free] = 0.0
    v *= scale
    return gf


@pytest.mark.parametrize("kind", ["trig", "quad"])
def test_residual_equals_fixed_at_zero_and_load_stiffness_grows_with_deformation(kind):
    """At u = 0 the follower residual is the fixed one.  At u = α w the difference is
    ``α s t ∫ cof(∇w) ∇p · v`` with the cofactor of the test written component by component
    (cof(I + G) = I + cof(G) in 2D): it grows linearly with the deformation."""
    from ngsolve import CF, Grad, InnerProduct, LinearForm, grad

    fixed, follower, rho, p = _pair(kind, p_in=1e5)
    zero = follower.gfu.vec.CreateVector()
    zero[:] = 0.0
    r0f, r0b = _residual(follower, zero), _residual(fixed, zero)
    assert np.linalg.norm(r0b) > 0
    rel0 = np.linalg.norm(r0f - r0b) / np.linalg.norm(r0b)
    assert rel0 < 1e-14, rel0  # measured 0.0 (bitwise equal)

    w = _smooth(follower, 1.0)
    G = Grad(w)
    cofG = CF((G[1, 1], -G[1, 0], -G[0, 1], G[0, 0]), dims=(2, 2))
    v = follower.fes.TestFunction()
    ref = LinearForm(follower.fes)
    ref += T * InnerProduct(cofG * grad(follower.coeffs["p"]), v) * follower.DX
    ref.Assemble()
    ref = ref.vec.FV().NumPy()
    diffs = []
    for alpha in (1e-4, 2e-4, 4e-4):
        ua = _smooth(follower, alpha).vec
        d = _residual(follower, ua) - _residual(fixed, ua)
        err = np.linalg.norm(d - alpha * ref) / np.linalg.norm(alpha * ref)
        assert err < 1e-9, err  # measured 6e-12 .. 9e-12 (round-off of the cancelling energy)
        diffs.append(np.linalg.norm(d))
    assert diffs[0] > 1e-3 * np.linalg.norm(r0b)  # a real difference, not round-off
    assert np.allclose(np.array(diffs[1:]) / diffs[:-1], 2.0, rtol=1e-9)


def test_follower_tends_to_fixed_at_vanishing_pressure():
    """Neo-Hookean equilibria under both loads: the relative difference of the solutions
    vanishes linearly with the pressure (rate 1 per decade)."""
    fixed, follower, rho, p = _pair("quad", p_in=1.0)
    errs = []
    for P in (4e5, 4e4, 4e3):
        for m in (fixed, follower):
            m.target = P
            m.forward(rho, p)
        uf, ub = follower.gfu.vec.FV().NumPy(), fixed.gfu.vec.FV().NumPy()
        errs.append(np.linalg.norm(uf - ub) / np.linalg.norm(ub))
    rates = np.log10(np.array(errs[:-1]) / errs[1:])
    print("relative differences", errs, "rates", rates)
    assert errs[0] > 1e-3  # the follower effect is visible at the largest pressure
    assert np.all(np.abs(rates - 1.0) < 0.02), rates  # measured 0.994, 0.9994


@pytest.mark.parametrize("model", ["neohookean", "wang"])
@pytest.mark.parametrize("kind", ["trig", "quad"])
def test_tangent_is_the_derivative_of_the_residual(model, kind):
    """K(u)·d (AssembleLinearization) against (R(u + h d) - R(u - h d)) / 2h at a deformed
    state: the error falls like h² (a wrong tangent would leave a plateau).  The load stiffness
    alone (follower minus fixed) is checked too; the follower residual is affine in u in 2D, so
    its central difference is exact up to round-off."""
    fixed, follower, rho, p = _pair(kind, model, p_in=1e5)
    u0 = _smooth(follower, 2e-4).vec
    rng = np.random.default_rng(7)
    d = u0.CreateVector()
    step = rng.uniform(-1.0, 1.0, follower.fes.ndof)
    d.FV().NumPy()[:] = 2e-4 * np.where(follower.free, step, 0.0)
    f = follower.free
    kd = {}
    for name, m in (("fixed", fixed), ("follower", follower)):
        m.a.AssembleLinearization(u0)
        out = u0.CreateVector()
        out.data = m.a.mat * d
        kd[name] = out.FV().NumPy()[f].copy()
    errs, errs_ls = [], []
    for h in (1e-3, 1e-4):
        up, um = u0.CreateVector(), u0.CreateVector()
        up.data = u0 + h * d
        um.data = u0 - h * d
        fd = {name: (_residual(m, up) - _residual(m, um))[f] / (2 * h)
              for name, m in (("fixed", fixed), ("follower", follower))}
        k = kd["follower"]
        errs.append(np.linalg.norm(k - fd["follower"]) / np.linalg.norm(k))
        ls, ls_fd = kd["follower"] - kd["fixed"], fd["follower"] - fd["fixed"]
        errs_ls.append(np.linalg.norm(ls - ls_fd) / np.linalg.norm(ls))
    assert errs[1] < 1e-8, errs  # measured 8.2e-10 .. 8.6e-10
    assert 90 < errs[0] / errs[1] < 110, errs  # h²: measured 100.0
    assert max(errs_ls) < 1e-7, errs_ls  # measured 1.4e-9 .. 1.3e-8 (round-off)
    # the load stiffness is small next to the material's (p/E ~ 3e-4) but far above round-off
    assert np.linalg.norm(ls) > 1e-6 * np.linalg.norm(kd["fixed"])  # measured 1.1e-5


@pytest.mark.parametrize("kind", ["trig", "quad"])
@pytest.mark.parametrize("order", [1, 2])
def test_homogeneous_deformation_with_linear_pressure(kind, order):
    """u = (F - I) X and p = a·X: the follower residual is ``s t ∫ c·v`` with the constant
    ``c = det(F) F⁻ᵀ a`` (numpy), and its resultant is ``s t |Ω0| c`` (the spatial force
    ``-∫ ∇_x p dv = -|Ω_t| F⁻ᵀ a`` with the sign of a residual)."""
    from ngsolve import CF, GridFunction, H1, Integrate, InnerProduct, LinearForm, x, y

    mesh = small_pa_mesh(kind)
    Fh = np.array([[1.2, 0.3], [-0.1, 0.9]])
    a = np.array([3.0e5, -1.5e5])
    s = 0.7
    c = np.linalg.det(Fh) * np.linalg.inv(Fh).T @ a
    ph1 = H1(mesh, order=order)
    mech = Mechanics(mesh, order=order, energy=lambda G, cf: 0.0 * InnerProduct(G, G),
                     fields=(Field("p", ph1),), supports=Supports(clamp=("fixed",)),
                     thickness=T, residual_density=darcy_follower("p"))
    gp = GridFunction(ph1)
    gp.Set(a[0] * x + a[1] * y)
    mech.set_fields(gp.vec)
    gu = GridFunction(mech.fes)
    gu.Set(CF(((Fh[0, 0] - 1) * x + Fh[0, 1] * y, Fh[1, 0] * x + (Fh[1, 1] - 1) * y)))
    r = _residual(mech, gu.vec, s)
    ref = LinearForm(mech.fes)
    ref += s * T * InnerProduct(CF(tuple(c)), mech.fes.TestFunction()) * mech.DX
    ref.Assemble()
    ref = ref.vec.FV().NumPy()
    err = np.linalg.norm(r - ref) / np.linalg.norm(ref)
    assert err < 1e-12, err  # measured 1e-15 .. 1e-14
    area = Integrate(CF(1.0), mesh)
    for k in range(2):
        e = GridFunction(mech.fes)
        e.Set(CF((1.0, 0.0) if k == 0 else (0.0, 1.0)))
        res = float(r @ e.vec.FV().NumPy())
        assert abs(res - s * T * area * c[k]) < 1e-12 * s * T * area * np.abs(c).max()


def test_linear_material_with_follower_load_stays_affine():
    """With a linear material the follower residual ``K u - f + s t ∫ cof(∇u)∇p·v`` is affine in
    u in 2D: one Newton step is exact, so ``linear=True`` (one step) is kept for it, and Newton
    with ``linear=False`` stops after one iteration with the same solution."""
    P = 2e6
    fixed, lin, rho, p = _pair("trig", "linear", p_in=P, linear=True)
    _, nonlin, _, _ = _pair("trig", "linear", p_in=P, linear=False, rtol=1e-11)
    assert not lin.symmetric
    lin.forward(rho, p)
    nonlin.forward(rho, p)
    fixed.forward(rho, p)
    r = _residual(lin, lin.gfu.vec)[lin.free]
    ref = lin.load_norm(1.0)
    assert np.linalg.norm(r) < 1e-11 * ref, np.linalg.norm(r) / ref  # measured 1.3e-13
    assert nonlin.result.iterations == 1
    ul, un, ub = (m.gfu.vec.FV().NumPy() for m in (lin, nonlin, fixed))
    assert np.linalg.norm(ul - un) < 1e-10 * np.linalg.norm(ul)
    assert np.linalg.norm(ul - ub) > 1e-3 * np.linalg.norm(ub)  # the follower effect is real


def test_load_stiffness_symmetry():
    """``∫ -cof(F)∇p·v = ∫ p cof(F):∇v - ∮ p cof(F)N·v`` (Piola identity): the volume part is the
    derivative of ``∫ p (J - 1)``, so the load stiffness is unsymmetric only through boundaries
    where p varies and v is free.  The Darcy field of this layout is constant on every such
    boundary (P_in on the inlet, 0 on the zero boundaries; on the symmetry line v_y = 0), and
    its load stiffness is symmetric on the free dofs; a pressure that varies along the free
    boundary gives an unsymmetric one (hence the general unsymmetric solver)."""
    fixed, follower, rho, p = _pair("trig", p_in=1e5)
    u0 = _smooth(follower, 2e-4).vec
    rng = np.random.default_rng(11)
    f = follower.free
    e1, e2 = u0.CreateVector(), u0.CreateVector()
    e1.FV().NumPy()[:] = np.where(f, rng.normal(size=len(f)), 0.0)
    e2.FV().NumPy()[:] = np.where(f, rng.normal(size=len(f)), 0.0)

    def skew():
        fixed.a.AssembleLinearization(u0)
        follower.a.AssembleLinearization(u0)
        t1, t2 = u0.CreateVector(), u0.CreateVector()
        t1.data = follower.a.mat * e1 - fixed.a.mat * e1
        t2.data = follower.a.mat * e2 - fixed.a.mat * e2
        a12, a21 = e2.InnerProduct(t1), e1.InnerProduct(t2)
        return abs(a12 - a21) / max(abs(a12), abs(a21))

    darcy = skew()
    assert darcy < 1e-9, darcy  # measured 1.0e-11
    q = p.CreateVector()
    q.FV().NumPy()[:] = rng.uniform(0.0, 1e5, len(q))  # varies along every boundary
    for m in (fixed, follower):
        m.set_fields(rho, q)
    other = skew()
    assert other > 1e-2, other  # measured 0.55


@pytest.mark.parametrize("kind", ["trig", "quad"])
def test_wang_follower_is_follower_in_solid_and_fixed_in_void(kind):
    """``darcy_follower(gamma=...)`` follows ``I + γ∇u``: with γ ≡ 1 its residual is the plain
    follower's, with γ ≡ 0 the fixed load's, at a deformed state; in between it is affine in γ."""
    from ngsolve import CF

    fixed, follower, rho, p = _pair(kind, p_in=1e5)
    ua = _smooth(follower, 1e-3).vec
    ref_fol, ref_fix = _residual(follower, ua), _residual(fixed, ua)
    n = np.linalg.norm(ref_fol - ref_fix)  # the load stiffness's share: the scale of the test
    assert n > 1e-6 * np.linalg.norm(ref_fix)  # measured 2.6e-5 (trig), 3.0e-5 (quad)
    out = {}
    for g in (0.0, 0.5, 1.0):
        energy, guard, lin = _energy("neohookean")
        mech = Mechanics(follower.mesh, residual_density=darcy_follower("p", gamma=lambda c, g=g: CF(g)),
                         fields=("rho_bar", DarcyPressure(follower.mesh, inlet="inlet", zero="zero",
                                                          p_in=1e5).field()),
                         order=1, energy=energy, thickness=T, guard=guard, linear=lin,
                         supports=Supports(clamp=("fixed",), fix_y=("symmetry",)))
        mech.set_fields(rho, p)
        out[g] = _residual(mech, ua)
    # measured: 3.6e-12 (γ = 0), 4.9e-12 (0.5), 0.0 (1) relative to n (trig)
    assert np.linalg.norm(out[1.0] - ref_fol) / n < 1e-9
    assert np.linalg.norm(out[0.0] - ref_fix) / n < 1e-9
    assert np.linalg.norm(out[0.5] - 0.5 * (ref_fol + ref_fix)) / n < 1e-9
