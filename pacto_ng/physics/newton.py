"""Newton's method with a J > 0 guard, step cutting and adaptive load increments
(docs/theory.md §3).

The problem object supplies ``residual(vec, out, load)``, ``assemble_tangent(vec, load)``,
``solve_tangent(rhs, out)``, ``admissible(vec)``, ``load_norm(load)`` and ``free`` (a numpy
mask of free dofs).  One Newton iteration at load factor ``s`` solves ``K(u) du = R(u; s)`` and
tries ``u - α du`` for ``α = 1, 1/2, 1/4, ...``:

* ``line_search="guard"`` (default) accepts the first ``α`` whose state is admissible
  (``det F > 0`` at every integration point where the energy needs it) with a finite residual;
* ``line_search="residual"`` also asks for the Armijo-type decrease
  ``|R(u - α du)| <= (1 - 1e-4 α) |R(u)|`` of the free-dof residual norm, and otherwise takes
  the admissible trial with the smallest residual.

An inadmissible state is never accepted.  The iteration stops when ``|R| <= rtol |f|`` (``f``
the external load at the target) or at the round-off floor (``|R| < 1e-7 |f|`` and no longer
halving).  An attempt also gives up after ``stall`` iterations without a new smallest residual
(at most ``max_iter`` otherwise).  Load increments grow after easy steps and are halved after
a failed one (the increment tried, also where it was cut to the target); the last converged
state is kept, so a failure reports the load factor reached and why.

Measured (iterations per load step; guard / residual): cantilever 1 x 0.25 m, 1410
triangles, solid, Neo-Hookean, Wang and gnl alike, P1 and P2: 2e5 N in one step 5 / 19,
5e5 N in one step 7 / 23 + 18, 5e5 N in four steps 5 / 13; C-beam sweeps (Neo-Hookean and
Wang, Q1, Q2, P2) 4.5-5.0 / 7-19.  Backtracking on the residual norm over-damps Newton, as the
NGSolve notes warned; the guard-only search is the default and the other one an option.
"""
from __future__ import annotations

import shutil
from dataclasses import dataclass, field, replace

from ..errors import InputError
from ..parallel import free_norm
from ..settings import Settings, setting
from .compiled import COMPILE_PAYS, COMPILE_PAYS_SYMBOLIC
from .routes import DIRECT_MAX_DOFS_3D, SOLVERS

import numpy as np

# Newton's residual tolerance (relative to the full external load) when none is given: each
# route's own.  The direct route's exact solves make the last digits cheap (Newton converges
# quadratically).  On the iterative route each digit costs Krylov iterations, and the optimiser
# needs far fewer: measured on the 25th design of a cantilever-3d and a pneunet-3d run (order
# 2, 32 901 and 90 249 dofs; docs/studies.md, "The iterative route's tolerance"), 1e-6
# against 1e-12 moves the objective by 1.2e-14 (compliance) and 5.8e-7 (pneunet-3d's -Δ/SE),
# the gradient by 2.2e-9 and 1.9e-6 of its largest entry, far below the optimiser's
# objective tolerance (obj_tol 1e-4), for 33 % and 36 % fewer CG iterations than 1e-10.
DIRECT_RTOL = 1e-10
ITERATIVE_RTOL = 1e-6


LINE_SEARCHES = ("guard", "residual", "guard+residual")
#: the guard's attempt of "guard+residual" gives up after this many iterations without a new
#: smallest residual (the residual's then starts)
GUARD_STALL = 8
#: a Newton step that cut the residual at least this many times (Newton near its quadratic
#: convergence) lets the next steps reuse its factorised tangent (chord steps, no assembly or
#: factorisation) ...
CHORD_FROM = 100.0
#: ... while each of them cuts the residual at least this many times; the first that does
#: not is undone and a tangent assembled at the state
CHORD_CUT = 10.0


@dataclass(frozen=True)
class NewtonSettings:
    # residual norm relative to the full external load; 0: the route's (DIRECT_RTOL with a
    # direct solver of the tangent, ITERATIVE_RTOL with a Krylov solver)
    rtol: float = 0.0
    max_iter: int = 30
    # an attempt at one load factor gives up after this many iterations without a residual
    # below its smallest so far: Newton converging makes a new smallest at least every few
    # (at most 4 apart in the converged steps of gripper-silicone's part with its former
    # point spring, 2026-12-07, whose failed attempts each ran all of max_iter before this)
    stall: int = 8
    # ... and a warm start (Newton at the full load from the last equilibrium) after this many
    # (0: ``stall``), the load ramp then taking over
    warm_stall: int = 0
    max_backtracks: int = 8
    initial_increment: float = 1.0  # first load increment (fraction of the target)
    min_increment: float = 1.0 / 1024
    grow: float = 1.5
    easy: int = 4  # a step converging in <= easy iterations lets the increment grow
    max_steps: int = 200
    max_total_iter: int = 1000  # Newton iterations per solve, over all load steps and retries
    # a step that cut the residual CHORD_FROM-fold lets the next ones reuse its factorised
    # tangent (chord steps) while each cuts the residual CHORD_CUT-fold; in a warm start
    # only: a load ramp's steps keep full Newton (its increments grow after easy steps, and
    # chord steps made more steps easy: 1e9 Pa on the Neo-Hookean pa-inverter of
    # tests/physics/test_extremes.py then lost the load at its last increment)
    chord: bool = True
    # a sweep of one design over loads (a part's pressures, the expected sweep): the last
    # load's factorised tangent is near the next load's.  The warm start's first step is a
    # chord step with it, and each symmetric tangent is solved by CG preconditioned by it
    # (solvers.STALE_FORCING; LinearSolver.prepare(near=True)); not a follower load's:
    # UMFPACK's triangular solves cost 3.4 times sparse Cholesky's, and GMRES took pneunet-3d's
    # follower sweep from 101 to 117 s.  Across designs the last tangent was rarely near
    sweep: bool = False
    # "guard" (admissibility only), "residual" (Armijo on |R|) or "guard+residual" (the
    # guard's, stopping after GUARD_STALL iterations without progress; where it fails, the
    # residual's from the same start)
    line_search: str = "guard"
    # a failed warm start ramps the load from the last equilibrium's, never from zero (a
    # sweep of one design past a pressure maximum, where a ramp from zero would meet it again)
    ramp_from_last: bool = False
    solver: str = "auto"  # the tangent's linear solver: auto | direct | iterative (solvers.py)

    def __post_init__(self):
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}")
        if self.line_search not in LINE_SEARCHES:
            raise ValueError(f"line_search must be one of {', '.join(LINE_SEARCHES)}")
        if not 0 < self.initial_increment <= 1:
            raise ValueError("initial_increment must lie in (0, 1]")
        if self.rtol < 0 or self.max_iter < 1 or self.stall < 1:
            raise ValueError("rtol must be positive (or 0: the route's), max_iter and stall "
                             ">= 1")

    def for_contact(self) -> NewtonSettings:
        """These settings for a problem with contact: the guard's line search first, and where
        it fails the residual's (Armijo on ``|R|``, no ``stall`` limit short of ``max_iter``)
        from the same start.

        A full Newton step presses walls whose contact its tangent did not see deep into each
        other (the residual's norm grew up to 2e5 times on the squeezed slotted slab of
        tests/physics/test_contact.py), and Newton without the residual's search wanders: 174
        iterations on that slab with every wall a candidate (1213 tetrahedra, order 2,
        linear, 3 kPa), 16 with it; the 3D Hertz test's 191 s became 28 s (2026-12-07).
        Before it, converged steps went up to 26 iterations without a new smallest residual.
        But a Neo-Hookean Newton's full steps raise ``|R|`` 10-100 times before it converges
        quadratically (pneunet's part at 10-32 kPa, its walls apart, 2026-12-07): the
        residual's search alone cut them, 16-30 iterations per load step against 5-11, and
        lost the equilibrium near 27 kPa where the guard's found it."""
        return replace(self, stall=self.max_iter, line_search="guard+residual")

    def for_route(self, direct: bool) -> NewtonSettings:
        """These settings with ``rtol`` 0 replaced by the route's tolerance."""
        if self.rtol > 0:
            return self
        return replace(self, rtol=DIRECT_RTOL if direct else ITERATIVE_RTOL)


@dataclass(frozen=True)
class NewtonParameters(Settings):
    """The run's settings of Newton's method (:class:`NewtonSettings` holds the rest)."""

    newton_rtol: float = setting(0.0, "", "Newton residual tolerance (relative to the load; 0: "
                                 f"{DIRECT_RTOL:g} with the direct solver, {ITERATIVE_RTOL:g} "
                                 "with the iterative one); Newton also stops at the round-off "
                                 "floor: residual below 1e-7 of the load and no longer halving",
                                 range="[0, 0.1]")
    newton_max_iter: int = setting(30, "", "Newton iterations per load step",
                                   range="[1, 100000]")
    newton_increment: float = setting(1.0, "", "first load increment of Newton continuation "
                                      "(fraction)", range="(0, 1]")
    newton_min_increment: float = setting(1.0 / 1024, "", "smallest load increment before "
                                          "Newton gives up (fraction)", range="(0, 1]")
    realcompile: int = setting(-1, "", "compile the Newton forms to machine code: 1 on, 0 "
                               "off, -1 where it pays: a nonlinear model whose elements times "
                               f"Newton iterations expected reach {COMPILE_PAYS:.0e} "
                               f"({COMPILE_PAYS_SYMBOLIC:.0e} in 3D), with NGSolve's compiler "
                               "wrapper ngscxx on PATH (6-50 s once; an iteration 1.3x (3D) "
                               "to 2x faster)",
                               range="[-1, 1]")
    solver: str = setting("auto", "", "linear solver of the tangent: auto (sparse direct in "
                          f"2D, and in 3D at order 1 or up to {DIRECT_MAX_DOFS_3D:,} dofs; else "
                          "iterative) | direct | iterative (CG / GMRES with BDDC, "
                          "pacto_ng/physics/solvers.py)", choices=SOLVERS)

    def check(self):
        if 0 < self.newton_rtol < 1e-13:
            raise InputError("newton_rtol: must be 0 (the solver's) or lie in [1e-13, 0.1]")
        if self.newton_min_increment > self.newton_increment:
            raise InputError("newton_min_increment: must lie in (0, newton_increment]")

    def compiles(self, linear: bool, work: float, symbolic: bool = False) -> bool:
        """Whether the Newton forms of a model (``linear``: no Newton forms to speed up) are
        compiled, for ``work`` elements times Newton iterations expected: ``realcompile`` 1
        or 0, or with -1 where :data:`COMPILE_PAYS` (``symbolic``: the tangent from symbolic
        derivatives, :data:`COMPILE_PAYS_SYMBOLIC`) says it pays and ``ngscxx`` is found."""
        if self.realcompile >= 0:
            return bool(self.realcompile)
        pays = COMPILE_PAYS_SYMBOLIC if symbolic else COMPILE_PAYS
        return not linear and work >= pays and shutil.which("ngscxx") is not None

    def settings(self) -> NewtonSettings:
        """The Newton settings of these parameters."""
        return NewtonSettings(rtol=self.newton_rtol, max_iter=self.newton_max_iter,
                              initial_increment=self.newton_increment,
                              min_increment=self.newton_min_increment, solver=self.solver)


@dataclass
class NewtonResult:
    converged: bool
    iterations: int = 0  # Newton iterations summed over all load steps
    load_reached: float = 0.0  # the largest load factor at which equilibrium was found
    steps: int = 0  # accepted load increments
    reason: str = ""
    residual: float = float("nan")
    history: list = field(default_factory=list)
    ramp_first: float | None = None  # first accepted increment of a ramp from zero (fraction)


def newton_step_solve(problem, u, load, ref, s: NewtonSettings, linear=False):
    """Newton iterations at a fixed load factor.  Returns (converged, iterations, reason, res),
    the iterations counting every solve with a tangent (a chord step's, undone or not, too).

    ``u`` is updated in place only by accepted (admissible) steps.
    """
    r = u.CreateVector()
    du = u.CreateVector()
    trial = u.CreateVector()
    best = u.CreateVector()
    # a linear problem may offer a cheaper residual for the predictor (e.g. K u - s f with the
    # assembled K); the residuals that decide convergence are always problem.residual
    first = getattr(problem, "predictor_residual", None) if linear else None
    (first or problem.residual)(u, r, load)
    res = free_norm(r, problem.free)
    if not np.isfinite(res):
        return False, 0, "non-finite residual at the start of the step", res
    tol = s.rtol * ref
    it = 0
    prev = np.inf
    lowest, since = res, 0  # the smallest residual so far, and iterations since it
    chord = s.chord and s.sweep and not linear  # the next step reuses the last tangent
    while res > tol:
        if res < 1e-7 * ref and res > 0.5 * prev:
            break  # stagnation at the round-off floor, far below any meaningful tolerance
        prev = res
        if it >= s.max_iter:
            return False, it, f"no convergence in {s.max_iter} iterations (residual {res / ref:.2e} of the load)", res
        if since >= s.stall:
            return False, it, (f"no progress in {s.stall} iterations (residual {res / ref:.2e} "
                               f"of the load, at best {lowest / ref:.2e})"), res
        if chord:
            new = _chord_step(problem, u, r, (du, trial, best), load, res)
            it += 1
            if new is not None:
                u.data, res = trial, new
                lowest, since = (res, 0) if res < lowest else (lowest, since)
                continue
            chord, since = False, since + 1  # undone: r is again u's residual
        if s.sweep and problem.symmetric:
            problem.assemble_tangent(u, load, near=True)
        else:
            problem.assemble_tangent(u, load)
        problem.solve_tangent(r, du)
        alpha = 1.0
        new, best_res = np.inf, np.inf
        for _ in range(s.max_backtracks + 1):
            trial.data = u - alpha * du
            if problem.admissible(trial):
                problem.residual(trial, r, load)
                new = free_norm(r, problem.free)
                if np.isfinite(new):
                    if s.line_search == "guard" or new <= (1.0 - 1e-4 * alpha) * res:
                        break
                    if new < best_res:
                        best_res = new
                        best.data = trial
            alpha *= 0.5
        else:
            if not np.isfinite(best_res):
                return False, it + 1, ("every step length inverted an element (det F <= 0) "
                                       "or gave a non-finite residual"), res
            trial.data = best  # no sufficient decrease: the best admissible trial
            problem.residual(trial, r, load)
            new = best_res
        u.data = trial
        chord = s.chord and new * CHORD_FROM <= res
        res = new
        it += 1
        lowest, since = (res, 0) if res < lowest else (lowest, since + 1)
    return True, it, "", res


def _chord_step(problem, u, r, work, load, res):
    """A chord step of :func:`newton_step_solve` from ``u`` (``r`` its residual) with the last
    factorised tangent: its residual norm where it is admissible and cuts ``res``
    :data:`CHORD_CUT`-fold (``work[1]`` the new state, ``r`` its residual), else None (``r``
    ``u``'s residual again; ``work[2]`` a spare vector)."""
    du, trial, saved = work
    problem.solve_tangent(r, du)
    trial.data = u - du
    if problem.admissible(trial):
        saved.data = r
        problem.residual(trial, r, load)
        new = free_norm(r, problem.free)
        if new * CHORD_CUT <= res:
            return new
        r.data = saved
    return None


def _attempt(problem, u, load, ref, s, linear, accept):
    """Newton at one load factor (``line_search`` "guard+residual": the guard's, and where it
    fails the residual's from the same start), then the caller's acceptance test of the
    equilibrium."""
    if s.line_search == "guard+residual":
        saved = u.CreateVector()
        saved.data = u
        guard = replace(s, line_search="guard", stall=min(s.stall, GUARD_STALL))
        ok, it, why, res = newton_step_solve(problem, u, load, ref, guard, linear)
        if not ok:
            u.data = saved
            ok, more, why, res = newton_step_solve(problem, u, load, ref,
                                                   replace(s, line_search="residual"), linear)
            it += more
    else:
        ok, it, why, res = newton_step_solve(problem, u, load, ref, s, linear)
    if ok and accept is not None:
        why = accept(load, u)
        ok = not why
    return ok, it, why, res


def _warm_start(problem, u, loads, s: NewtonSettings, hooks, result: NewtonResult) -> bool:
    """The warm start of :func:`solve_with_continuation`: Newton from the current ``u`` at the
    full load (``loads``: the target and its reference norm; ``hooks``: linear, accept,
    on_step), recorded in ``result``; True if it converged.  On failure ``u`` is put back
    and ``result.reason`` says why."""
    (target, ref), (linear, accept, on_step) = loads, hooks
    saved = u.CreateVector()
    saved.data = u
    warm = replace(s, stall=s.warm_stall) if s.warm_stall else s
    ok, it, why, res = _attempt(problem, u, target, ref, warm, linear, accept)
    result.iterations += it
    if ok:
        result.converged, result.load_reached, result.steps = True, target, 1
        result.residual = res / ref
        result.history.append((target, it))
        if on_step is not None:
            on_step(target, u)
        return True
    u.data = saved
    result.reason = why
    return False


def solve_with_continuation(problem, u, target: float, s: NewtonSettings, *, warm: bool,
                            linear: bool = False, on_step=None, accept=None,
                            first_increment: float | None = None,
                            ramp: bool = True, start: float = 0.0) -> NewtonResult:
    """Bring ``u`` to equilibrium at load factor ``target``.

    With ``warm`` the current ``u`` (the previous design's equilibrium at the same load) is
    tried first at the full load; otherwise, or if that fails, the load is ramped from zero
    (unless ``ramp`` is False: then a failed warm start is the result, ``u`` restored).
    ``accept(load, u) -> str``, if given, may reject a converged equilibrium by returning a
    reason (an empty string accepts it); a rejected one counts as a failed increment.
    ``on_step(load, u)``, if given, is called at every accepted equilibrium.  On failure ``u``
    holds the last equilibrium, ``load_reached`` its load factor and ``reason`` says why.
    ``first_increment`` (a fraction of ``target``) replaces ``s.initial_increment`` as the first
    increment of a ramp from zero, e.g. the one that worked in the previous solve
    (``NewtonResult.ramp_first``), so that a ramp does not fail its way down to it again.
    ``start``: the load factor at which ``u`` is an equilibrium; with ``s.ramp_from_last``
    a failed warm start ramps the load from there (where below ``target``), never from zero
    (``u`` then holds the warm start's equilibrium, or the ramp's last).
    ``s.rtol`` 0 is the direct route's tolerance here (the mechanics block resolves its own
    route's, :meth:`NewtonSettings.for_route`).
    """
    s = s.for_route(direct=True)
    ref = problem.load_norm(target)
    if not np.isfinite(ref):
        return NewtonResult(False, 0, 0.0, 0, "non-finite external load (or residual at u = 0)")
    if ref == 0.0:
        u[:] = 0.0
        return NewtonResult(True, 0, target, 0, "no load", 0.0)
    result = NewtonResult(False)
    if warm and (_warm_start(problem, u, (target, ref), s, (linear, accept, on_step), result)
                 or not ramp):
        return result
    if warm and s.ramp_from_last:  # never from zero (past a maximum it meets it again)
        if 0.0 < start < target:
            ramp_load(problem, u, (start, target, ref), 0.5 * (target - start), s,
                      (linear, accept, on_step), result)
        return result
    u[:] = 0.0
    first = s.initial_increment if first_increment is None else min(1.0, max(first_increment, s.min_increment))
    ramp_load(problem, u, (0.0, target, ref), first * target, s, (linear, accept, on_step), result)
    return result


def ramp_load(problem, u, loads, inc: float, s: NewtonSettings, hooks,
              result: NewtonResult) -> bool:
    """The load ramp of :func:`solve_with_continuation` (and of a design path, design_path.py)
    from the equilibrium ``u`` at ``loads[0]`` to ``loads[1]`` (``loads[2]`` the target's load
    norm), ``inc`` the first increment; recorded in ``result`` (a ramp from zero sets
    ``ramp_first``); whether it got there (``u`` the last equilibrium either way)."""
    (load, target, ref), (linear, accept, on_step) = loads, hooks
    from_zero = load == 0.0
    saved = u.CreateVector()
    s = replace(s, chord=False)  # full Newton steps (NewtonSettings.chord)
    while load < target * (1 - 1e-12):
        if result.steps >= s.max_steps:
            result.reason = f"more than {s.max_steps} load steps"
            break
        if result.iterations >= s.max_total_iter:
            result.reason = (f"more than {s.max_total_iter} Newton iterations in all (load factor "
                             f"{load:.6g} of {target:.6g} reached; last failure: {result.reason or 'none'})")
            break
        trial_load = min(load + inc, target)
        saved.data = u
        ok, it, why, res = _attempt(problem, u, trial_load, ref, s, linear, accept)
        result.iterations += it
        if ok:
            load = trial_load
            result.steps += 1
            result.history.append((load, it))
            result.residual = res / ref
            if from_zero and result.ramp_first is None:
                result.ramp_first = load / target
            if on_step is not None:
                on_step(load, u)
            if it <= s.easy:
                inc *= s.grow
        else:
            u.data = saved
            inc = 0.5 * (trial_load - load)  # the increment tried (also one cut to the target)
            result.reason = why
            if inc < s.min_increment * target:
                result.reason = (f"load increment fell below {s.min_increment:g} of the target "
                                 f"at load factor {load:.6g} of {target:.6g}: {why}")
                break
    result.load_reached = load
    result.converged = load >= target * (1 - 1e-12)
    if result.converged:
        result.reason = ""
    return result.converged
