"""Newton with the J > 0 guard, step cutting and load continuation: what is accepted, what a
failure reports, and the line-search choice.

Confined uniaxial compression of a unit square (F = diag(λ1, 1)) has closed forms:
Neo-Hookean ``P11 = μ (λ1 - 1/λ1) + λ ln λ1 / λ1`` (unbounded as λ1 -> 0); St Venant–Kirchhoff
``P11 = (λ + 2μ) λ1 (λ1² - 1) / 2``, whose compressive force is largest, ``(λ + 2μ) / (3√3)``,
at λ1 = 1/√3: beyond that no equilibrium with J > 0 exists.
"""
from dataclasses import replace

import numpy as np
import pytest
from ngsolve.la import CreateVVector

from nonlinear_setup import cantilever, cantilever_mesh
from pacto_ng.mesh import Layout, Segment, structured_mesh
from pacto_ng.physics.equilibrium import NewtonFailure
from pacto_ng.physics.loads import PointLoad
from pacto_ng.physics.materials import jacobian, lame, neohookean_energy, svk_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.newton import GUARD_STALL, NewtonSettings, solve_with_continuation


pytestmark = pytest.mark.usefixtures("one_thread")


E, NU, T = 2.0e6, 0.4, 0.1
MU, LAM = lame(E, NU)


def square():
    lay = Layout(1.0, 1.0, segments=(
        Segment("left", (0, 0), (0, 1)), Segment("right", (1, 0), (1, 1)),
        Segment("bottom", (0, 0), (1, 0)), Segment("top", (0, 1), (1, 1))))
    return structured_mesh(lay, 3, 3)


def compressed_square(energy, P11, settings):
    mesh = square()
    mech = Mechanics(mesh, order=1, energy=lambda G, c: energy(G, E, NU),
                     supports=Supports(fix_x=("left",), fix_y=("bottom", "top")),
                     loads=(PointLoad("right", (P11 * 1.0 * T, 0.0)),), thickness=T,
                     guard=lambda G, c: jacobian(G), newton=settings)
    mech.set_fields(np.ones(mesh.ne))
    return mesh, mech


def vertex_jacobians(mech):
    """det F at every vertex of every element (independent of the guard's quadrature points)."""
    from ngsolve import Grad

    J = jacobian(Grad(mech.gfu))
    out = []
    for el in mech.mesh.Elements():
        for v in el.vertices:
            p = mech.mesh[v].point
            c = np.mean([mech.mesh[w].point for w in el.vertices], axis=0)
            q = 0.999 * np.array(p) + 0.001 * c  # just inside this element
            out.append(J(mech.mesh(*q)))
    return np.array(out)


class Scalar:
    """R(u) = atan(u) - s f: equilibria exist only for |s f| < π/2."""

    free = np.array([True])

    def __init__(self, f):
        self.f = f

    def residual(self, vec, out, load):
        out.FV().NumPy()[:] = np.arctan(vec.FV().NumPy()) - load * self.f

    def assemble_tangent(self, vec, load):
        x = float(np.clip(vec.FV().NumPy()[0], -1e150, 1e150))
        self.k = 1.0 / (1.0 + x * x)

    def solve_tangent(self, rhs, out):
        out.FV().NumPy()[:] = rhs.FV().NumPy() / self.k

    def admissible(self, vec):
        return bool(np.all(np.isfinite(vec.FV().NumPy())))

    def load_norm(self, load):
        return abs(load * self.f)


def test_inverting_step_is_cut_never_accepted():
    """A single full-load Newton step towards λ1 = 0.2 would invert the square: the guard cuts
    the step; every accepted iterate has det F > 0; the solution is the closed form."""
    stretch = 0.2
    P11 = MU * (stretch - 1 / stretch) + LAM * np.log(stretch) / stretch
    settings = NewtonSettings(rtol=1e-12, initial_increment=1.0)
    mesh, mech = compressed_square(neohookean_energy, P11, settings)
    verdicts, accepted_J = [], []
    guard = mech.admissible
    mech.admissible = lambda v: verdicts.append(guard(v)) or verdicts[-1]
    assemble = mech.assemble_tangent

    def record(vec, load):  # the tangent is assembled at every accepted iterate
        accepted_J.append(vertex_jacobians(mech).min())
        assemble(vec, load)

    mech.assemble_tangent = record
    # the undamped first step (the linear solution) inverts the material
    lin_stretch = 1.0 + P11 / (LAM + 2 * MU)
    assert lin_stretch < 0.0
    mech.forward(np.ones(mesh.ne))
    assert mech.result.converged and mech.result.steps == 1
    assert verdicts[:1] == [False]  # the full step was rejected ...
    assert sum(not v for v in verdicts) >= 1 and verdicts[-1]
    assert min(accepted_J) > 0.0  # ... and nothing inverted was ever accepted
    assert mech.gfu(mesh(1.0, 0.5))[0] == pytest.approx(stretch - 1.0, rel=1e-9)


def test_unreachable_load_fails_with_load_reached_and_reason():
    """St Venant–Kirchhoff with the J > 0 guard cannot carry more than (λ+2μ)/(3√3) in
    confined compression: asking 1.2 times that fails, reports how far it got (just below
    1/1.2 of the target) and why, and Mechanics.forward raises NewtonFailure."""
    P_limit = -(LAM + 2 * MU) / (3 * np.sqrt(3))
    settings = NewtonSettings(rtol=1e-12, initial_increment=0.25, min_increment=1.0 / 256,
                              max_iter=15)
    mesh, mech = compressed_square(svk_energy, 1.2 * P_limit, settings)
    with pytest.raises(NewtonFailure) as info:
        mech.forward(np.ones(mesh.ne))
    res = info.value.result
    assert res is mech.result
    assert not res.converged
    assert 0.0 < res.load_reached < 1.0
    assert res.load_reached == pytest.approx(1.0 / 1.2, abs=0.02)
    assert res.load_reached <= 1.0 / 1.2 + 1e-9
    assert res.reason
    assert res.reason in str(info.value)
    # the state kept is the last equilibrium, with J > 0
    assert vertex_jacobians(mech).min() > 0.0
    ux = mech.gfu(mesh(1.0, 0.5))[0]
    s = 1.0 + ux
    P_reached = res.load_reached * 1.2 * P_limit
    assert (LAM + 2 * MU) * s * (s * s - 1) / 2 == pytest.approx(P_reached, rel=1e-8)


def test_without_guard_svk_jumps_to_the_inverted_branch():
    """The same load without the guard 'converges' to an inverted state (λ1 < 0): the guard is
    what keeps such states out.  Newton wanders past the limit point on its way there, longer
    than the default ``stall`` lets an attempt go without progress."""
    P_limit = -(LAM + 2 * MU) / (3 * np.sqrt(3))
    mesh = square()
    mech = Mechanics(mesh, order=1, energy=lambda G, c: svk_energy(G, E, NU),
                     supports=Supports(fix_x=("left",), fix_y=("bottom", "top")),
                     loads=(PointLoad("right", (1.2 * P_limit * T, 0.0)),), thickness=T,
                     newton=NewtonSettings(rtol=1e-12, initial_increment=0.25, stall=30))
    mech.forward(np.ones(mesh.ne))
    assert 1.0 + mech.gfu(mesh(1.0, 0.5))[0] < 0.0


def test_failure_reasons_of_the_continuation():
    """Non-finite loads and the step cap are reported, with the load reached."""
    u = CreateVVector(1)
    u[:] = 0.0
    res = solve_with_continuation(Scalar(1.0), u, 1.0, NewtonSettings(), warm=False)
    assert res.converged and u.FV().NumPy()[0] == pytest.approx(np.tan(1.0), rel=1e-9)
    res = solve_with_continuation(Scalar(2.0), u, 1.0, NewtonSettings(initial_increment=0.5),
                                  warm=False)
    assert not res.converged and res.reason
    assert res.load_reached < np.pi / 4 and res.load_reached > 0.5  # atan < π/2 bounds s f
    res = solve_with_continuation(Scalar(float("nan")), u, 1.0, NewtonSettings(), warm=False)
    assert not res.converged and res.load_reached == 0.0 and "non-finite" in res.reason
    res = solve_with_continuation(Scalar(1.0), u, 1.0, NewtonSettings(initial_increment=0.01,
                                  grow=1.0, max_steps=10), warm=False)
    assert not res.converged and res.load_reached == pytest.approx(0.1)
    assert "load steps" in res.reason
    # an equilibrium rejected by the caller counts as a failed increment
    seen = []
    res = solve_with_continuation(Scalar(1.0), u, 1.0, NewtonSettings(initial_increment=0.25),
                                  warm=False, accept=lambda s, v: "too far" if s > 0.6 else "",
                                  on_step=lambda s, v: seen.append(s))
    assert not res.converged and 0.5 <= res.load_reached <= 0.6 and "too far" in res.reason
    assert seen == [h[0] for h in res.history] and max(seen) == res.load_reached
    # a ramp reports its first accepted increment; a later ramp can start there
    res = solve_with_continuation(Scalar(1.0), u, 1.0, NewtonSettings(initial_increment=0.25),
                                  warm=False)
    assert res.converged and res.ramp_first == pytest.approx(0.25)
    res = solve_with_continuation(Scalar(1.0), u, 1.0, NewtonSettings(), warm=False,
                                  first_increment=0.125)
    assert res.converged and res.history[0][0] == pytest.approx(0.125)
    assert res.ramp_first == pytest.approx(0.125)


def test_a_warm_start_gives_up_after_warm_stall_iterations_without_progress():
    """``warm_stall``: a warm start that makes no progress hands over to the load ramp after
    that many iterations, whatever ``stall`` allows the ramp's steps (contact's settings:
    physics/equilibrium.py WARM_STALL).  R(u) = atan(u) - 0.5 from u = 3: full Newton steps
    overshoot further each time (|R| grows towards π/2 + 0.5), so the warm start never finds
    a smaller residual; the ramp from zero then converges."""
    runs = {}
    for warm_stall in (0, 3):
        u = CreateVVector(1)
        u[:] = 3.0
        settings = NewtonSettings(stall=20, max_iter=20, warm_stall=warm_stall)
        runs[warm_stall] = solve_with_continuation(Scalar(0.5), u, 1.0, settings, warm=True)
        assert runs[warm_stall].converged
        assert u.FV().NumPy()[0] == pytest.approx(np.tan(0.5), rel=1e-9)
    assert runs[0].iterations - runs[3].iterations == 20 - 3  # the warm start's iterations


def test_a_ramp_starts_where_the_last_one_succeeded():
    """The Neo-Hookean cantilever at 5e5 N from u = 0 needs small first increments; the next
    ramp from zero (e.g. after a failed warm start) starts at the first increment that worked
    instead of failing its way down to it again: fewer Newton iterations, same equilibrium."""
    mesh = cantilever_mesh("trig")
    rho = np.ones(mesh.ne)
    mech = cantilever(mesh, "neohookean", 1, load=2e6,
                      newton=NewtonSettings(rtol=1e-12, initial_increment=1.0, max_iter=12))
    u1 = mech.forward(rho).FV().NumPy().copy()
    first = mech.result
    assert first.ramp_first is not None and first.ramp_first < 1.0
    mech.result = None  # forget the equilibrium: the next solve ramps from zero
    u2 = mech.forward(rho).FV().NumPy().copy()
    assert mech.result.history[0][0] == pytest.approx(first.ramp_first)
    assert mech.result.iterations < first.iterations
    assert np.linalg.norm(u1 - u2) <= 1e-8 * np.linalg.norm(u1)


def test_settings_validation():
    with pytest.raises(ValueError):
        NewtonSettings(line_search="wolfe")
    with pytest.raises(ValueError):
        NewtonSettings(initial_increment=0.0)


def test_guard_line_search_needs_fewer_iterations_than_residual_backtracking():
    """Neo-Hookean cantilever, 2e5 N in one step: the searches find the same equilibrium; the
    guard-only search takes fewer Newton iterations (measured 5 against 19 on 1410 triangles,
    see newton.py), and "guard+residual" (contact's) as few, its guard's attempt converging."""
    mesh = cantilever_mesh("trig")
    rho = np.ones(mesh.ne)
    out = {}
    for ls in ("guard", "residual", "guard+residual"):
        mech = cantilever(mesh, "neohookean", 2, load=2e5,
                          newton=NewtonSettings(rtol=1e-12, initial_increment=1.0, line_search=ls))
        u = mech.forward(rho)
        out[ls] = (u.FV().NumPy().copy(), mech.result.iterations)
    a = out["guard"][0]
    for ls in ("residual", "guard+residual"):
        assert np.linalg.norm(a - out[ls][0]) <= 1e-9 * np.linalg.norm(a)
    assert out["guard"][1] < out["residual"][1]
    assert out["guard+residual"][1] == out["guard"][1]


def test_guard_then_residual_line_search_where_full_steps_diverge():
    """R(u) = atan(u) - 0.5 from u = 3 at the full load, no ramp: full Newton steps overshoot
    further each time, so the guard's search fails; "guard+residual" then takes the
    residual's (Armijo on |R|) from the same start and converges, GUARD_STALL iterations
    later than the residual's alone."""
    runs = {}
    for ls in ("guard", "residual", "guard+residual"):
        u = CreateVVector(1)
        u[:] = 3.0
        runs[ls] = solve_with_continuation(Scalar(0.5), u, 1.0, NewtonSettings(line_search=ls),
                                           warm=True, ramp=False)
        if runs[ls].converged:
            assert u.FV().NumPy()[0] == pytest.approx(np.tan(0.5), rel=1e-9)
    assert not runs["guard"].converged
    assert runs["residual"].converged and runs["guard+residual"].converged
    assert runs["guard+residual"].iterations == runs["residual"].iterations + GUARD_STALL


def test_a_new_design_is_reached_along_the_design_path():
    """A design change Newton cannot take in one go at the full load (a band of the Wang
    cantilever voided at 2e6 N): the warm start fails, the design path
    (physics/design_path.py) blends the designs and reaches the new design's equilibrium, the
    one a ramp from zero finds, in half its Newton iterations (58 against 117 when
    written; full Newton steps alone, no chord steps, so that iterations count tangents)."""
    mesh = cantilever_mesh("trig")
    centres = np.array([np.mean([mesh[v].point for v in el.vertices], axis=0)
                        for el in mesh.Elements()])
    band = (centres[:, 1] > 0.08) & (centres[:, 1] < 0.17) & (centres[:, 0] < 0.9)
    solid, voided = np.ones(mesh.ne), np.where(band, 1e-3, 1.0)
    settings = NewtonSettings(rtol=1e-12, chord=False)
    mech = cantilever(mesh, "wang", 1, load=2e6, newton=settings)
    mech.forward(solid)
    along = mech.forward(voided).FV().NumPy().copy()
    path = mech.result
    assert path.converged and path.ramp_first is None  # no load ramp from zero
    assert path.history[0][0] == 0.5  # the path's first point: halfway between the designs
    fresh = cantilever(mesh, "wang", 1, load=2e6, newton=settings)
    ramped = fresh.forward(voided).FV().NumPy().copy()
    assert np.linalg.norm(along - ramped) <= 1e-9 * np.linalg.norm(ramped)
    assert path.iterations < 0.5 * fresh.result.iterations
    fields = mech.fields[0].gf.vec.FV().NumPy()
    assert np.array_equal(fields, voided)  # the fields are the new design's


class CountedScalar(Scalar):
    """:class:`Scalar` that counts its tangents."""

    tangents = 0

    def assemble_tangent(self, vec, load):
        self.tangents += 1
        super().assemble_tangent(vec, load)


def test_chord_steps_reach_the_same_root_with_fewer_tangents():
    """atan(u) = 0.5 from u = 0.3, at the full load: once a Newton step has cut the residual
    CHORD_FROM-fold, the next steps reuse its tangent while each cuts the residual
    CHORD_CUT-fold; the root is the same to round-off, with fewer tangents (2 against 4 when
    written), each chord step counted as a Newton iteration."""
    runs = {}
    for chord in (False, True):
        problem, u = CountedScalar(0.5), CreateVVector(1)
        u[:] = 0.3
        result = solve_with_continuation(problem, u, 1.0, NewtonSettings(rtol=1e-14, chord=chord),
                                         warm=True, ramp=False)
        assert result.converged
        assert u.FV().NumPy()[0] == pytest.approx(np.tan(0.5), rel=1e-14)
        runs[chord] = (problem.tangents, result.iterations)
    assert runs[True][0] < runs[False][0]
    assert runs[True][1] > runs[False][1]  # more, cheaper steps


def test_chord_steps_in_a_warm_start_of_a_new_design():
    """The Neo-Hookean cantilever at 2e5 N, warm-started at a design with a softened band:
    chord steps reach the equilibrium full Newton steps reach (to 1e-10 of it, both at a
    residual of 1e-12 of the load) with fewer tangents assembled (4 against 6 when written)."""
    mesh = cantilever_mesh("trig")
    centres = np.array([np.mean([mesh[v].point for v in el.vertices], axis=0)
                        for el in mesh.Elements()])
    softened = np.where(centres[:, 1] > 0.15, 0.8, 1.0)
    runs = {}
    for chord in (False, True):
        mech = cantilever(mesh, "neohookean", 1, load=2e5,
                          newton=NewtonSettings(rtol=1e-12, chord=chord))
        mech.forward(np.ones(mesh.ne))
        count, assemble = [0], mech.assemble_tangent

        def counted(vec, load):
            count[0] += 1
            assemble(vec, load)

        mech.assemble_tangent = counted
        u = mech.forward(softened).FV().NumPy().copy()
        assert mech.result.converged and mech.result.ramp_first is None  # the warm start
        runs[chord] = (u, count[0])
    full, chorded = runs[False][0], runs[True][0]
    assert np.linalg.norm(chorded - full) <= 1e-10 * np.linalg.norm(full)
    assert runs[True][1] < runs[False][1]


def test_a_sweep_solves_its_tangents_preconditioned_by_the_last_factorisation():
    """The Neo-Hookean cantilever swept over 1e5, 2e5, 3e5 N, each load warm-started from the
    last: with ``sweep`` (after the first load, as a part's analysis sets it) each tangent is
    solved by CG preconditioned by the last factorisation, to 1e-12; the equilibria equal those
    of factorised tangents (to 1e-10 of them, both at a residual of 1e-12 of the load), with
    fewer factorisations (7 against 15 when written: 10 solves preconditioned, 2 of them
    factorised after all)."""
    mesh = cantilever_mesh("trig")
    runs = {}
    for sweep in (False, True):
        mech = cantilever(mesh, "neohookean", 1, load=3e5,
                          newton=NewtonSettings(rtol=1e-12, chord=False))
        states = []
        for target in (1 / 3, 2 / 3, 1.0):
            mech.target = target
            states.append(mech.forward(np.ones(mesh.ne)).FV().NumPy().copy())
            assert mech.result.converged
            mech.settings = replace(mech.settings, sweep=sweep)
        runs[sweep] = (states, mech.solver_info)
    for full, swept in zip(runs[False][0], runs[True][0]):
        assert np.linalg.norm(swept - full) <= 1e-10 * np.linalg.norm(full)
    full, swept = runs[False][1], runs[True][1]
    assert full["factors_reused"] == 0 and swept["solves"] == full["solves"]
    factorised = swept["solves"] - swept["factors_reused"] + swept["factors_reused_failed"]
    assert factorised < full["solves"] // 2 + 1
