"""Mooney–Rivlin, Yeoh and Ogden (pacto_ng/physics/hyperelastic.py) and material presets
(pacto_ng/physics/presets.py).

* Energy and first Piola–Kirchhoff stress (``.Diff`` of the energy) at homogeneous uniaxial,
  equibiaxial and planar states, compressible and isochoric, 3D and plane strain, against an
  independent numpy transcription written here (invariant derivatives by hand; Ogden from
  ``numpy.linalg.eigh`` and the spectral derivative ``∂c_i/∂C = N_i ⊗ N_i``): 1e-9 relative.
* At isochoric states (J = 1) the differences of Cauchy principal stresses against the published
  incompressible nominal-stress formulas: Rivlin's ``P = 2 (λ - λ^-2)(W1 + W2/λ)`` (uniaxial),
  ``2 (λ - λ^-5)(W1 + λ² W2)`` (equibiaxial), ``2 (λ - λ^-3)(W1 + W2)`` (planar), and Ogden's
  (1972) ``P = Σ 2μ_p/α_p (λ^(α_p-1) - λ_3^α_p/λ)``; ``σ1 - σ3 = λ P``.
* Mooney–Rivlin with C01 = 0, Yeoh with one term and Ogden with one term α = 2 equal the
  isochoric Neo-Hookean ``μ/2 (Ī1 - 3) + K/2 (J - 1)²`` to 1e-12; at u = 0 the residual is zero
  and finite and the assembled tangent is the linear-elastic one to 1e-9.
* Finite-difference checks of the whole chain (filter, projection, Darcy pressure, mechanics,
  responses) for each law and for Wang over Ogden, under the fixed and the follower Darcy load,
  and one 3D check; the preset rule and ``pacto run --set material=NAME``.

The shapes below (coefficients / μ0) are test parameters chosen to exercise every term
(negative C01, three Yeoh terms, an Ogden term with a negative exponent), not material data.
"""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

from pacto_ng.physics.hyperelastic import (Law, mooney_rivlin_energy, ogden_energy,
                                           stretch_power_sums, yeoh_energy)
from pacto_ng.physics.materials import first_piola_kirchhoff, linear_energy


pytestmark = pytest.mark.usefixtures("one_thread")

E, NU = 2.0e5, 0.45
SHAPES = {
    "mooney_rivlin": (0.7, -0.2),
    "yeoh": (0.5, 0.04, 0.002),
    "ogden": ((1.2, 2.5), (-0.2, -2.0)),
}
ENERGY = {"mooney_rivlin": mooney_rivlin_energy, "yeoh": yeoh_energy, "ogden": ogden_energy}


# --------------------------------------------------------------------------------------------
# the independent transcription (numpy)
# --------------------------------------------------------------------------------------------
def reference(law, shape, F, E=E, nu=NU):
    """``(W, P)`` of ``law`` at ``F`` (2x2: plane strain, F33 = 1), by hand."""
    d = F.shape[0]
    F3 = np.eye(3)
    F3[:d, :d] = F
    J = np.linalg.det(F3)
    C = F3.T @ F3
    FiT = np.linalg.inv(F3).T
    I1 = np.trace(C)
    I2 = 0.5 * (I1 ** 2 - np.trace(C @ C))
    mu = E / (2 * (1 + nu))
    K = E / (3 * (1 - 2 * nu))
    I1b, I2b = J ** (-2 / 3) * I1, J ** (-4 / 3) * I2
    dI1b = J ** (-2 / 3) * (2 * F3 - 2 / 3 * I1 * FiT)
    dI2b = J ** (-4 / 3) * (2 * I1 * F3 - 2 * F3 @ C - 4 / 3 * I2 * FiT)
    if law == "mooney_rivlin":
        a10, a01 = shape
        W = mu * (a10 * (I1b - 3) + a01 * (I2b - 3))
        P = mu * (a10 * dI1b + a01 * dI2b)
    elif law == "yeoh":
        x = I1b - 3
        W = mu * sum(a * x ** (i + 1) for i, a in enumerate(shape))
        P = mu * sum((i + 1) * a * x ** i for i, a in enumerate(shape)) * dI1b
    else:
        c, N = np.linalg.eigh(C)
        cb = J ** (-2 / 3) * c
        Ci = np.linalg.inv(C)
        W, dWdC = 0.0, np.zeros((3, 3))
        for m, al in shape:
            W += mu * 2 * m / al ** 2 * (np.sum(cb ** (al / 2)) - 3)
            for i in range(3):
                dWdC += (mu * 2 * m / al ** 2 * (al / 2) * cb[i] ** (al / 2 - 1) * J ** (-2 / 3)
                         * (np.outer(N[:, i], N[:, i]) - c[i] / 3 * Ci))
        P = 2 * F3 @ dWdC
    W += K / 2 * (J - 1) ** 2
    P = P + K * (J - 1) * J * FiT
    return W, P[:d, :d]


def isochoric_neohookean(F, E=E, nu=NU):
    """``μ/2 (Ī1 - 3) + K/2 (J - 1)²`` and its P, by hand (F 3x3)."""
    J = np.linalg.det(F)
    I1 = np.trace(F.T @ F)
    mu, K = E / (2 * (1 + nu)), E / (3 * (1 - 2 * nu))
    FiT = np.linalg.inv(F).T
    W = mu / 2 * (J ** (-2 / 3) * I1 - 3) + K / 2 * (J - 1) ** 2
    P = mu / 2 * J ** (-2 / 3) * (2 * F - 2 / 3 * I1 * FiT) + K * (J - 1) * J * FiT
    return W, P


def states(kind, lam, lat):
    """Principal stretches of a homogeneous state: uniaxial (λ, λt, λt), equibiaxial (λ, λ,
    λt), planar (λ, 1, λt); ``lat=None``: the isochoric λt."""
    if kind == "uniaxial":
        t = lam ** -0.5 if lat is None else lat
        return np.array([lam, t, t])
    if kind == "equibiaxial":
        t = lam ** -2.0 if lat is None else lat
        return np.array([lam, lam, t])
    t = 1 / lam if lat is None else lat
    return np.array([lam, 1.0, t])


# --------------------------------------------------------------------------------------------
# evaluation of the code's CFs at one point of a one-element mesh
# --------------------------------------------------------------------------------------------
_MESHES = {}


def _point(d):
    from ngsolve import GridFunction, VectorH1
    from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh

    if d not in _MESHES:
        mesh = MakeStructured3DMesh(nx=1, ny=1, nz=1) if d == 3 else MakeStructured2DMesh(1, 1)
        gfu = GridFunction(VectorH1(mesh, order=1))
        _MESHES[d] = (mesh, gfu, mesh(*([0.3, 0.6, 0.45][:d])))
    return _MESHES[d]


_COMPILED = {}


def code_w_p(energy, F, key=None):
    """The code's energy and ``P = ∂φ/∂F`` (by .Diff) at the homogeneous state ``F``; ``key``
    names the energy so that its compiled CFs are built once for every state."""
    from ngsolve import CF, Grad, Integrate, x, y, z

    d = F.shape[0]
    mesh, gfu, mp = _point(d)
    X = (x, y, z)[:d]
    A = F - np.eye(d)
    gfu.Set(CF(tuple(sum(A[i, j] * X[j] for j in range(d)) for i in range(d))))
    if key is None or (key, d) not in _COMPILED:
        G = Grad(gfu)
        cfs = (energy(G).Compile(), first_piola_kirchhoff(energy, G))
        if key is not None:
            _COMPILED[key, d] = cfs
    else:
        cfs = _COMPILED[key, d]
    # the field is constant: its integral over the unit square / cube is its value (compiled,
    # vectorised evaluation; a point evaluation of these CFs is not)
    W = Integrate(cfs[0], mesh, order=0)
    P = Integrate(cfs[1], mesh, order=0)
    return W, np.array(P).reshape(d, d)


def close(a, b, rtol):
    return np.abs(np.asarray(a) - np.asarray(b)).max() <= rtol * np.abs(np.asarray(b)).max()


# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("law", list(SHAPES))
@pytest.mark.parametrize("kind", ["uniaxial", "equibiaxial", "planar"])
@pytest.mark.parametrize("lam,lat", [(1.8, 0.8), (0.6, 1.25), (2.5, None), (0.7, None)])
def test_homogeneous_states_3d(law, kind, lam, lat):
    """Energy and P at uniaxial, equibiaxial and planar stretch (compressible and isochoric)
    against the numpy transcription: 1e-9 relative."""
    F = np.diag(states(kind, lam, lat))
    W, P = code_w_p(lambda G: ENERGY[law](G, E, NU, shape=SHAPES[law]), F, key=law)
    Wr, Pr = reference(law, SHAPES[law], F)
    assert W == pytest.approx(Wr, rel=1e-9)
    assert close(P, Pr, 1e-9), (P, Pr)


@pytest.mark.parametrize("law", list(SHAPES))
@pytest.mark.parametrize("F", [np.diag([1.7, 1 / 1.7]), np.diag([0.8, 1.3]),
                               np.array([[1.3, 0.4], [-0.2, 0.9]]),
                               np.array([[1.0, 0.5], [0.0, 1.0]])])
def test_plane_strain_states(law, F):
    """Plane strain (F33 = 1): planar stretch, a compressible stretch, a general F and simple
    shear against the transcription: 1e-9."""
    W, P = code_w_p(lambda G: ENERGY[law](G, E, NU, shape=SHAPES[law]), F, key=law)
    Wr, Pr = reference(law, SHAPES[law], F)
    assert W == pytest.approx(Wr, rel=1e-9)
    assert close(P, Pr, 1e-9), (P, Pr)


def _w1_w2(law, shape, I1b, mu):
    if law == "mooney_rivlin":
        return mu * shape[0], mu * shape[1]
    x = I1b - 3
    return mu * sum((i + 1) * a * x ** i for i, a in enumerate(shape)), 0.0


def published_nominal(law, shape, kind, lam, mu):
    """Incompressible nominal stress P(λ) of each test, as published (module docstring)."""
    if law == "ogden":
        l3 = {"uniaxial": lam ** -0.5, "equibiaxial": lam ** -2.0, "planar": 1 / lam}[kind]
        return sum(2 * mu * m / a * (lam ** (a - 1) - l3 ** a / lam) for m, a in shape)
    s = states(kind, lam, None)
    W1, W2 = _w1_w2(law, shape, np.sum(s ** 2), mu)
    if kind == "uniaxial":
        return 2 * (lam - lam ** -2) * (W1 + W2 / lam)
    if kind == "equibiaxial":
        return 2 * (lam - lam ** -5) * (W1 + lam ** 2 * W2)
    return 2 * (lam - lam ** -3) * (W1 + W2)


@pytest.mark.parametrize("law", list(SHAPES))
@pytest.mark.parametrize("kind", ["uniaxial", "equibiaxial", "planar"])
@pytest.mark.parametrize("lam", [1.5, 3.0, 0.75])
def test_isochoric_stress_differences_match_published_formulas(law, kind, lam):
    """At J = 1: σ1 - σ3 = λ P_published (3D; and σ_x - σ_y for planar stretch in plane
    strain, its third direction the constrained one)."""
    mu = E / (2 * (1 + NU))
    s = states(kind, lam, None)
    F = np.diag(s)
    energy = lambda G: ENERGY[law](G, E, NU, shape=SHAPES[law])  # noqa: E731
    _, P = code_w_p(energy, F, key=law)
    sigma = P @ F.T / np.linalg.det(F)
    expect = lam * published_nominal(law, SHAPES[law], kind, lam, mu)
    assert sigma[0, 0] - sigma[2, 2] == pytest.approx(expect, rel=1e-9)
    if kind == "planar":
        F2 = np.diag([lam, 1 / lam])
        _, P2 = code_w_p(energy, F2, key=law)
        sig2 = P2 @ F2.T
        assert sig2[0, 0] - sig2[1, 1] == pytest.approx(expect, rel=1e-9)


@pytest.mark.parametrize("F", [np.diag([1.4, 0.9, 1.1]), np.diag([2.0, 0.5, 0.5]),
                               np.array([[1.2, 0.3, 0.0], [0.1, 0.8, 0.2], [0.0, -0.3, 1.1]])])
def test_reduce_to_isochoric_neohookean(F):
    """Mooney–Rivlin (C01 = 0), Yeoh (one term) and Ogden (one term, α = 2): the isochoric
    Neo-Hookean, energy and P to 1e-12."""
    Wr, Pr = isochoric_neohookean(F)
    for key, energy in (("mr-nh", lambda G: mooney_rivlin_energy(G, E, NU, shape=(0.5, 0.0))),
                        ("yeoh-nh", lambda G: yeoh_energy(G, E, NU, shape=(0.5,))),
                        ("ogden-nh", lambda G: ogden_energy(G, E, NU, shape=((1.0, 2.0),)))):
        W, P = code_w_p(energy, F, key=key)
        assert W == pytest.approx(Wr, rel=1e-12)
        assert close(P, Pr, 1e-12)


def test_stretch_sums_through_both_branches():
    """Σ c_i^a from the invariants against the eigenvalues, on both sides of the switches
    (triple coincidence J2 = 1e-4 m², equal pair δ² = 1e-4 b²) and at coalescence: 1e-12."""
    from ngsolve import CF

    exps = [1.25, -1.0, 3.5]
    cases = [np.array([1.0, 1.0, 1.0]), np.array([1.0 + 1e-9, 1.0, 1.0 - 1e-9])]
    for eps in (5e-3, 8e-3, 1.2e-2, 2e-2, 0.3):  # J2/m² around 1e-4 for eps ~ 1e-2
        cases.append(np.array([1 + eps, 1.0, 1 - eps]))
    for d in (0.0, 1e-8, 0.9e-2, 1.1e-2, 0.2):  # pairs around δ/b = 1e-2
        cases.append(np.array([3.0, 1.0 + d, 1.0 - d]))
    mesh, _, mp = _point(2)
    for c in cases:
        c = c / np.prod(c) ** (1 / 3)  # det = 1
        I1, I2 = c.sum(), c[0] * c[1] + c[1] * c[2] + c[0] * c[2]
        got = [s(mp) for s in stretch_power_sums(CF(I1), CF(I2), exps)]
        for g, a in zip(got, exps):
            assert g == pytest.approx(np.sum(c ** a), rel=1e-12), (c, a)


# --------------------------------------------------------------------------------------------
def _assembled(energy, mesh, order, vec=None):
    from ngsolve import BilinearForm, Grad, GridFunction, Variation, VectorH1, dx

    fes = VectorH1(mesh, order=order)
    u = fes.TrialFunction()
    a = BilinearForm(fes)
    a += Variation(energy(Grad(u)).Compile() * dx)
    gfu = GridFunction(fes)
    if vec is not None:
        gfu.Set(vec[0])
        gfu.vec.FV().NumPy()[:] += vec[1](fes.ndof)
    a.AssembleLinearization(gfu.vec)
    r = gfu.vec.CreateVector()
    a.Apply(gfu.vec, r)
    return a, gfu, r


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("law", list(SHAPES))
def test_u_zero_residual_and_tangent_are_linear_elasticity(law, d):
    """At u = 0 (where Newton starts): the residual is finite and zero (to round-off: below
    1e-15 of the largest tangent entry), and the tangent is the linear-elastic one with (E, ν)
    to 1e-9 relative."""
    from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh

    mesh = MakeStructured3DMesh(nx=1, ny=1, nz=2) if d == 3 else MakeStructured2DMesh(3, 2)
    a, _, r = _assembled(lambda G: ENERGY[law](G, E, NU, shape=SHAPES[law]), mesh, 2)
    lin, _, _ = _assembled(lambda G: linear_energy(G, E, NU), mesh, 2)
    res = r.FV().NumPy()
    K, KL = a.mat.AsVector().FV().NumPy(), lin.mat.AsVector().FV().NumPy()
    assert np.all(np.isfinite(res)) and np.all(np.isfinite(K))
    # zero to round-off: ∂Ī1/∂F = 2F - 2/3 I1 F^-T vanishes at F = I only in exact arithmetic
    assert np.abs(res).max() <= 1e-15 * np.abs(KL).max()
    assert np.abs(K - KL).max() <= 1e-9 * np.abs(KL).max()


@pytest.mark.parametrize("law", list(SHAPES))
@pytest.mark.parametrize("state", ["general-2d", "uniaxial-3d"])
def test_tangent_is_derivative_of_residual(law, state):
    """K(u) d against central differences of the residual: at a large deformation plus noise
    (2D, order 2), and at an exact uniaxial stretch (3D, two equal stretches: Ogden's equal-pair
    branch)."""
    from ngsolve import CF, x, y, z
    from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh

    rng = np.random.default_rng(5)
    if state == "general-2d":
        mesh, order = MakeStructured2DMesh(3, 3), 2
        u0 = (CF((0.4 * x * y - 0.1 * y, -0.5 * x * x + 0.2 * y * y)),  # stretch, shear, rotation
              lambda n: 1e-3 * rng.standard_normal(n))
    else:
        mesh, order = MakeStructured3DMesh(nx=2, ny=2, nz=2), 1
        u0 = (CF((0.6 * x, -0.2 * y, -0.2 * z)), lambda n: np.zeros(n))
    a, gfu, _ = _assembled(lambda G: ENERGY[law](G, E, NU, shape=SHAPES[law]), mesh, order,
                           vec=u0)
    assert np.all(np.isfinite(gfu.vec.FV().NumPy()))
    d = gfu.vec.CreateVector()
    d.FV().NumPy()[:] = rng.standard_normal(len(d))
    kd = d.CreateVector()
    kd.data = a.mat * d
    h = 1e-6
    w, rp, rm = d.CreateVector(), d.CreateVector(), d.CreateVector()
    w.data = gfu.vec + h * d
    a.Apply(w, rp)
    w.data = gfu.vec - h * d
    a.Apply(w, rm)
    fd = (rp.FV().NumPy() - rm.FV().NumPy()) / (2 * h)
    err = np.linalg.norm(fd - kd.FV().NumPy()) / np.linalg.norm(fd)
    assert err <= 1e-7, err


def test_plane_stress_and_bad_shapes_are_refused():
    from ngsolve import Grad

    _, gfu, _ = _point(2)
    for law in SHAPES:
        with pytest.raises(ValueError, match="plane"):
            ENERGY[law](Grad(gfu), E, NU, "stress", shape=SHAPES[law])
    with pytest.raises(ValueError, match="sum"):
        mooney_rivlin_energy(Grad(gfu), E, NU, shape=(0.5, 0.1))
    with pytest.raises(ValueError, match="sum"):
        ogden_energy(Grad(gfu), E, NU, shape=((0.5, 2.0),))
    with pytest.raises(ValueError, match="law"):
        Law("arruda_boyce", ())


# --------------------------------------------------------------------------------------------
# presets: the rule, through the settings
# --------------------------------------------------------------------------------------------
MU0 = 1.0e8  # μ0 of the test preset (E1 ≈ 3e8 Pa, the stiffness of the small pa-inverter tests)
TEST_PRESET = "test-rubber"


def _test_preset():
    from pacto_ng.physics.presets import Fit, Preset

    src = "test parameters of tests/physics/test_hyperelastic_models.py (not a material)"
    mr = tuple(MU0 * c for c in SHAPES["mooney_rivlin"])
    yeoh = tuple(MU0 * c for c in SHAPES["yeoh"])
    ogden = tuple((MU0 * m, a) for m, a in SHAPES["ogden"])
    return Preset(TEST_PRESET, "test rubber", (Fit("ogden", ogden, src),
                                               Fit("mooney_rivlin", mr, src),
                                               Fit("yeoh", yeoh, src)))


@pytest.fixture
def preset():
    from pacto_ng.physics.presets import register, unregister

    p = register(_test_preset())
    yield p
    unregister(TEST_PRESET)


def test_preset_rule(preset):
    """A preset sets E1 = 2 μ0 (1 + ν), scales E0 with it, and its own ν (0.45) unless
    ``--set nu=`` gave another; the rubber models take the preset's fit of their law; a law the
    preset has no fit of, and an unknown name, are one-line errors naming the field."""
    from pacto_ng.params import InputError, Parameters
    from pacto_ng.physics.presets import law_for

    case = Parameters(model="linear", E1=3e9, E0=3e3, nu=0.3)  # a case's defaults
    p = case.with_overrides({"material": TEST_PRESET})
    assert p.material == TEST_PRESET
    assert p.nu == 0.45 and p.E1 == pytest.approx(2 * MU0 * 1.45, rel=1e-15)
    assert p.E0 / p.E1 == pytest.approx(3e3 / 3e9, rel=1e-15)
    assert p.replace(order=2).E1 == p.E1 and p.replace(order=2).nu == 0.45  # stable
    q = case.with_overrides({"material": TEST_PRESET, "nu": "0.49"})  # the user's ν wins
    assert q.nu == 0.49 and q.E1 == pytest.approx(2 * MU0 * 1.49, rel=1e-15)
    for model in ("mooney_rivlin", "yeoh", "ogden"):
        law = law_for(model, TEST_PRESET)
        assert law.name == model and law.shape == pytest.approx(np.array(SHAPES[model]),
                                                                rel=1e-15)
    assert law_for("wang", TEST_PRESET).name == "ogden"  # the preset's own law
    assert law_for("linear", TEST_PRESET) is None
    with pytest.raises(InputError, match="^material: unknown preset 'nonesuch'"):
        case.with_overrides({"material": "nonesuch"})
    from pacto_ng.physics.presets import Fit, Preset, register, unregister

    register(Preset("yeoh-only", "t", (Fit("yeoh", (1e5, 0.0, 0.0), "test parameters"),)))
    try:
        with pytest.raises(InputError, match="^model: material 'yeoh-only' has no ogden fit"):
            case.with_overrides({"material": "yeoh-only", "model": "ogden"})
    finally:
        unregister("yeoh-only")


#: the shipped presets' published Yeoh coefficients (C10, C20, C30) in Pa, transcribed here
#: from their sources (the MPa values of the sources times 1e6), independently of presets.py
PUBLISHED_YEOH = {
    "ecoflex-00-30": (17e3, -200.0, 23.0),
    "dragonskin-30": (153.6e3, 1.6e3, 0.0),
    "elastic-50a": (505.6e3, 0.0, 2.562e3),
}


@pytest.mark.parametrize("name", sorted(PUBLISHED_YEOH))
@pytest.mark.parametrize("kind", ["uniaxial", "equibiaxial", "planar"])
@pytest.mark.parametrize("lam", [0.8, 1.5, 3.0])
def test_shipped_preset_against_published_yeoh(name, kind, lam):
    """Each shipped preset through ``--set material=NAME`` (the settings' E1 and ν, the law the
    yeoh and wang models use) gives, at isochoric homogeneous states, ``σ1 - σ3 = λ P`` with
    Rivlin's nominal stress of the published Yeoh coefficients in Pa, to 1e-9."""
    from pacto_ng.params import Parameters
    from pacto_ng.physics.presets import law_for

    p = Parameters(model="yeoh", E1=3e9, E0=3e3, nu=0.3).with_overrides({"material": name})
    C = PUBLISHED_YEOH[name]
    assert p.nu == 0.45 and p.E1 == pytest.approx(2 * 2 * C[0] * 1.45, rel=1e-14)
    s = states(kind, lam, None)
    x = np.sum(s ** 2) - 3
    W1 = C[0] + 2 * C[1] * x + 3 * C[2] * x ** 2
    nominal = {"uniaxial": 2 * (lam - lam ** -2), "equibiaxial": 2 * (lam - lam ** -5),
               "planar": 2 * (lam - lam ** -3)}[kind] * W1
    law = law_for("yeoh", name)
    assert law_for("wang", name) == law
    _, P = code_w_p(lambda G: law(G, p.E1, p.nu), np.diag(s), key=("preset", name))
    sigma = P @ np.diag(s)  # J = 1
    assert sigma[0, 0] - sigma[2, 2] == pytest.approx(lam * nominal, rel=1e-9)


# --------------------------------------------------------------------------------------------
# finite-difference checks of the whole chain (the small pa-inverter of tests/small_cases.py)
# --------------------------------------------------------------------------------------------
P_IN = 2e6


def _chain(model, load):
    """x -> filter -> projection -> Darcy p -> mechanics (``model`` with the test preset, as
    ``make_energy`` builds it for a run) -> output displacement, strain energy, -Δ/SE (and the
    Darcy compliance under the fixed load)."""
    from ngsolve import Parameter

    from small_cases import small_pa_mesh
    from pacto_ng.core import Chain
    from pacto_ng.design import DesignField, Embed, FixPassive
    from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
    from pacto_ng.params import Parameters
    from pacto_ng.physics.darcy import DarcyPressure
    from pacto_ng.physics.darcy_load import Compliance, darcy_body, darcy_follower
    from pacto_ng.physics.energy import make_energy
    from pacto_ng.physics.loads import Port, Spring
    from pacto_ng.physics.mechanics import Mechanics, Supports
    from pacto_ng.physics.newton import NewtonSettings
    from pacto_ng.responses import MechanismRatio, StrainEnergy, output_displacement

    mesh = small_pa_mesh("quads")
    params = Parameters(model=model, material=TEST_PRESET, E0=3e4, nu=0.4)
    energy, guard, linear = make_energy(params, Parameter(3.0))
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=P_IN, order=1)
    if load == "fixed":
        extra = {"body": darcy_body("p")}
    else:
        extra = {"residual_density": darcy_follower(
            "p", energy.gamma if model == "wang" else None)}
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), thickness=1e-3, guard=guard,
                     linear=linear, newton=NewtonSettings(rtol=1e-12), **extra)
    field = DesignField(mesh, solid=("block",))
    responses = [output_displacement(mech, Port("output", (-1.0, 0.0))), StrainEnergy(mech),
                 MechanismRatio(scale=1.0)]
    if load == "fixed":
        responses.append(Compliance(mech, dar))
    chain = Chain([Embed(field), HelmholtzFilter(mesh, 0.002), HeavisideProjection(2.0),
                   FixPassive(field), dar, mech] + responses)
    x0 = np.random.default_rng(1).uniform(0.2, 0.8, field.n)
    return chain, mech, x0, [r.output for r in responses]


#: the fast ones (measured first forward passes on 200 quads: Mooney–Rivlin and Yeoh 0.1 s,
#: Ogden 0.6 s, Wang over Ogden 0.54 s; the others carry the ``slow`` mark)
FAST_CHAINS = {("mooney_rivlin", "fixed"), ("yeoh", "follower")}


def _chain_params():
    for model in ("mooney_rivlin", "yeoh", "ogden", "wang"):
        for load in ("fixed", "follower"):
            marks = () if (model, load) in FAST_CHAINS else (pytest.mark.slow,)
            yield pytest.param(model, load, marks=marks, id=f"{model}-{load}")


@pytest.mark.parametrize("model,load", _chain_params())
def test_chain_gradient(preset, model, load):
    """Every response's adjoint gradient against central differences along random directions
    (relative error < 1e-6), at a state Newton needs several iterations for; Wang interpolates
    the preset's Ogden law."""
    from small_cases import chain_fd

    chain, mech, x0, names = _chain(model, load)
    chain.forward(x=x0)
    assert mech.result.converged and mech.result.iterations > 1
    errors = {n: chain_fd(chain, n, x0, h=1e-5, directions=3).rel_error for n in names}
    print(model, load, errors)
    assert max(errors.values()) < 1e-6, errors


@pytest.mark.slow
def test_chain_gradient_3d(preset):
    """3D: the 8 x 3 x 2 hexahedral box of tests/physics/test_3d_gradients.py, Ogden with the
    test preset, fixed Darcy load on a face: compliance and output displacement."""
    from ngsolve import Parameter
    from ngsolve.meshes import MakeStructured3DMesh

    from small_cases import chain_fd
    from pacto_ng.core import Chain
    from pacto_ng.design import DesignField, Embed, FixPassive
    from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
    from pacto_ng.params import Parameters
    from pacto_ng.physics.darcy import DarcyPressure
    from pacto_ng.physics.darcy_load import Compliance, darcy_body
    from pacto_ng.physics.energy import make_energy
    from pacto_ng.physics.loads import Port
    from pacto_ng.physics.mechanics import Field, Mechanics, Supports
    from pacto_ng.physics.newton import NewtonSettings
    from pacto_ng.responses import output_displacement

    mesh = MakeStructured3DMesh(hexes=True, nx=8, ny=3, nz=2,
                                mapping=lambda x, y, z: (1.0 * x, 0.4 * y, 0.3 * z))
    params = Parameters(model="ogden", material=TEST_PRESET, E0=3e4, nu=0.4)
    energy, guard, linear = make_energy(params, Parameter(3.0))
    field = DesignField(mesh)
    dar = DarcyPressure(mesh, inlet="left", zero="right", p_in=2e5, delta_s=0.1, order=1)
    port = Port("front", (0.0, 1.0, 0.0), spring=1e6)
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", Field("p", dar.fes)),
                     body=darcy_body("p"), supports=Supports(clamp=("back",)), guard=guard,
                     linear=linear, springs=port.springs(), newton=NewtonSettings(rtol=1e-12))
    responses = [Compliance(mech, dar), output_displacement(mech, port)]
    chain = Chain([Embed(field), HelmholtzFilter(mesh, 0.3), HeavisideProjection(2.0),
                   FixPassive(field), dar, mech] + responses)
    x0 = np.random.default_rng(2).uniform(0.3, 0.7, field.n)
    chain.forward(x=x0)
    assert mech.result.converged and mech.result.iterations > 1
    errors = {r.output: chain_fd(chain, r.output, x0, h=1e-4, directions=2, stencil=4).rel_error
              for r in responses}
    print(errors)
    assert max(errors.values()) < 1e-6, errors


# --------------------------------------------------------------------------------------------
# pacto run --set material=NAME (a case file registers its preset, as a user's would)
# --------------------------------------------------------------------------------------------
CASE_FILE = """
import pacto_ng as pn
from pacto_ng.physics.presets import Fit, Preset, register

register(Preset("test-rubber", "test rubber", (
    Fit("ogden", ((1.2e5, 2.5), (-2e4, -2.0)), "test parameters (not a material)"),)))
CASE = pn.get_case("cantilever")
"""


@pytest.mark.parametrize("model", ["linear", pytest.param("ogden", marks=pytest.mark.slow)])
def test_pacto_run_with_a_material(tmp_path, model):
    """``pacto run case.py --set material=test-rubber`` on a small mesh: the run completes, and
    params.json holds the preset's E1 = 2 μ0 (1 + 0.45) and ν = 0.45."""
    import json

    from pacto_ng.cli import main
    from pacto_ng.physics.presets import unregister

    case = tmp_path / "rubber_case.py"
    case.write_text(textwrap.dedent(CASE_FILE))
    out = tmp_path / model
    try:
        assert main(["run", "--no-part", str(case), "--nelx", "20", "--nely", "10", "--iterations", "1",
                     "--model", model, "--load", "0.5", "--set", "material=test-rubber",
                     "--out", str(out), "--quiet"]) == 0
    finally:
        unregister("test-rubber")  # the case file registered it in this process
    params = json.loads((out / "params.json").read_text())["params"]
    assert params["material"] == "test-rubber" and params["nu"] == 0.45
    assert params["E1"] == pytest.approx(2 * 1e5 * 1.45, rel=1e-12)


def test_unknown_material_is_one_line_exit_2(capsys):
    from pacto_ng.cli import main

    assert main(["run", "--no-part", "mbb", "--set", "material=no-such-silicone"]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and "material: unknown preset 'no-such-silicone'" in lines[0], lines
    assert "Traceback" not in err
