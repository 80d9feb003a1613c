"""The symbolic linear system of a linear, conservative Mechanics block whose energy declares
itself quadratic (``Mechanics.linear_system``) against the automatic-differentiation route it replaces: the tangent from
``AssembleLinearization`` of the ``Variation`` form, the residual from ``Apply``, the strain
energy from ``Integrate`` and every derivative from ``.Diff``."""
import numpy as np
import pytest
import scipy.sparse as sp

from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_body
from pacto_ng.physics.loads import PointLoad, Spring
from pacto_ng.physics.materials import linear_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.traits import DeclarationError, declare
from pacto_ng.responses import StrainEnergy
from tests.small_cases import small_pa_mesh

pytestmark = pytest.mark.usefixtures("one_thread")

SUP = Supports(clamp=("fixed",), fix_y=("symmetry",))




def _variation_residual(mech, vec, out, load=1.0):
    """The general route: Apply of the Variation form minus the body load's LinearForm."""
    from ngsolve import LinearForm

    mech.load.Set(load)
    mech.a.Apply(vec, out)
    if mech.body is not None:
        lf = LinearForm(mech.fes)
        lf += mech.thickness * mech.body(mech.fes.TestFunction(), mech.coeffs) * mech.DX
        lf.Assemble()
        out.data -= load * lf.vec

def _diff_form(dens, field, DX):
    """The reference: the LinearForm of the symbolic derivative ``dens.Diff(field, q)``."""
    from ngsolve import LinearForm

    lf = LinearForm(field.space)
    lf += dens.Diff(field.gf, field.space.TestFunction()) * DX
    lf.Assemble()
    return lf

def _csr(mat):
    r, c, v = mat.COO()
    return sp.csr_matrix((np.array(v), (np.array(r), np.array(c))), shape=(mat.height, mat.width))


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def _simp(plane="stress"):
    """SIMP linear elasticity declared quadratic (no numpy modulus: C per element per design)."""
    return declare(lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4,
                                              plane), reads=("rho_bar",), quadratic=True)


def _block(kind, order, energy=None, plane="stress", darcy=False):
    mesh = small_pa_mesh(kind)
    energy = energy or _simp(plane)
    fields, body, loads, dar = ["rho_bar"], None, (), None
    if darcy:
        dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=order)
        fields.append(dar.field())
        body = darcy_body("p")
    else:
        loads = (PointLoad("output", (0.0, -1.0)),)
    mech = Mechanics(mesh, order=order, energy=energy, fields=fields, supports=SUP,
                     loads=loads, springs=(Spring("output", 1e4, (1.0, 0.0)),), body=body,
                     thickness=1e-3, linear=True)
    rng = np.random.default_rng(3)
    rho = rng.uniform(0.05, 1.0, mesh.ne)
    values = [rho] + ([dar.forward(rho)] if darcy else [])
    mech.set_fields(*values)
    return mech, rng


def _compare(mech, rng):
    lin = mech.linear_system
    assert lin is not None and mech.assembly["linear_system"] is not None
    u = mech.gfu.vec
    u.FV().NumPy()[:] = np.where(mech.free, 1e-4 * rng.standard_normal(len(mech.free)), 0.0)
    mech.assemble_tangent(u, 1.0)
    mech.a.AssembleLinearization(u)
    K, K_ad = _csr(mech.matrix), _csr(mech.a.mat)
    assert abs(K - K_ad).max() <= 1e-12 * abs(K_ad).max()  # measured 2e-16
    for load in (1.0, 0.37):
        r, r_ad = u.CreateVector(), u.CreateVector()
        mech.residual(u, r, load)
        _variation_residual(mech, u, r_ad, load)
        # relative to the larger of the two parts K u and s f
        Ku = (mech.matrix * u).Evaluate().FV().NumPy()
        scale = max(np.max(np.abs(Ku)), np.max(np.abs(load * lin.f.vec.FV().NumPy())))
        assert np.max(np.abs(r.FV().NumPy() - r_ad.FV().NumPy())) <= 1e-12 * scale
        ext = u.CreateVector()
        ext[:] = 0.0
        _variation_residual(mech, ext, r_ad, load)
        assert mech.load_norm(load) == pytest.approx(
            np.linalg.norm(r_ad.FV().NumPy()[mech.free]), rel=1e-12)


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quads", 1), ("quads", 2)])
@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_symbolic_tangent_and_residual_equal_the_variation_ones(kind, order, plane):
    mech, rng = _block(kind, order, plane=plane)
    _compare(mech, rng)
    assert mech.assembly["linear_system"] == "hessian" and mech.assembly["modulus"] is None


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quads", 2)])
def test_design_dependent_body_load_takes_the_symbolic_route(kind, order):
    """With a Darcy body load: K, R = K u - s f (f the body load of this design) and the load
    norm equal the Variation ones, and so does λᵀ∂R/∂field for both fields (ρ through C and
    the body term, p through the body term)."""
    mech, rng = _block(kind, order, darcy=True)
    _compare(mech, rng)
    assert mech.assembly["body_coupling"] == ("p",)
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0.0)
    for f, g in zip(mech.fields, mech.backward(mech.lam.vec)):
        gen = _diff_form(mech.volume_density(mech.gfu).Diff(mech.gfu, mech.lam), f, mech.DX)
        a = g if isinstance(g, np.ndarray) else g.FV().NumPy()
        assert _rel(-a, gen.vec.FV().NumPy()) <= 1e-12, f.name


@pytest.mark.parametrize("seed", [0, 1] + [pytest.param(s, marks=pytest.mark.slow)
                                           for s in (2, 3, 4)])
def test_pressure_case_finite_differences_at_the_round_off_floor(seed):
    """The symbolic route with a Darcy load, end to end: the PneuNet's gradients against
    five-point finite differences on five random designs (seeds 0-4; 2-4 are slow: each
    design is one more whole check of the same route, 2.7 s of the default run apiece).
    Measured 5e-10 - 2.4e-9 with the
    residual and SE evaluated element by element; with K u and ½ u·K_φ u from the assembled
    matrix (whose entries cancel where the structure moves rigidly) 5e-7 - 1.2e-5.  Since K
    comes from element matrices (pacto_ng/physics/scatter.py) and Newton's predictor from K u
    (the convergence test still uses the element-wise residual): 2.3e-10 - 1.8e-8 over three runs
    (2026-12-02)."""
    from pacto_ng.case import get_case
    from pacto_ng.gradcheck import check_case

    case = get_case("pneunet")
    # at β = 32, where the floor above was measured: the check runs at the case's final β, and
    # the case's 128 steepens the projection so that the five-point differences' own error
    # reaches 1.3e-7 (seed 1)
    params = case.defaults.with_overrides({"load_sensitivity": "1", "beta_max": "32"})
    assert check_case(case, params, seed=seed, quiet=True) <= 1e-7


def _undeclared_and_declared(energy):
    """``(block of the energy as it is, block of the energy declared quadratic)``; the second
    is None when the declaration is refused (its DeclarationError is returned instead)."""
    mech, _ = _block("quads", 1, energy=energy)
    try:
        _block("quads", 1, energy=declare(energy, reads=("rho_bar",), quadratic=True))
    except DeclarationError as err:
        return mech, err
    raise AssertionError("a wrong quadratic declaration was accepted")


def test_position_dependent_energy_is_not_quadratic_per_element():
    """E depends on x: C is not constant per element.  Undeclared: the general route; declared
    quadratic: refused."""
    from ngsolve import x

    energy = lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0) * (1 + 50 * x), 0.4)
    mech, err = _undeclared_and_declared(energy)
    assert mech.linear_system is None and mech.assembly["linear_system"] is None
    assert "constant on each element" in str(err)


def test_energy_with_a_linear_term_keeps_the_variation_route():
    """A pre-stress σ0 : G: the residual is not K u - s f, so Mechanics keeps ``Variation``,
    and a quadratic declaration is refused."""
    from ngsolve import CF, InnerProduct

    s0 = CF((1e3, 2e3, 2e3, -1e3), dims=(2, 2))
    energy = lambda G, c: (linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4)
                           + InnerProduct(s0, G))
    mech, err = _undeclared_and_declared(energy)
    assert mech.linear_system is None
    assert "linear term" in str(err)


def test_energy_with_a_constant_is_not_quadratic():
    """φ + const: SE is not ½ u·K_φ u, so it is not quadratic (StrainEnergy integrates and
    differentiates it automatically); a quadratic declaration is refused."""
    energy = lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4) + 7.0
    mech, err = _undeclared_and_declared(energy)
    assert mech.linear_system is None and not StrainEnergy(mech).uses_linear_system
    assert "constant in G" in str(err)


def test_a_declaration_verified_at_drawn_points_still_refuses_each_wrong_one(monkeypatch):
    """On a mesh with more quadrature points than ``VERIFY_POINTS`` the declaration is
    verified at that many drawn points (here 7 of the small mesh's): each wrong declaration
    above is still refused for its own reason, and the right one is accepted."""
    from ngsolve import CF, InnerProduct, x

    from pacto_ng.physics import linear_system

    monkeypatch.setattr(linear_system, "VERIFY_POINTS", 7)
    simp = lambda c: simp_cf(c["rho_bar"], 3e3, 3e9, 3.0)
    s0 = CF((1e3, 2e3, 2e3, -1e3), dims=(2, 2))
    wrong = {"constant on each element": lambda G, c: linear_energy(G, simp(c) * (1 + 50 * x),
                                                                    0.4),
             "linear term": lambda G, c: linear_energy(G, simp(c), 0.4) + InnerProduct(s0, G),
             "constant in G": lambda G, c: linear_energy(G, simp(c), 0.4) + 7.0}
    for why, energy in wrong.items():
        assert why in str(_undeclared_and_declared(energy)[1])
    mech, _ = _block("quads", 1, energy=declare(lambda G, c: linear_energy(G, simp(c), 0.4),
                                                reads=("rho_bar",), quadratic=True))
    assert mech.linear_system is not None


def test_undeclared_energy_takes_the_general_route():
    """The same SIMP energy without its declaration (with a Darcy load): no linear system and
    no body coupling (the energy may read p), and the Variation route gives the same solution
    as the declared one."""
    declared, _ = _block("trig", 1, darcy=True)
    plain, _ = _block("trig", 1, energy=lambda G, c: _simp()(G, c), darcy=True)
    assert declared.assembly["linear_system"] == "hessian"
    assert declared.assembly["body_coupling"] == ("p",)
    assert plain.assembly == {"linear_system": None, "modulus": None, "body_coupling": (),
                              "load_norm": "residual"}
    u1, u2 = declared.forward(), plain.forward()
    assert np.max(np.abs(u1.FV().NumPy())) > 0
    assert _rel(u2.FV().NumPy(), u1.FV().NumPy()) <= 1e-10


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quads", 2)])
def test_quadratic_energy_responses_and_sensitivities(kind, order):
    """SE, ∂SE/∂u, ∂SE/∂ρ and λᵀ∂R/∂ρ from C equal the Integrate / Variation / Diff ones."""
    from ngsolve import BilinearForm, Grad, Integrate, Variation

    mech, rng = _block(kind, order)
    u = mech.gfu.vec
    u.FV().NumPy()[:] = np.where(mech.free, 1e-4 * rng.standard_normal(len(mech.free)), 0.0)
    se = StrainEnergy(mech)
    assert se.uses_linear_system
    val = se.forward(u)
    dens = mech.thickness * mech.energy(Grad(se.gfu), mech.coeffs)
    assert val == pytest.approx(Integrate(dens * mech.DX, mech.mesh), rel=1e-12)
    du, drho = se.backward(1.0)
    w = mech.fes.TrialFunction()
    ef = BilinearForm(mech.fes)
    ef += Variation((mech.thickness * mech.energy(Grad(w), mech.coeffs)) * mech.DX)
    ref = u.CreateVector()
    ef.Apply(u, ref)
    assert _rel(du.FV().NumPy(), ref.FV().NumPy()) <= 1e-12
    f_rho = mech.fields[0]
    lf = _diff_form(dens, f_rho, mech.DX)
    assert _rel(drho, lf.vec.FV().NumPy()) <= 1e-12
    # mechanics sensitivity λᵀ∂R/∂ρ (through C and the body term) against the Diff form
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0.0)
    fast = mech.field_sensitivity("rho_bar")
    gen = _diff_form(mech.volume_density(mech.gfu).Diff(mech.gfu, mech.lam), f_rho, mech.DX)
    assert _rel(fast, gen.vec.FV().NumPy()) <= 1e-12


def test_new_design_reassembles():
    """set_fields marks K, f and ∂C/∂ρ stale: a second design gives its own residual."""
    mech, rng = _block("quads", 1)
    u = mech.gfu.vec
    u.FV().NumPy()[:] = np.where(mech.free, 1e-4 * rng.standard_normal(len(mech.free)), 0.0)
    r1, r2, r_ad = u.CreateVector(), u.CreateVector(), u.CreateVector()
    mech.residual(u, r1, 1.0)
    rho = rng.uniform(0.05, 1.0, mech.mesh.ne)
    mech.set_fields(rho)
    mech.residual(u, r2, 1.0)
    _variation_residual(mech, u, r_ad)
    assert _rel(r2.FV().NumPy(), r_ad.FV().NumPy()) <= 1e-10
    assert _rel(r1.FV().NumPy(), r_ad.FV().NumPy()) > 1e-3


# -- nonlinear, stress-free energies: the load norm from the LinearForm of the loads -----------
@pytest.mark.parametrize("model", ["neohookean", "wang"])
@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_load_norm_of_a_stress_free_energy_equals_the_residual_at_zero(model, plane):
    from pacto_ng.physics.energy import make_energy
    from pacto_ng.params import Parameters
    from ngsolve import Parameter

    mesh = small_pa_mesh("trig")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=1)
    params = Parameters().with_overrides({"model": model, "plane": plane, "E1": "3e9",
                                          "E0": "3e3", "nu": "0.4"})
    energy, guard, linear = make_energy(params, Parameter(3.0))
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", dar.field()),
                     supports=SUP, springs=(Spring("output", 1e4, (1.0, 0.0)),),
                     body=darcy_body("p"), thickness=1e-3, guard=guard, linear=linear)
    assert mech.assembly["load_norm"] == "load_vectors"
    rng = np.random.default_rng(5)
    rho = rng.uniform(0.05, 1.0, mesh.ne)
    mech.set_fields(rho, dar.forward(rho))
    zero, r = mech.gfu.vec.CreateVector(), mech.gfu.vec.CreateVector()
    zero[:] = 0.0
    for load in (1.0, 0.25):
        mech.residual(zero, r, load)
        ref = np.linalg.norm(r.FV().NumPy()[mech.free])
        assert mech.load_norm(load) == pytest.approx(ref, rel=1e-12)


def test_prestressed_energy_keeps_the_residual_load_norm():
    from ngsolve import CF, InnerProduct

    mesh = small_pa_mesh("trig")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=1)
    s0 = CF((1e3, 0.0, 0.0, 1e3), dims=(2, 2))
    from pacto_ng.physics.materials import neohookean_energy

    energy = lambda G, c: (neohookean_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4)
                           + InnerProduct(s0, G))
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", dar.field()),
                     supports=SUP, body=darcy_body("p"), thickness=1e-3)
    assert mech.assembly["load_norm"] == "residual"


# -- the numpy modulus of the element-matrix route ------------------------------------------
def _case_energy(penal=3.0, fields=("rho_bar",), wrong=False):
    from ngsolve import Parameter

    from pacto_ng.physics.energy import make_energy
    from pacto_ng.params import Parameters

    params = Parameters(model="linear", E0=3e3, E1=3e9, E2=6e9, nu=0.4, plane="stress")
    energy, _, _ = make_energy(params, Parameter(penal), fields)
    if wrong:  # a numpy twin that is not the energy's modulus (p = 2.9): must be refused
        import dataclasses

        from pacto_ng.interpolation import simp_np

        def bad(values):
            E, d = simp_np(values[fields[0]], 3e3, 3e9, 2.9)
            return E, {fields[0]: d}
        energy.traits = dataclasses.replace(energy.traits, modulus=bad)
    return energy


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quads", 2)])
def test_numpy_modulus_gives_the_variation_tangent_and_sensitivities(kind, order):
    """The case's energy declares its numpy modulus: it is checked against the CF when the block
    is built and then gives g and ∂g/∂ρ per design; from the second design on (element
    matrices) K, R and λᵀ∂R/∂ρ equal the Variation / Diff ones."""
    mech, rng = _block(kind, order, energy=_case_energy())
    assert mech.assembly["modulus"] == "numpy"
    mech.assemble_tangent(mech.gfu.vec, 1.0)  # the first design: assembled by NGSolve
    assert mech.assembly["linear_system"] == "hessian"
    mech.set_fields(rng.uniform(0.05, 1.0, mech.mesh.ne))  # the second design
    _compare(mech, rng)
    # the element-matrix route, with the numpy modulus
    assert mech.assembly["linear_system"] == "element_matrices"
    f_rho = mech.fields[0]
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0.0)
    fast = mech.field_sensitivity("rho_bar")
    gen = _diff_form(mech.volume_density(mech.gfu).Diff(mech.gfu, mech.lam), f_rho, mech.DX)
    assert _rel(fast, gen.vec.FV().NumPy()) <= 1e-12


def test_design_dependent_body_load_term_on_the_element_matrix_route():
    """A body load that reads the density (a self-weight ``ρ̄ b``): its ``-s t ∂(b·λ)/∂ρ``
    joins λᵀ∂R/∂ρ also once the element matrices carry ∂C/∂ρ (from the second design on).
    It used to be assembled with ∂C/∂ρ from a field that route no longer fills."""
    mesh = small_pa_mesh("quads")
    body = lambda u, c: -1e6 * c["rho_bar"] * u[1]  # noqa: E731
    mech = Mechanics(mesh, order=1, energy=_case_energy(), fields=["rho_bar"], supports=SUP,
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), body=body, thickness=1e-3,
                     linear=True)
    rng = np.random.default_rng(5)
    for _ in range(2):  # the second design takes the element-matrix route
        mech.set_fields(rng.uniform(0.05, 1.0, mesh.ne))
        mech.forward()
    assert mech.assembly["linear_system"] == "element_matrices"
    mech.lam.vec.FV().NumPy()[:] = np.where(mech.free, rng.standard_normal(len(mech.free)), 0.0)
    fast = mech.field_sensitivity("rho_bar")
    gen = _diff_form(mech.volume_density(mech.gfu).Diff(mech.gfu, mech.lam), mech.fields[0],
                     mech.DX)
    assert _rel(fast, gen.vec.FV().NumPy()) <= 1e-12


def test_numpy_modulus_follows_the_penalty_parameter():
    """The penalty is an NGSolve Parameter changed by the continuation: the numpy modulus reads
    it at every design, so K after a change of p equals the Variation tangent at the new p."""
    from ngsolve import Parameter

    from pacto_ng.physics.energy import make_energy
    from pacto_ng.params import Parameters

    penal = Parameter(1.0)
    energy, _, _ = make_energy(Parameters(model="linear", E0=3e3, E1=3e9, nu=0.4,
                                          plane="stress"), penal)
    mech, rng = _block("trig", 1, energy=energy)
    assert mech.assembly["modulus"] == "numpy"
    mech.assemble_tangent(mech.gfu.vec, 1.0)
    mech.set_fields(rng.uniform(0.05, 1.0, mech.mesh.ne))
    mech.assemble_tangent(mech.gfu.vec, 1.0)
    assert mech.assembly["linear_system"] == "element_matrices"
    penal.Set(3.0)
    mech.set_fields(rng.uniform(0.05, 1.0, mech.mesh.ne))
    _compare(mech, rng)


def test_two_material_numpy_modulus_and_a_wrong_one():
    mesh_fields = ("rho_bar1", "rho_bar2")
    mesh = small_pa_mesh("trig")
    mech = Mechanics(mesh, order=1, energy=_case_energy(fields=mesh_fields), fields=mesh_fields,
                     supports=SUP, loads=(PointLoad("output", (0.0, -1.0)),), thickness=1e-3,
                     linear=True)
    assert mech.assembly["modulus"] == "numpy"
    rng = np.random.default_rng(5)
    for _ in range(2):
        mech.set_fields(rng.uniform(0.05, 1.0, mesh.ne), rng.uniform(0.05, 1.0, mesh.ne))
        mech.assemble_tangent(mech.gfu.vec, 1.0)
    assert mech.assembly["linear_system"] == "element_matrices"
    mech.set_fields(rng.uniform(0.05, 1.0, mesh.ne), rng.uniform(0.05, 1.0, mesh.ne))
    _compare(mech, rng)
    with pytest.raises(DeclarationError, match="modulus"):  # refused, with the reason
        _block("trig", 1, energy=_case_energy(wrong=True))
