"""The Wang interpolation (thesis ch. 5): its limits, its strain and stress measures against
the formulas of thesis App. E.2 written out by hand, its guard, and the C-beam load limit."""
import math

import numpy as np
import pytest

from nonlinear_setup import cantilever, cantilever_mesh
from pacto_ng.physics.wang import WangModel, wang_energy, wang_gamma_cf, wang_model


pytestmark = pytest.mark.usefixtures("one_thread")


def _state(mech, seed=0):
    """A large-deformation state: the Neo-Hookean equilibrium at 2e5 N plus noise."""
    rng = np.random.default_rng(seed)
    u = mech.gfu.vec
    u.FV().NumPy()[mech.free] += 1e-3 * rng.standard_normal(mech.free.sum())
    return u


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quad", 2)])
@pytest.mark.parametrize("gamma,reference", [(0.0, "linear"), (1.0, "neohookean")])
def test_gamma_limits_reproduce_linear_and_neohookean(kind, order, gamma, reference):
    """γ ≡ 0 gives the linear model, γ ≡ 1 the Neo-Hookean one: energy and residual to 1e-10."""
    from ngsolve import CF, Integrate

    mesh = cantilever_mesh(kind)
    rho = np.random.default_rng(1).uniform(0.3, 1.0, mesh.ne)
    ref = cantilever(mesh, "neohookean", order)
    ref.forward(rho)  # a genuinely nonlinear state (tip rotation ~ 0.5 rad)
    u = _state(ref)
    wang = cantilever(mesh, "wang", order, gamma_fn=lambda c: CF(gamma))
    other = cantilever(mesh, reference, order)
    for m in (wang, other):
        m.set_fields(rho)
    e_w = Integrate(wang.volume_density(ref.gfu) * wang.DX, mesh)
    e_r = Integrate(other.volume_density(ref.gfu) * other.DX, mesh)
    assert abs(e_w - e_r) <= 1e-10 * abs(e_r)
    r_w, r_r = u.CreateVector(), u.CreateVector()
    wang.residual(u, r_w, 1.0)
    other.residual(u, r_r, 1.0)
    a, b = r_w.FV().NumPy(), r_r.FV().NumPy()
    assert np.linalg.norm(a - b) <= 1e-10 * np.linalg.norm(b)


@pytest.mark.parametrize("rho_value,reference", [(0.0, "linear"), (1.0, "neohookean")])
def test_default_gamma_is_exact_at_void_and_solid(rho_value, reference):
    """With eq. 5.2 (β1 = 100, η1 = 0.001) ρ̄ = 0 is the linear model, ρ̄ = 1 the Neo-Hookean."""
    mesh = cantilever_mesh("trig")
    rho = np.full(mesh.ne, rho_value)
    load = 2e5 if rho_value == 1.0 else 2e-1  # the void is 1e6 times softer
    u_w = cantilever(mesh, "wang", 1, load=load).forward(rho)
    u_r = cantilever(mesh, reference, 1, load=load).forward(rho)
    a, b = u_w.FV().NumPy(), u_r.FV().NumPy()
    assert np.linalg.norm(a - b) <= 1e-9 * np.linalg.norm(b)
    assert np.abs(b).max() > 0.05  # a large-displacement state


def test_gamma_interpolation_values():
    """γ = H(ρ̄^p; η1, β1) (eq. 5.2) at chosen densities, both parameter sets."""
    from ngsolve import GridFunction, L2
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(nx=1, ny=1)
    g = GridFunction(L2(mesh, order=0))
    mp = mesh(0.5, 0.5)
    for beta, eta in ((100.0, 0.001), (500.0, 0.01)):
        den = math.tanh(beta * eta) + math.tanh(beta * (1 - eta))
        for rho in (0.0, 0.05, 0.1, 0.2, 0.3, 1.0):
            g.vec[:] = rho
            expect = (math.tanh(beta * eta) + math.tanh(beta * (rho ** 3 - eta))) / den
            assert wang_gamma_cf(g, 3.0, beta, eta)(mp) == pytest.approx(expect, abs=1e-15)
        g.vec[:] = 0.0
        assert wang_gamma_cf(g, 3.0, beta, eta)(mp) == pytest.approx(0.0, abs=1e-15)
        g.vec[:] = 1.0
        assert wang_gamma_cf(g, 3.0, beta, eta)(mp) == pytest.approx(1.0, abs=1e-15)


# --------------------------------------------------------------------------------------------
# thesis App. E.2, written out by hand in numpy
def _app_e2(uX, uY, vX, vY, g, E, nu):
    mu = 0.5 * E / (1 + nu)
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    # strains (E.2 lines 163-171): E_W1
    eXX = uX - g * uX + (g * uX + 1) ** 2 / 2 + g ** 2 * vX ** 2 / 2 - 0.5
    eXY = (uY / 2 + vX / 2 - g * uY / 2 - g * vX / 2 + g * uY * (g * uX + 1) / 2
           + g * vX * (g * vY + 1) / 2)
    eYY = vY - g * vY + g ** 2 * uY ** 2 / 2 + (g * vY + 1) ** 2 / 2 - 0.5
    ew1 = np.array([[eXX, eXY], [eXY, eYY]])
    # eq. 5.5: E_W2
    e12 = 0.5 * (uY + vX + (uX * uY + vX * vY) * g)
    ew2 = np.array([[0.5 * (2 * uX + (uX ** 2 + vX ** 2) * g), e12],
                    [e12, 0.5 * (2 * vY + (uY ** 2 + vY ** 2) * g)]])
    # energy (E.2 lines 54-66): phi_HE(γu) - phi_L(γu) + phi_L(u)
    F11, F12, F21, F22 = 1 + uX * g, uY * g, vX * g, 1 + vY * g
    C11, C12, C22 = F11 ** 2 + F21 ** 2, F11 * F12 + F21 * F22, F12 ** 2 + F22 ** 2
    Jg = math.sqrt(C11 * C22 - C12 ** 2)
    phi_he = 0.5 * mu * (C11 + C22 + 1 - 3) - mu * math.log(Jg) + 0.5 * lam * math.log(Jg) ** 2
    phi_l = lambda a, b, c, d: (lam * (a + d) ** 2 / 2
                                + mu * (2 * (b / 2 + c / 2) ** 2 + a ** 2 + d ** 2))
    phi = phi_he - phi_l(g * uX, g * uY, g * vX, g * vY) + phi_l(uX, uY, vX, vY)
    # stress (E.2 lines 69-131): S = S_NL(γu) - S_L(γu) + S_L(u), S_NL = μ (I - C⁻¹) + λ ln J C⁻¹
    Ci = np.linalg.inv(np.array([[C11, C12], [C12, C22]]))
    s_nl = mu * (np.eye(2) - Ci) + lam * math.log(Jg) * Ci
    s_l = lambda a, b, c, d: np.array([[lam * (a + d) + 2 * mu * a, mu * (b + c)],
                                       [mu * (b + c), lam * (a + d) + 2 * mu * d]])
    S = s_nl - s_l(g * uX, g * uY, g * vX, g * vY) + s_l(uX, uY, vX, vY)
    return phi, ew1, ew2, S


@pytest.mark.parametrize("grad,gamma", [
    ((0.000192837, 0.0000456456, -0.000001, -0.00000000000000007777777777), 0.7),  # App. E.2
    ((0.35, -0.6, 0.25, -0.3), 0.7),
    ((1.2, 0.4, -0.8, 0.9), 0.35),
    ((-0.5, 0.3, 0.2, -0.4), 1.0),
    ((-0.5, 0.3, 0.2, -0.4), 0.0),
])
def test_energy_strains_and_stress_match_appendix_e2(grad, gamma):
    """φ (eq. 5.1), E_W1 (eq. 5.4), E_W2 (eq. 5.5) and S (eq. 5.3) against App. E.2 by hand."""
    from ngsolve import CF, GridFunction, Grad, VectorH1, x, y
    from ngsolve.meshes import MakeStructured2DMesh

    E, nu = 180e6, 0.4  # the values of App. E.2
    uX, uY, vX, vY = grad
    mesh = MakeStructured2DMesh(nx=1, ny=1)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((uX * x + uY * y, vX * x + vY * y)))
    model = wang_model(lambda c: E, nu, gamma_fn=lambda c: CF(gamma))
    G, mp = Grad(gfu), mesh(0.4, 0.3)
    phi, ew1, ew2, S = _app_e2(uX, uY, vX, vY, gamma, E, nu)
    scale = max(abs(phi), 1e-300)
    assert model.energy(G, {})(mp) == pytest.approx(phi, rel=1e-9, abs=1e-9 * scale)
    mat = lambda cf: np.array(cf(mp)).reshape(2, 2)
    assert np.allclose(mat(model.strain_w1(G, {})), ew1, rtol=1e-12, atol=1e-15)
    assert np.allclose(mat(model.strain_w2(G, {})), ew2, rtol=1e-12, atol=1e-15)
    s_scale = np.abs(S).max()
    assert np.allclose(mat(model.stress(G, {})), S, rtol=1e-9, atol=1e-9 * s_scale)


def test_guard_ignores_the_void():
    """det(I + γ∇u) is 1 where γ = 0, whatever ∇u: an inverted void is admissible, an
    inverted solid is not."""
    from ngsolve import CF, GridFunction, Grad, L2, VectorH1, x, y
    from ngsolve.meshes import MakeStructured2DMesh

    mesh = MakeStructured2DMesh(nx=1, ny=1)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((-1.5 * x, 0.2 * y)))  # det(I + ∇u) = -0.6
    rho = GridFunction(L2(mesh, order=0))
    model = wang_model(lambda c: 1.0, 0.3)
    energy, guard = model
    mp = mesh(0.5, 0.5)
    for value, expect in ((0.0, 1.0), (1.0, -0.6)):
        rho.vec[:] = value
        assert guard(Grad(gfu), {"rho_bar": rho})(mp) == pytest.approx(expect, rel=1e-14)
    rho.vec[:] = 0.0
    assert np.isfinite(energy(Grad(gfu), {"rho_bar": rho})(mp))
    assert wang_model(lambda c: 1.0, 0.3, hyper="gnl").guard is None


def test_settings_are_validated():
    with pytest.raises(ValueError, match="hyperelastic"):
        wang_model(lambda c: 1.0, 0.3, hyper="mooney")
    with pytest.raises(ValueError, match="eta"):
        WangModel(lambda c: 1.0, 0.3, eta=1.5)
    with pytest.raises(ValueError, match="plane"):
        wang_model(lambda c: 1.0, 0.3, plane="3d")
    m = wang_model(lambda c: 1.0, 0.3, beta=500.0, eta=0.01)
    assert (m.beta, m.eta) == (500.0, 0.01)


def test_wang_energy_with_svk():
    """The Wang interpolation of St Venant–Kirchhoff: γ = 1 gives the gnl energy exactly."""
    from ngsolve import CF, GridFunction, Grad, VectorH1, x, y
    from ngsolve.meshes import MakeStructured2DMesh
    from pacto_ng.physics.materials import svk_energy

    mesh = MakeStructured2DMesh(nx=1, ny=1)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((0.3 * x - 0.2 * y, 0.1 * x + 0.4 * y)))
    mp = mesh(0.5, 0.5)
    assert wang_energy(Grad(gfu), 2.0, 0.3, 1.0, hyper="gnl")(mp) == pytest.approx(
        svk_energy(Grad(gfu), 2.0, 0.3)(mp), rel=1e-14)


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("order", [1, 2])
def test_c_beam_wang_carries_six_times_the_neohookean_load(order):
    """C-beam (cases/c_beam.py, 10 x 10 quads): Wang reaches at least 6x the Neo-Hookean load factor.

    Neo-Hookean stops when a void element inverts (det F <= 0 at a vertex or edge midpoint);
    the Wang model linearises the void and carries the C to the cap of λ = 12.
    Measured: Neo-Hookean λ ≈ 1.40 (Q1) and 0.66 (Q2); Wang reaches the cap.
    """
    from pacto_ng.studies import c_beam_limit

    nh = c_beam_limit("neohookean", order=order, mesh="quad", lam_max=12.0)
    wang = c_beam_limit("wang", order=order, mesh="quad", lam_max=12.0)
    assert "inverted" in nh.reason
    assert 0.1 < nh.load_factor < 2.0
    assert wang.reached_max and wang.load_factor == pytest.approx(12.0)
    assert wang.load_factor >= 6.0 * nh.load_factor
    # the Wang solid never inverts; its void does, harmlessly
    assert min(s[1] for s in wang.steps) > 0.0
    assert min(s[2] for s in wang.steps) < 0.0


def test_realcompile_gives_the_same_residual_and_tangent():
    """``realcompile`` (machine code for the Newton forms) changes nothing but the speed: the
    Wang residual and tangent at a large-deformation state equal the default ones to 1e-12."""
    mesh = cantilever_mesh("trig")
    rho = np.random.default_rng(2).uniform(0.0, 1.0, mesh.ne)
    plain = cantilever(mesh, "wang", 1)
    fast = cantilever(mesh, "wang", 1, realcompile=True)
    plain.forward(rho)
    fast.set_fields(rho)
    u = _state(plain)
    r_p, r_f = u.CreateVector(), u.CreateVector()
    plain.residual(u, r_p, 1.0)
    fast.residual(u, r_f, 1.0)
    a, b = r_f.FV().NumPy()[plain.free], r_p.FV().NumPy()[plain.free]
    assert np.linalg.norm(a - b) <= 1e-12 * np.linalg.norm(b)
    plain.assemble_tangent(u, 1.0)
    fast.assemble_tangent(u, 1.0)
    ka, kb = fast.a.mat.AsVector().FV().NumPy(), plain.a.mat.AsVector().FV().NumPy()
    assert np.linalg.norm(ka - kb) <= 1e-12 * np.linalg.norm(kb)


@pytest.mark.parametrize("gamma, reference", [(0.0, "linear"), (1.0, "neohookean")])
def test_optimisation_history_with_constant_gamma_equals_the_limit_model(gamma, reference):
    """A short cantilever optimisation (filter + projection, 4 MMA iterations) with the Wang
    model at γ ≡ 0 has the objective history of the linear model, at γ ≡ 1 that of
    Neo-Hookean, to 1e-10 relative."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.optimize.driver import LoopState, optimize
    from pacto_ng.initial import initial_design

    case = get_case("cantilever")
    hist = {}
    for model, extra in (("wang", {"wang_gamma": str(gamma)}), (reference, {})):
        # one order for both (the cantilever's own order differs by model)
        params = case.defaults.with_overrides({"model": model, "maxh": "0.05", "load": "2e5",
                                               "order": "1", "iterations": "4", **extra})
        problem = build_problem(case, params)
        state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
        optimize(problem, params.schedule.schedule(), iterations=4, tol=0.0, method="mma",
                 move=params.move, state=state)
        hist[model] = np.array([h["objective"] for h in state.history])
    a, b = hist["wang"], hist[reference]
    assert len(a) == 4 and a[-1] < a[0]
    err = np.max(np.abs(a - b) / np.abs(b))
    assert err < 1e-10, err  # measured 8.0e-13 (γ = 0), 5.8e-16 (γ = 1)
