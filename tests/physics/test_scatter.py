"""Matrices from precomputed element matrices (:mod:`pacto_ng.physics.scatter`) against
NGSolve's assembly of the same forms, and where each block uses them."""
import numpy as np
import pytest
import scipy.sparse as sp

from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.energy import make_energy
from pacto_ng.physics.loads import PointLoad, Spring
from pacto_ng.physics.materials import linear_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.scatter import ElementMatrices, element_colours
from pacto_ng.physics.traits import DeclarationError, declare
from tests.small_cases import small_pa_mesh


def _csr(mat):
    r, c, v = mat.COO()
    return sp.csr_matrix((np.array(v), (np.array(r), np.array(c))), shape=(mat.height, mat.width))


@pytest.mark.parametrize("kind", ["trig", "quads"])
def test_colours_share_no_vertex(kind):
    from ngsolve import VOL

    mesh = small_pa_mesh(kind)
    colour = element_colours(mesh)
    seen = {}
    for e, el in enumerate(mesh.Elements(VOL)):
        for v in el.vertices:
            assert (v.nr, colour[e]) not in seen, "two elements of one colour share a vertex"
            seen[(v.nr, colour[e])] = e
    assert colour.min() == 0 and colour.max() < 20


@pytest.mark.parametrize("kind,order", [("trig", 1), ("trig", 3), ("quads", 2)])
def test_darcy_matrix_and_sensitivity_equal_the_assembled_forms(kind, order):
    mesh = small_pa_mesh(kind)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e4, p_out=300.0, order=order)
    dar._build_scatter()
    assert dar._scatter is not None
    rng = np.random.default_rng(5)
    k, d = rng.uniform(1e-7, 1.0, mesh.ne), rng.uniform(0.0, 50.0, mesh.ne)
    dar._scatter.assemble([k, d])
    A = _csr(dar.a.mat).copy()
    dar.K.vec.FV().NumPy()[:] = k
    dar.D.vec.FV().NumPy()[:] = d
    dar.a.Assemble()
    A_ref = _csr(dar.a.mat)
    assert abs(A - A_ref).max() <= 1e-13 * abs(A_ref).max()
    # the element quadratic forms against the LinearForm sensitivity (dK = 1, dD = 0 and back)
    x, y = rng.standard_normal(dar.fes.ndof), rng.standard_normal(dar.fes.ndof)
    qK, qD = dar._scatter.quadratic(x, y)
    dar.gfp.vec.FV().NumPy()[:] = y + dar.p_out * dar._one  # (p - p_out) = y
    dar.lam.vec.FV().NumPy()[:] = x
    for dk, dd, q in ((1.0, 0.0, qK), (0.0, 1.0, qD)):
        dar._dK.vec.FV().NumPy()[:] = dk
        dar._dD.vec.FV().NumPy()[:] = dd
        dar._sens.Assemble()
        ref = dar._sens.vec.FV().NumPy()
        assert np.max(np.abs(q - ref)) <= 1e-12 * np.max(np.abs(ref))


def _mech(kind, order, energy):
    mesh = small_pa_mesh(kind)
    mech = Mechanics(mesh, order=order, energy=energy, supports=Supports(clamp=("fixed",)),
                     loads=(PointLoad("output", (0.0, -1.0)),),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), thickness=1e-3, linear=True)
    return mech, mesh


@pytest.mark.parametrize("kind,order", [("trig", 1), ("quads", 2)])
def test_simp_stiffness_from_element_matrices(kind, order):
    """SIMP declares C = E(ρ̄) C1, so from the second design on the tangent comes from the
    element matrices; equal to the Variation tangent, springs included."""
    from ngsolve import Parameter

    from pacto_ng.params import Parameters

    energy, _, _ = make_energy(Parameters(model="linear", E0=3e3, E1=3e9, nu=0.4,
                                          plane="stress"), Parameter(3.0))
    mech, mesh = _mech(kind, order, energy)
    rng = np.random.default_rng(2)
    mech.set_fields(rng.uniform(0.01, 1.0, mesh.ne))
    mech.assemble_tangent(mech.gfu.vec, 1.0)
    assert mech.assembly["linear_system"] == "hessian"  # the first design: no element matrices
    mech.set_fields(rng.uniform(0.01, 1.0, mesh.ne))
    mech.assemble_tangent(mech.gfu.vec, 1.0)
    assert mech.assembly["linear_system"] == "element_matrices"
    K = _csr(mech.matrix).copy()
    mech.a.AssembleLinearization(mech.gfu.vec)
    K_ref = _csr(mech.a.mat)
    assert abs(K - K_ref).max() <= 1e-12 * abs(K_ref).max()


def test_not_proportional_stiffness_keeps_the_assembly():
    """ν depending on ρ̄: C(ρ̄) is not a multiple of one tensor.  Declared quadratic without a
    modulus: no element matrices, also from the second design on; declared with the SIMP
    modulus: refused."""
    from pacto_ng.interpolation import simp_np

    energy = lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0),
                                        0.2 + 0.2 * c["rho_bar"], "stress")
    mech, mesh = _mech("trig", 1, declare(energy, reads=("rho_bar",), quadratic=True))
    rng = np.random.default_rng(2)
    for _ in range(2):
        mech.set_fields(rng.uniform(0.01, 1.0, mesh.ne))
        mech.assemble_tangent(mech.gfu.vec, 1.0)
    assert mech.assembly["linear_system"] == "hessian" and mech.assembly["modulus"] is None

    def modulus(values):
        E, d = simp_np(values["rho_bar"], 3e3, 3e9, 3.0)
        return E, {"rho_bar": d}

    with pytest.raises(DeclarationError, match="not E\\(fields\\) C1"):
        _mech("trig", 1, declare(energy, reads=("rho_bar",), quadratic=True, modulus=modulus))


def test_element_matrix_budget_falls_back():
    """Above ``max_entries`` the build declines (and the form is assembled as before)."""
    mesh = small_pa_mesh("trig")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", order=1)

    def setc(cs):
        dar.K.vec.FV().NumPy()[:] = cs[0]
        dar.D.vec.FV().NumPy()[:] = cs[1]

    assert ElementMatrices.build(dar.a, dar.fes, setc, 2, max_entries=10) is None


def test_element_matrices_come_with_the_second_design():
    """A single analysis does not build them; from the second design on both blocks use them,
    and the gradient of a design is the same before and after (to round-off); after
    expect_many_designs from the first design on."""
    from pacto_ng.case import build_problem, get_case

    case = get_case("pa-inverter")
    problem = build_problem(case, case.defaults.with_overrides({"model": "linear",
                                                                "maxh": "0.008"}))
    rng = np.random.default_rng(4)
    x1, x2 = (rng.uniform(0.2, 0.8, problem.field.n) for _ in range(2))
    f1, _, g1, _ = problem.evaluate(x1)
    assert problem.mech.assembly["linear_system"] == "hessian"
    assert problem.pressure_block.route == "forms"
    problem.evaluate(x2)
    assert problem.mech.assembly["linear_system"] == "element_matrices"
    assert problem.pressure_block.route == "element_matrices"
    f1b, _, g1b, _ = problem.evaluate(x1)
    assert abs(f1b - f1) <= 1e-12 * abs(f1)  # measured 2.4e-14
    assert np.max(np.abs(g1b - g1)) <= 1e-11 * np.max(np.abs(g1))  # measured 1.2e-13
    # an optimisation says that many designs follow: both blocks use them from the first
    # design of a new problem on, with the same values (to round-off)
    fresh = build_problem(case, case.defaults.with_overrides({"model": "linear",
                                                              "maxh": "0.008"}))
    fresh.mech.expect_many_designs()
    fresh.pressure_block.expect_many_designs()
    f1c, _, g1c, _ = fresh.evaluate(x1)
    assert fresh.mech.assembly["linear_system"] == "element_matrices"
    assert fresh.pressure_block.route == "element_matrices"
    assert abs(f1c - f1) <= 1e-12 * abs(f1)
    assert np.max(np.abs(g1c - g1)) <= 1e-11 * np.max(np.abs(g1))


@pytest.mark.parametrize("order", [1, 2])
def test_element_by_element_equals_the_colouring_on_tetrahedra(order, monkeypatch):
    """Above MAX_COLOURS colours (Netgen tetrahedra) the element matrices come element by
    element from the volume integrators; the springs' point and boundary terms stay in the
    constant part.  Both routes must give the same S_k, and NGSolve's assembly."""
    from netgen.occ import X, Box, OCCGeometry
    from ngsolve import CF, L2, BilinearForm, GridFunction, Grad, InnerProduct, Mesh, Sym, \
        VectorH1, dx, ds

    from pacto_ng.physics import scatter

    box = Box((0, 0, 0), (1, 0.5, 0.3))
    box.faces.Max(X).name = "end"
    mesh = Mesh(OCCGeometry(box).GenerateMesh(maxh=0.2))
    assert element_colours(mesh).max() + 1 > scatter.MAX_COLOURS
    fes = VectorH1(mesh, order=order)
    u, v = fes.TnT()
    c = GridFunction(L2(mesh, order=0))
    a = BilinearForm(fes, symmetric=True)
    a += c * InnerProduct(Sym(Grad(u)), Sym(Grad(v))) * dx
    volume = list(a.integrators)
    a += 3.0 * (CF((1, 0, 0)) * u) * (CF((1, 0, 0)) * v) * ds("end")

    def setc(cs):
        c.vec.FV().NumPy()[:] = cs[0]

    by_element = ElementMatrices.build(a, fes, setc, 1, volume=volume)
    monkeypatch.setattr(scatter, "MAX_COLOURS", 10_000)
    by_colour = ElementMatrices.build(a, fes, setc, 1)
    diff = abs(by_element.S[0] - by_colour.S[0]).max()
    assert diff <= 1e-13 * abs(by_colour.S[0]).max()
    # and against NGSolve's assembly of a design of its own
    rng = np.random.default_rng(2)
    coef = rng.uniform(1e-3, 1.0, mesh.ne)
    by_element.assemble([coef])
    A = _csr(a.mat).copy()
    setc([coef])
    a.Assemble()
    assert abs(A - _csr(a.mat)).max() <= 1e-13 * abs(_csr(a.mat)).max()
