"""The linear solvers' routes (pacto_ng/physics/solvers.py): the choice, the iterative route's
gradients against central finite differences, and direct against iterative.

The chain ``x -> Embed -> HelmholtzFilter -> HeavisideProjection -> FixPassive ->
DarcyPressure -> Mechanics -> output displacement, strain energy, -Δ/SE`` on the small
pa-inverter (tests/small_cases.py) at order 2 (at order 1 in 2D every dof is a BDDC vertex
dof and CG converges in one step), every block on the iterative route: the filter by CG with
h1amg, the Darcy pressure and the symmetric tangents by CG with BDDC, the follower tangent by
GMRES with BDDC (its adjoint by GMRES on Kᵀ).  Linear and Neo-Hookean, the Darcy pressure as
a fixed and as a follower load, Newton to 1e-12 of the load; central differences along random
directions (:func:`pacto_ng.core.check_gradient`).
"""
from __future__ import annotations

import numpy as np
import pytest

from small_cases import chain_fd, small_pa_mesh
from pacto_ng.core import Chain
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
from pacto_ng.interpolation import simp_cf, simp_np
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_body, darcy_follower
from pacto_ng.physics.loads import PointLoad, Port, Spring
from pacto_ng.physics.materials import jacobian, linear_energy, neohookean_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.routes import DIRECT_MAX_DOFS_3D, choose
from pacto_ng.physics.traits import declare
from pacto_ng.responses import MechanismRatio, StrainEnergy, output_displacement

pytestmark = pytest.mark.usefixtures("one_thread")

ORDER = 2
FD_TOL = 1e-6  # as tests/gradients/test_follower_gradients.py
SAME_TOL = 1e-8  # direct against iterative: objective and displacement (relative)


def _chain(model, load, solver):
    mesh = small_pa_mesh("trig")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=2e6 if model != "linear" else 1e5,
                        order=ORDER, solver=solver)
    modulus = lambda c: simp_cf(c["rho_bar"], 3e3, 3e8, 3.0)
    if model == "linear":
        energy, guard = (lambda G, c: linear_energy(G, modulus(c), 0.4)), None
    else:
        energy, guard = (lambda G, c: neohookean_energy(G, modulus(c), 0.4)), \
            (lambda G, c: jacobian(G))
    mech = Mechanics(mesh, order=ORDER, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),),
                     body=darcy_body("p") if load == "fixed" else None,
                     residual_density=darcy_follower("p") if load == "follower" else None,
                     thickness=1e-3, guard=guard, linear=model == "linear",
                     newton=NewtonSettings(rtol=1e-12, solver=solver))
    field = DesignField(mesh, solid=("block",))
    flt = HelmholtzFilter(mesh, 0.002, solver=solver)
    chain = Chain([Embed(field), flt, HeavisideProjection(2.0), FixPassive(field), dar, mech,
                   output_displacement(mech, Port("output", (-1.0, 0.0))), StrainEnergy(mech),
                   MechanismRatio(scale=1.0)])
    x0 = np.random.default_rng(1).uniform(0.2, 0.8, field.n)
    return chain, (flt, dar, mech), x0


def _fd(chain, name, x0):
    return chain_fd(chain, name, x0, h=1e-5, directions=3)


def test_choice():
    """``auto``: direct in 2D, for a 3D vector space of order 1 and below the threshold;
    iterative above it at order 2 and for the scalar order-1 systems (h1amg)."""
    big = DIRECT_MAX_DOFS_3D + 1
    assert choose("auto", 10 ** 7, 2, 2) == "direct"
    assert choose("auto", big, 3, 1, "bddc") == "direct"
    assert choose("auto", big, 3, 2, "bddc") == "iterative"
    assert choose("auto", big, 3, 1, "h1amg") == "iterative"
    assert choose("auto", DIRECT_MAX_DOFS_3D, 3, 2, "bddc") == "direct"
    assert choose("iterative", 10, 2, 1) == "iterative"
    assert choose("direct", big, 3, 2) == "direct"
    with pytest.raises(ValueError):
        choose("cg", 10, 2, 1)
    with pytest.raises(ValueError):
        NewtonSettings(solver="cg")


def test_auto_is_direct_in_2d():
    chain, (flt, dar, mech), x0 = _chain("linear", "fixed", "auto")
    chain.forward(x=x0)
    for block in (flt, dar, mech):
        assert block.solver_info["kind"] == "direct"
        assert block.solver_info["preconditioner"] is None
    assert mech.solver_info["method"] == "sparsecholesky"


@pytest.mark.parametrize("model,load", [("linear", "fixed"), ("linear", "follower"),
                                        ("neohookean", "fixed"), ("neohookean", "follower")])
def test_iterative_gradients(model, load):
    """The whole chain's gradients through the iterative route pass the FD check; the
    tangent's method follows its symmetry, a nonlinear energy's tangent is preconditioned by
    BDDC of its tangent at rest, and a linear system keeps assembling K by its form
    (the preconditioner is built during the assembly)."""
    chain, (flt, dar, mech), x0 = _chain(model, load, "iterative")
    chain.forward(x=x0)
    assert mech.result.converged
    info = mech.solver_info
    at_rest = model == "neohookean"
    assert info["kind"] == "iterative"
    assert info["preconditioner"] == ("bddc at rest, once per design" if at_rest else "bddc")
    assert info["method"] == ("GMRES" if load == "follower" else "CG")
    assert info["iterations"] > 1
    assert flt.solver_info["preconditioner"] == "h1amg"
    assert dar.solver_info["preconditioner"] == "bddc"
    errs = {name: _fd(chain, name, x0).rel_error for name in ("objective", "delta", "se")}
    print(model, load, errs, mech.solver_info)
    assert max(errs.values()) < FD_TOL, errs
    if mech.linear_system is not None:
        assert mech.assembly["linear_system"] == "hessian"


@pytest.mark.parametrize("model,load", [("linear", "fixed"), ("neohookean", "follower")])
def test_direct_equals_iterative(model, load):
    """The same design on both routes: the objective, the displacement and the gradient agree
    to SAME_TOL (relative)."""
    out = {}
    for solver in ("direct", "iterative"):
        chain, (_, _, mech), x0 = _chain(model, load, solver)
        vals = chain.forward(x=x0)
        out[solver] = (vals["objective"], mech.gfu.vec.FV().NumPy().copy(),
                       chain.gradient("objective"))
    (jd, ud, gd), (ji, ui, gi) = out["direct"], out["iterative"]
    assert abs(ji - jd) <= SAME_TOL * abs(jd)
    assert np.max(np.abs(ui - ud)) <= SAME_TOL * np.max(np.abs(ud))
    assert np.max(np.abs(gi - gd)) <= 1e-6 * np.max(np.abs(gd))


# -- 3D: a small tetrahedral box at order 2 (BDDC with the vertex coarse space) ---------------
L3, W3, D3 = 1.0, 0.4, 0.3


def _chain_3d(model, load, solver):
    """The box of tests/physics/test_3d_gradients.py (Netgen tetrahedra, maxh 0.15) at order
    2: clamped at x = 0, a force on the end face (compliance) or the Darcy pressure as a
    follower load (strain energy), and the output displacement of the end face against a
    spring."""
    from netgen.occ import X, Y, Box, OCCGeometry
    from ngsolve import Mesh

    from pacto_ng.physics.mechanics import Field
    from pacto_ng.responses import compliance

    box = Box((0, 0, 0), (L3, W3, D3))
    box.faces.Min(X).name = "clamp"
    box.faces.Max(X).name = "end"
    box.faces.Min(Y).name = "inlet"
    box.faces.Max(Y).name = "zero"
    mesh = Mesh(OCCGeometry(box, dim=3).GenerateMesh(maxh=0.15))
    field = DesignField(mesh)
    flt = HelmholtzFilter(mesh, 0.3, solver=solver)
    blocks = [Embed(field), flt, HeavisideProjection(2.0), FixPassive(field)]
    modulus = lambda c: simp_cf(c["rho_bar"], 3e3, 3e9, 3.0)
    if model == "linear":  # declared as the cases declare it (pacto_ng/physics/energy.py)
        energy = declare(lambda G, c: linear_energy(G, modulus(c), 0.4), reads=("rho_bar",),
                         quadratic=True, stress_free=True, modulus=lambda v: (
                             simp_np(v["rho_bar"], 3e3, 3e9, 3.0)[0],
                             {"rho_bar": simp_np(v["rho_bar"], 3e3, 3e9, 3.0)[1]}))
        guard = None
    else:
        energy, guard = (lambda G, c: neohookean_energy(G, modulus(c), 0.4)), \
            (lambda G, c: jacobian(G))
    port = Port("end", (0.0, 1.0, 0.0), spring=1e6)
    kw = dict(order=ORDER, energy=energy, supports=Supports(clamp=("clamp",)), guard=guard,
              linear=model == "linear" and load == "force", springs=port.springs(),
              newton=NewtonSettings(rtol=1e-12, solver=solver))
    if load == "force":
        mech = Mechanics(mesh, loads=(PointLoad("end", (0.0, 2e5, 0.0)),), **kw)
        responses = [compliance(mech)]
    else:
        dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=2e6, delta_s=0.1,
                            order=ORDER, solver=solver)
        blocks.append(dar)
        mech = Mechanics(mesh, fields=("rho_bar", Field("p", dar.fes)),
                         residual_density=darcy_follower("p"), **kw)
        responses = [StrainEnergy(mech)]
    responses.append(output_displacement(mech, port))
    chain = Chain(blocks + [mech] + responses)
    x0 = np.random.default_rng(2).uniform(0.3, 0.7, field.n)
    return chain, mech, [r.output for r in responses], x0


@pytest.mark.parametrize("model,load", [
    ("linear", "force"), ("neohookean", "force"),
    # slow (12 s of the default run): the unsymmetric follower tangent by GMRES and the Darcy
    # pressure on the iterative route are checked by default in 2D
    # (test_iterative_gradients[neohookean-follower]), BDDC in 3D with Newton by
    # [neohookean-force] here
    pytest.param("neohookean", "follower", marks=pytest.mark.slow)])
def test_iterative_gradients_3d(model, load):
    """The 3D chain's gradients through the iterative route (CG or GMRES with BDDC on the
    vertex coarse space, built on the tangent at rest for Neo-Hookean; h1amg for the filter) pass the FD check (five-point stencil at
    h = 1e-4, as tests/physics/test_3d_gradients.py), and BDDC really iterates."""
    chain, mech, names, x0 = _chain_3d(model, load, "iterative")
    chain.forward(x=x0)
    info = mech.solver_info
    assert info["kind"] == "iterative"
    assert info["preconditioner"] == ("bddc" if model == "linear" else
                                      "bddc at rest, once per design")
    assert info["iterations"] > 3
    errors = {}
    for name in names:
        errors[name] = chain_fd(chain, name, x0, h=1e-4, directions=2, stencil=4).rel_error
    print(model, load, errors, mech.solver_info)
    assert max(errors.values()) < FD_TOL, errors


def test_direct_equals_iterative_3d():
    """The 3D linear box on both routes: the compliance and the displacement agree to
    SAME_TOL (relative)."""
    out = {}
    for solver in ("direct", "iterative"):
        chain, mech, names, x0 = _chain_3d("linear", "force", solver)
        vals = chain.forward(x=x0)
        out[solver] = (vals[names[0]], mech.gfu.vec.FV().NumPy().copy())
    (jd, ud), (ji, ui) = out["direct"], out["iterative"]
    assert abs(ji - jd) <= SAME_TOL * abs(jd)
    assert np.max(np.abs(ui - ud)) <= SAME_TOL * np.max(np.abs(ud))


@pytest.mark.parametrize("cap", [None, 1])
def test_a_linear_systems_preconditioner_kept_across_designs(cap, monkeypatch):
    """The 3D linear box on the iterative route over designs that change a little, then a
    lot: BDDC is set up at the first two designs (the second builds the element matrices,
    whose check assembles the form) and kept for the next ones, whose matrices come from the
    element matrices; every compliance and displacement equals the direct route's to
    SAME_TOL.  With ``cap`` 1 every solve with a kept BDDC stops after one CG iteration, BDDC
    is set up from the current matrix and CG goes on from there, and the next design is built
    afresh (pacto_ng/physics/reuse.py)."""
    from pacto_ng.physics.reuse import Reuse

    if cap is not None:
        monkeypatch.setattr(Reuse, "cap", property(lambda self: cap))
    chains = {s: _chain_3d("linear", "force", s) for s in ("direct", "iterative")}
    x0 = chains["direct"][3]
    designs = [x0, 1.01 * x0, 1.02 * x0, 1.03 * x0, np.full_like(x0, 0.9), 0.5 + 0.0 * x0]
    for x in designs:
        out = {}
        for solver, (chain, mech, names, _) in chains.items():
            vals = chain.forward(x=x)
            out[solver] = (vals[names[0]], mech.gfu.vec.FV().NumPy().copy())
        (jd, ud), (ji, ui) = out["direct"], out["iterative"]
        assert abs(ji - jd) <= SAME_TOL * abs(jd)
        assert np.max(np.abs(ui - ud)) <= SAME_TOL * np.max(np.abs(ud))
    info = chains["iterative"][1].solver_info
    print(info)
    assert info["preconditioner"] == "bddc"
    if cap is None:
        assert info["preconditioner_builds"] < len(designs)
        assert info["preconditioner_kept_designs"] >= 2
        assert info["preconditioner_rebuilt_in_solve"] == 0
    else:  # after the second design: kept, its cap reached and rebuilt within the solve,
        # then a design built afresh (the back-off), twice
        assert info["preconditioner_rebuilt_in_solve"] == 2
        assert info["preconditioner_builds"] == len(designs)
        assert info["preconditioner_kept_designs"] == 0


def test_darcy_order1_h1amg():
    """The Darcy pressure at order 1 on the iterative route (CG with h1amg, Dirichlet inlet and
    zero boundaries): its pressure and its backward pass equal the direct route's."""
    mesh = small_pa_mesh("trig")
    rho = np.random.default_rng(3).uniform(0.0, 1.0, mesh.ne)
    out = {}
    for solver in ("direct", "iterative"):
        dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=1, solver=solver)
        p = dar.forward(rho).FV().NumPy().copy()
        g = dar.backward(np.linspace(0.0, 1.0, len(p)))[0]
        out[solver] = (p, g, dar.solver_info)
    (pd, gd, _), (pi, gi, info) = out["direct"], out["iterative"]
    assert info["preconditioner"] == "h1amg" and info["iterations"] > 1
    assert np.max(np.abs(pi - pd)) <= SAME_TOL * np.max(np.abs(pd))
    assert np.max(np.abs(gi - gd)) <= 1e-6 * np.max(np.abs(gd))


def test_follower_adjoint_by_gmres_with_an_exact_preconditioner():
    """P1 tetrahedra: BDDC's coarse space holds every dof, an exact inverse, and GMRES stops
    at its first iteration (an Arnoldi breakdown) without recording the residual it reached.
    The follower load's adjoint on the iterative route is accepted, and its gradients equal
    the direct route's (pneunet-3d, Neo-Hookean, follower; these were refused as 'did not
    reach the relative tolerance 1e-12 (reached 1.0)')."""
    from pacto_ng.case import build_problem, get_case

    case = get_case("pneunet-3d")
    got = {}
    for solver in ("direct", "iterative"):
        problem = build_problem(case, case.parameters(
            {"maxh": 0.006, "model": "neohookean", "load_type": "follower", "solver": solver,
             "newton_rtol": 1e-10,  # both routes to the same Newton tolerance
             "realcompile": 0}))  # one evaluation: the compiler would not pay
        x = np.random.default_rng(3).uniform(0.2, 1.0, problem.n_design)
        got[solver] = problem.evaluate(x)
        assert problem.mech.solver_info["kind"] == solver
    (f0, f, df0, df), (g0, g, dg0, dg) = got["direct"], got["iterative"]
    assert g0 == pytest.approx(f0, rel=1e-9) and np.allclose(g, f, rtol=1e-9)
    assert np.abs(dg0 - df0).max() <= 1e-9 * np.abs(df0).max()
    assert np.abs(dg - df).max() <= 1e-9 * np.abs(df).max()


@pytest.mark.parametrize("case_name,maxh", [("pneunet-3d", 0.006), ("cantilever-3d", 0.06)])
def test_the_iterative_routes_tolerance_is_below_what_the_optimiser_resolves(case_name, maxh):
    """Newton's tolerance is the route's unless set: 1e-10 of the load on the direct route,
    1e-6 on the iterative one, whose adjoint solves to a tenth of it.  At those defaults the
    iterative route's objective, constraints and gradients equal the direct route's to a tenth
    of the case's objective tolerance (its obj_tol, relative: pneunet-3d 1e-3, cantilever-3d
    the optimiser's default 1e-4; gradients relative to their largest entry), on a random
    design of each 3D linear case at order 2.  Measured: pneunet-3d's objective 3.1e-5 apart
    (its random design's objective 5.4e-5: -Δ/SE of a design that barely bends), gradients
    2.1e-7."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.physics.newton import DIRECT_RTOL, ITERATIVE_RTOL

    case = get_case(case_name)
    got = {}
    for solver in ("direct", "iterative"):
        problem = build_problem(case, case.parameters(
            {"maxh": maxh, "order": 2, "solver": solver}))
        x = np.random.default_rng(3).uniform(0.2, 1.0, problem.n_design)
        got[solver] = problem.evaluate(x)
        info = problem.mech.solver_info
        assert info["kind"] == solver
        if solver == "direct":
            assert info["newton_rtol"] == DIRECT_RTOL
        else:
            assert info["newton_rtol"] == ITERATIVE_RTOL
            assert info["tolerance"] == pytest.approx(0.1 * ITERATIVE_RTOL)
            assert info["iterations"] > 3  # BDDC really iterates
    (f0, f, df0, df), (g0, g, dg0, dg) = got["direct"], got["iterative"]
    tol = 0.1 * case.defaults.obj_tol
    assert abs(g0 - f0) <= tol * abs(f0)
    assert np.all(np.abs(g - f) <= tol * np.abs(f))
    assert np.abs(dg0 - df0).max() <= tol * np.abs(df0).max()
    for a, b in zip(dg, df):
        assert np.abs(a - b).max() <= tol * np.abs(b).max()


def test_bddc_coarse_space_is_the_vertices_and_the_boundary_terms_regions():
    """In 3D at order 2 BDDC's coarse (wirebasket) dofs are the vertices' alone for a form
    without boundary terms; a spring on a face adds that face's dofs, and residual terms (a
    follower pressure, possibly on any face) every boundary's.  Counted against the dofs the
    mesh's regions hold, not against the code's own list."""
    from netgen.occ import X, Box, OCCGeometry
    from ngsolve import Mesh, ds, specialcf
    from ngsolve.comp import COUPLING_TYPE

    box = Box((0, 0, 0), (L3, W3, D3))
    box.faces.Min(X).name = "clamp"
    box.faces.Max(X).name = "end"
    mesh = Mesh(OCCGeometry(box, dim=3).GenerateMesh(maxh=0.15))
    energy = lambda G, c: linear_energy(G, 1e6, 0.3)

    def coarse(**kw):
        mech = Mechanics(mesh, order=2, energy=energy, supports=Supports(clamp=("clamp",)),
                         newton=NewtonSettings(solver="iterative"), **kw)
        assert mech.solver_info["preconditioner"].startswith("bddc")
        types = mech.fes.couplingtype
        return mech.fes, {d for d in range(mech.fes.ndof)
                          if types[d] == COUPLING_TYPE.WIREBASKET_DOF}

    fes, plain = coarse(loads=(PointLoad("end", (0.0, 1.0, 0.0)),))
    assert len(plain) == 3 * mesh.nv
    on = lambda region: {d for d, b in enumerate(fes.GetDofs(region)) if b}
    _, spring = coarse(springs=(Spring("end", 1e3, (0.0, 1.0, 0.0)),))
    assert spring == plain | on(mesh.Boundaries("end"))
    assert len(spring) > len(plain)
    pressure = lambda u, v, load: (load * 1e3 * (specialcf.normal(3) * v)) * ds("end")
    _, terms = coarse(residual_terms=pressure, symmetric=False)
    assert terms == plain | on(mesh.Boundaries(".*"))


def test_a_linear_design_is_one_cg_solve_to_newtons_residual():
    """A linear problem on the iterative route: CG stops on the Euclidean norm of the residual
    on the free dofs, half of Newton's tolerance, so that Newton's test (the residual from
    the element matrices, not CG's recurrence) accepts its one step, whose residual is
    recomputed here."""
    from pacto_ng.parallel import free_norm

    chain, mech, names, x0 = _chain_3d("linear", "force", "iterative")
    chain.forward(x=x0)
    assert mech.result.converged and mech.result.iterations == 1
    assert mech.solver_info["iterations"] > 3  # BDDC really iterates
    r = mech.gfu.vec.CreateVector()
    mech.residual(mech.gfu.vec, r, mech.target)
    ref = mech.load_norm(mech.target)
    assert free_norm(r, mech.free) <= mech.settings.rtol * ref


@pytest.mark.parametrize("load", ["fixed", "follower"])
def test_the_adjoint_preconditioned_by_newtons_factorisation(load, monkeypatch):
    """On the direct route the adjoint's tangent (at the converged state) is solved by CG, or
    GMRES on Kᵀ for the follower load, preconditioned by the factorisation of Newton's last
    full step at the same design (solvers.STALE_RTOL), instead of being factorised: the
    gradient equals the one of the tangent factorised (a STALE_RTOL of 1e-300, which no
    Krylov solve reaches: every such solve factorises) to 1e-9 of its largest entry (1.0e-15
    fixed, 2.4e-15 follower when written), and passes the FD check."""
    from pacto_ng.physics import solvers

    grads = {}
    for reuse in (True, False):
        if not reuse:
            monkeypatch.setattr(solvers, "STALE_RTOL", 1e-300)
        chain, (_, _, mech), x0 = _chain("neohookean", load, "direct")
        chain.forward(x=x0)
        grads[reuse] = chain.gradient("objective")
        info = mech.solver_info
        assert info["factors_reused"] > 0
        assert info["factors_reused_failed"] == (0 if reuse else info["factors_reused"])
        if reuse:
            errs = {name: _fd(chain, name, x0).rel_error for name in ("objective", "delta", "se")}
            assert max(errs.values()) < FD_TOL, errs
    assert np.max(np.abs(grads[True] - grads[False])) <= 1e-9 * np.max(np.abs(grads[False]))


def test_neohookean_tangent_at_a_large_deflection_with_bddc_at_rest():
    """cantilever-3d (order 2, maxh 0.06, 4962 dofs), Neo-Hookean, its initial design under
    2e4 N from rest: BDDC built on each Newton tangent made CG fail (1000 iterations, 7e-8
    where 1e-11 was asked): BDDC built on an indefinite deformed tangent is no preconditioner.
    With BDDC built once on the tangent at rest (symmetric positive definite), the iterative
    route reaches the direct route's equilibrium: the compliance to 1e-9.  The preconditioner
    is built once per design, not at each Newton step."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.initial import initial_design

    case = get_case("cantilever-3d")
    got = {}
    for solver in ("direct", "iterative"):
        problem = build_problem(case, case.parameters(
            {"maxh": 0.06, "order": 2, "model": "neohookean", "solver": solver,
             "newton_rtol": 1e-10, "realcompile": 0, "load": 2e4}))
        penal, beta, _ = problem.schedule_now()
        problem.apply_schedule(penal, beta, 1.0)
        x = initial_design(problem)
        got[solver] = problem.evaluate(x)[0]
        assert problem.mech.result.converged
    info = problem.mech.solver_info
    assert info["preconditioner"] == "bddc at rest, once per design"
    assert got["iterative"] == pytest.approx(got["direct"], rel=1e-9)
    assert info["preconditioner_builds"] == 1 and problem.mech.result.iterations > 5
    problem.evaluate(x * 1.01)
    assert problem.mech.solver_info["preconditioner_builds"] == 2


def test_gmres_restarts_stop_after_the_iterations_given():
    """A GMRES solve that stagnates (no preconditioner, a tolerance it cannot reach) stops
    after the iterations it is given, restarted every GMRES_RESTART (NGSolve's own restart
    counts afresh each cycle and recursed until Python's limit), its residuals recorded."""
    from ngsolve import H1, BilinearForm, IdentityMatrix, dx, grad

    from pacto_ng.physics.krylov import gmres
    from pacto_ng.physics.solvers import GMRES_RESTART

    mesh = small_pa_mesh("trig")
    fes = H1(mesh, order=3, dirichlet="inlet")
    u, v = fes.TnT()
    a = BilinearForm(grad(u) * grad(v) * dx).Assemble()
    rhs, out = a.mat.CreateColVector(), a.mat.CreateColVector()
    rhs.FV().NumPy()[:] = np.where(np.array(list(fes.FreeDofs()), dtype=bool), 1.0, 0.0)
    run = gmres(a.mat, IdentityMatrix(fes.ndof), rhs, out, 1e-300, 2 * GMRES_RESTART + 10,
                GMRES_RESTART)
    assert 2 * GMRES_RESTART < run.iterations <= 2 * GMRES_RESTART + 10
    assert run.residuals[-1] < run.residuals[0]
