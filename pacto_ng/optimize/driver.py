"""The optimisation loop (reads like the 88-line code: set-up, then one section per step).

``optimize`` runs outer iterations ``k = start, start+1, ...``: schedule values, analysis and
sensitivities through the chain, one MMA/GCMMA update with the external move limit, history
and checkpoint callbacks, and the convergence test (which restarts whenever a schedule value
changes, so a run cannot stop mid-continuation).  With ``load_adapt``, a design that Newton
cannot analyse is helped in two ways.  If β rose at this iteration and Newton cannot carry the
load, the β step is cut (the geometric mean, down to steps of :data:`MIN_BETA_STEP`) before
the load is lowered, and the cut β held :data:`BETA_HOLD` iterations before the next step:
the optimiser mends what the sharper projection opened first.  Otherwise, if Newton carried no
more than :data:`COLLAPSE` of the load, the design is moved back towards the last good design
(the design step halved, up to :data:`DESIGN_CUTS` times; history.csv ``design_cuts``), each
cut design analysed from the last good design's equilibria; after the last cut the adaptive
load continuation takes what Newton carries.  If no load is carried, the loop stops cleanly:
the last good design is kept and the reason is returned.  The convergence test waits for the
schedule's β.

Adaptive load continuation (``load_adapt = g > 1``): when the analysis fails at the scheduled
load factor ``s(k)`` after Newton's own step cutting, the iteration goes on at the load factor
Newton did reach (``s_r``, warm-started from that equilibrium; if that solve falls short too,
as near a limit point, at the load it reached, at least 5 % lower, up to 3 times) instead of
stopping; the load is
then capped, ``s = min(s(k), cap)``, and the cap grows by ``g`` after every successful iteration
until it is 1 again.  The design keeps improving at the load it can carry, and it is analysed
at the full load as soon as it can carry it.  The convergence test waits for the full load.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..physics.equilibrium import NewtonFailure
from ..settings import Settings, setting
from .mma import Optimizer
from .schedules import Schedule


@dataclass(frozen=True)
class OptimizerSettings(Settings):
    """The optimisation loop: optimiser, move limit, stopping tests, adaptive load
    continuation."""

    iterations: int = setting(100, "", "maximum optimisation iterations", range="[0, 1000000]")
    optimizer: str = setting("mma-gcmma", "", "mma-gcmma: MMA, then GCMMA (whose accepted steps "
                             "lower the objective) once the objective zigzags on the final "
                             "problem | mma | gcmma", choices=("mma-gcmma", "mma", "gcmma"))
    move: float = setting(0.1, "", "move limit per iteration", range="[1e-6, 1]")
    tol: float = setting(0.01, "", "stop when the largest design change falls below this",
                         range="[0, 1]")
    obj_tol: float = setting(1e-4, "", "... or the objective changed by less than this "
                             "(relative) in each of the last 5 iterations", range="[0, 1]")
    load_adapt: float = setting(1.2, "", "on a Newton failure go on at the load reached, "
                                "raising it by this factor per iteration (0: stop at the "
                                "failure)", range="[0, 100]")

    def check(self):
        if self.load_adapt != 0 and not self.load_adapt > 1:
            raise InputError(f"load_adapt: must be 0 (off) or a growth factor > 1 (got "
                             f"{self.load_adapt:g})")


@dataclass
class LoopState:
    """Everything needed to continue a run exactly (saved in the checkpoint)."""

    k: int
    x: np.ndarray
    opt_state: dict | None
    scale: float | None  # objective normalisation fixed at the first iteration
    history: list = field(default_factory=list)
    stable: int = 0  # consecutive settled iterations with a small change
    last_good: np.ndarray | None = None  # the last design whose analysis succeeded
    load_cap: float = 1.0  # adaptive load continuation: the largest load factor to ask for
    load_failed_at: int = -1  # ... and the last iteration whose analysis failed at the cap
    beta_cap: float = float("inf")  # a β step Newton could not take: the largest β to use
    beta_capped_at: int = -1  # ... the iteration at which the cap last changed
    beta_step: float = 2.0  # ... and the ratio of the cut step that Newton took

    @classmethod
    def start(cls, x: np.ndarray, ref: float) -> LoopState:
        """The state a run starts from at the design ``x``: the objective scaled to 10 at its
        reference value ``ref`` (none where it is not positive)."""
        return cls(k=0, x=x, opt_state=None, scale=10.0 / ref if ref > 0 else None)


@dataclass
class LoopResult:
    state: LoopState
    converged: bool
    stopped: str  # "converged" | "iterations" | "newton"
    message: str
    #: an iterate better than the reported design (:func:`best_iterate`), or None
    best: dict | None = None


def best_iterate(history: list, schedule: Schedule, final_objective: float) -> dict | None:
    """The iteration with the lowest objective among those of the final problem (the final
    penalty and β, the full load) that met every constraint (<= 1e-3), if it is lower than
    the reported design's ``final_objective`` by more than 1e-6 relative; else None."""
    final = schedule.final_values()
    rows = [r for r in history
            if (r["penal"], r["beta"]) == final[:2] and r["load"] >= 1.0
            and r["constraint"] <= 1e-3]
    if not rows:
        return None
    best = min(rows, key=lambda r: r["objective"])
    if best["objective"] < final_objective - 1e-6 * abs(final_objective):
        return {"iteration": int(best["iteration"]), "objective": float(best["objective"])}
    return None


def _stalled(history: list, obj_tol: float, window: int = 5) -> bool:
    """The objective changed by less than ``obj_tol`` (relative) in each of the last ``window``
    iterations."""
    if obj_tol <= 0 or len(history) <= window:
        return False
    recent = np.array([h["objective"] for h in history[-window - 1:]])
    scale = max(abs(recent[-1]), 1e-300)
    return bool(np.max(np.abs(np.diff(recent))) / scale < obj_tol)


def zigzag_at(objectives: list, changes: int = 4) -> int | None:
    """The first index of ``objectives`` where its last ``changes`` changes alternated in sign
    (a 2-cycle of the optimiser), or None."""
    d = np.sign(np.diff(np.asarray(objectives, dtype=float)))
    for end in range(changes, d.size + 1):
        w = d[end - changes:end]
        if np.all(w != 0) and np.all(w[1:] == -w[:-1]):
            return end
    return None


#: how many times the step from the last good design is halved when Newton carries no load on
#: the new design (:func:`optimize`)
DESIGN_CUTS = 3
#: ... also when Newton carries no more than this fraction of the iteration's load (a collapse
#: the adaptive load continuation would otherwise follow); after the cuts it does
COLLAPSE = 0.1
#: a β step (from the last iteration's β) that Newton cannot take at the iteration's load is
#: cut to the geometric mean of the two β, down to steps of this ratio (a doubling: √2, 2^(1/4),
#: 2^(1/8)); the cut β is held BETA_HOLD iterations, then raised by the step that worked,
#: until it is the schedule's β again
MIN_BETA_STEP = 2.0 ** 0.125
BETA_HOLD = 5


def _analyse(evaluate, problem, state, x, penal, beta, load, scheduled, load_adapt, k,
             floor=0.0):
    """Values and gradients at ``x``, with the adaptive load continuation (module docstring).
    Returns ``(F0, f, dF0, df, load)``; raises NewtonFailure when no load is carried, or no
    more than ``floor`` times the load asked for."""
    try:
        F0, f, dF0, df = evaluate(x)
    except NewtonFailure as err:
        reached = err.result.load_reached
        if not load_adapt or reached <= floor * load:
            raise
        # go on at the load Newton reached.  Near a limit point a fresh solve may fall just
        # short of it again: then retry at the load that one reached, at least 5 % lower each
        # time (3 retries)
        state.load_failed_at = k
        for retry in range(4):
            load = state.load_cap = reached
            problem.apply_schedule(penal, beta, load)
            try:
                F0, f, dF0, df = evaluate(x)
                break
            except NewtonFailure as again:
                reached = min(again.result.load_reached, 0.95 * load)
                if retry == 3 or reached <= 0.0:
                    raise
    else:
        # raise the cap after a success, but not in the iteration after a failure
        if load_adapt and load < scheduled and k - state.load_failed_at >= 2:
            state.load_cap = min(1.0, load * load_adapt)
    return F0, f, dF0, df, load


def _counting(problem, evaluate):
    """``evaluate`` that adds the Newton work of every analysis it runs to its list ``work``:
    ``[Newton iterations, accepted load steps]``.  An analysis is a mechanics block whose
    :class:`~pacto_ng.physics.newton.NewtonResult` the call replaced, failed or not (a robust
    realisation that failed ends the call; the realisations after it were not analysed)."""

    def counted(*args, **kwargs):
        blocks = getattr(problem, "mechanics", None) or (problem.mech,)
        before = [m.result for m in blocks]
        try:
            return evaluate(*args, **kwargs)
        finally:
            for m, old in zip(blocks, before):
                if m.result is not None and m.result is not old:
                    counted.work[0] += int(m.result.iterations)
                    counted.work[1] += int(m.result.steps)

    counted.work = [0, 0]
    return counted


class _NoDesign(Exception):
    """No design of this iteration could be analysed (:func:`_analyse_or_cut`); the message
    says why and which design is kept."""


def _values_only(evaluate, state):
    """GCMMA's inner loop's evaluation: the scaled objective and the constraints of a trial
    design; a trial design Newton cannot analyse ends the loop (None), and the step of the
    last approximation is taken, as MMA would."""

    def values_only(xt):
        try:
            F0, f = evaluate(xt, gradients=False)
        except NewtonFailure:
            return None
        return np.asarray(F0) * state.scale, f

    return values_only


def _stage(problem, schedule: Schedule, state: LoopState, k: int, start_iteration):
    """The continuation schedules of iteration ``k``, with the held β cap and the adaptive
    load cap, applied to ``problem``: ``(penal, beta, scheduled load, load)``."""
    penal, beta_s, scheduled = schedule.values(k, state.history)
    if k - state.beta_capped_at >= BETA_HOLD and state.beta_cap < np.inf:
        # the capped β has run BETA_HOLD iterations: the next step (of the ratio that
        # worked) towards the schedule's
        state.beta_cap *= state.beta_step
        state.beta_capped_at = k
        if state.beta_cap >= beta_s * (1 - 1e-12):
            state.beta_cap = float("inf")
    beta = min(beta_s, state.beta_cap)
    load = min(scheduled, state.load_cap)
    problem.apply_schedule(penal, beta, load)
    if start_iteration is not None:
        start_iteration(k, state.history)
    return penal, beta, scheduled, load


def _analyse_or_cut(evaluate, problem, state: LoopState, x, penal, beta, load, scheduled,
                    load_adapt, k):
    """Values and gradients at ``x``; with ``load_adapt``, a failed β step is cut, and a design
    that Newton cannot analyse (a new mechanism, a wall that folds at the first increment) is
    brought back towards the last good one, each from the last good design's equilibria
    (module docstring).  Returns ``(F0, f, dF0, df, x, beta, load, cuts)``; raises
    :class:`_NoDesign` when no design can be analysed."""
    cuts = 0
    before = state.history[-1]["beta"] if state.history else beta
    # the last good design's equilibria: where a cut design's analysis starts
    warm = getattr(problem, "warm", None) if load_adapt else None
    while True:
        # a β step that Newton cannot carry at this load is cut before the load is lowered
        beta_cut = (load_adapt and beta > before
                    and math.sqrt(beta / before) >= MIN_BETA_STEP * (1 - 1e-12))
        # a design step after which Newton carries at most COLLAPSE of the load is cut
        # before the load is lowered
        can_cut = state.last_good is not None and cuts < DESIGN_CUTS
        try:
            F0, f, dF0, df, load = _analyse(evaluate, problem, state, x, penal, beta, load,
                                            scheduled, 0.0 if beta_cut else load_adapt, k,
                                            floor=COLLAPSE if can_cut else 0.0)
            return F0, f, dF0, df, x, beta, load, cuts
        except NewtonFailure as err:
            if beta_cut:
                # the β step is what Newton cannot take: a smaller one (the geometric
                # mean), held BETA_HOLD iterations, so that the optimiser can mend what the
                # sharper projection opens (an eroded realisation's leak) before the next
                state.beta_step = math.sqrt(beta / before)
                beta = state.beta_cap = before * state.beta_step
                state.beta_capped_at = k
                problem.apply_schedule(penal, beta, load)
                if warm is not None:
                    problem.set_warm(warm)
                continue
            if (not load_adapt or not can_cut
                    or err.result.load_reached > COLLAPSE * load):
                kept = (f"the last good design (iteration {k - 1}) is saved" if k > 0 else
                        "no design could be analysed at this load; the initial design is "
                        "saved")
                tried = f" (also with the design step halved {cuts} times)" if cuts else ""
                if warm is not None:  # the final analysis of the kept design starts there
                    problem.set_warm(warm)
                raise _NoDesign(f"iteration {k}: {err}{tried}; {kept}") from None
            cuts += 1
            x = state.last_good + 0.5 * (x - state.last_good)
            if warm is not None:
                problem.set_warm(warm)
            load = min(scheduled, state.load_cap)
            problem.apply_schedule(penal, beta, load)


def _switch_on_zigzag(opt, method: str, schedule: Schedule, state: LoopState, k: int,
                      f0: float, load: float) -> None:
    """mma-gcmma: GCMMA from now on once the objective zigzags on the final problem (the
    switch once; a resumed run scans its history again)."""
    if (method == "mma-gcmma" and opt.method != "gcmma" and state.beta_cap == np.inf
            and schedule.settled(k, history=state.history) and load >= 1.0):
        final = [r["objective"] for r in state.history
                 if schedule.settled(r["iteration"], history=state.history)
                 and r["load"] >= 1.0] + [f0]
        if zigzag_at(final) is not None:
            opt.method = "gcmma"


def _settled_small(state: LoopState, schedule: Schedule, k: int, change: float, load: float,
                   tol: float, obj_tol: float) -> bool:
    """The convergence test's step: the design (or the objective) changed little, and every
    schedule has settled (the full load, no β cap for more than 5 iterations)."""
    small = change < tol or _stalled(state.history, obj_tol)
    settled = (schedule.settled(k, window=5, history=state.history) and load >= 1.0
               and state.beta_cap == np.inf and k - state.beta_capped_at > 5)
    return small and settled


def optimize(problem, schedule: Schedule, *, iterations: int, tol: float, method: str,
             move: float, state: LoopState, on_iteration=None, obj_tol: float = 0.0,
             load_adapt: float = 0.0) -> LoopResult:
    # ---- set-up: everything invariant before the loop ------------------------------------
    n = state.x.size
    m = len(problem.constraints)
    # mma-gcmma: MMA, and GCMMA once MMA zigzags on the final problem (zigzag_at).  With MMA
    # alone the Darcy cases zigzag there (pa-inverter: -Δ/SE alternating by 12 % for the last
    # 60 iterations, every design change at the move limit; with move 0.005 still 2.5 %): at
    # β = 32 a step of 0.005 in x changes ρ̄ of a wall element by up to 0.08, and the strain
    # energy of the pressurised wall follows it.  GCMMA from the first iteration of the final
    # problem instead was slower where MMA does not zigzag (SoRoTop's set-up: Δ 75.6 after 200
    # iterations against 91.6 at convergence in 99; docs/studies.md, "Convergence at
    # defaults")
    # optional parts of the problem's protocol (the robust formulation, pacto_ng.robust): the
    # terms of a worst-case objective, for MMA's bound formulation, and what changes with the
    # iteration besides the schedules
    terms = len(getattr(problem, "objective_terms", ())) or 1
    evaluate = _counting(problem, problem.evaluate_terms if terms > 1 else problem.evaluate)
    start_iteration = getattr(problem, "start_iteration", None)
    opt = Optimizer(n, m, method="mma" if method == "mma-gcmma" else method, move=move,
                    terms=terms)
    opt.state = state.opt_state
    x = state.x.copy()
    values_only = _values_only(evaluate, state)

    while state.k < iterations:
        k = state.k
        t0 = time.perf_counter()
        # ---- continuation schedules ------------------------------------------------------
        penal, beta, scheduled, load = _stage(problem, schedule, state, k, start_iteration)
        # ---- analysis and sensitivities ---------------------------------------------------
        evaluate.work[:] = [0, 0]  # the Newton work of this iteration's analyses (_counting)
        try:
            F0, f, dF0, df, x, beta, load, cuts = _analyse_or_cut(
                evaluate, problem, state, x, penal, beta, load, scheduled, load_adapt, k)
        except _NoDesign as stop:
            return LoopResult(state, False, "newton", str(stop))
        state.last_good = x.copy()
        f0 = float(np.max(F0))  # the objective (the worst of its terms)
        if state.scale is None:  # fix the objective normalisation once (kept on resume)
            state.scale = 10.0 / max(abs(f0), 1e-300)
        # ---- design update (MMA / GCMMA with move limit) ------------------------------------
        _switch_on_zigzag(opt, method, schedule, state, k, f0, load)
        # ---- record: read of x before GCMMA's inner loop analyses trial designs ------------
        row = dict(iteration=k, objective=f0, volume=problem.volume_fraction(),
                   constraint=float(np.max(f)), change=None, penal=penal, beta=beta, load=load,
                   newton=None, load_steps=None, design_cuts=cuts, time=None,
                   **{name: float(problem.values[name]) for name in problem.reports})
        xnew = opt.update(k + 1, x, np.asarray(F0) * state.scale, dF0 * state.scale, f, df,
                          evaluate=values_only if opt.method == "gcmma" else None)
        # Newton's work in this iteration: every analysis of every realisation (the robust
        # formulation's too), the attempts cut short and GCMMA's trial designs.  The next
        # iteration's analysis of an accepted trial design starts at its equilibrium and
        # takes no Newton iteration: the work was done here
        row["newton"], row["load_steps"] = evaluate.work
        change = row["change"] = float(np.max(np.abs(xnew - x)))
        row["time"] = time.perf_counter() - t0
        state.history.append(row)
        x = xnew
        state.x, state.opt_state, state.k = x.copy(), opt.state, k + 1
        # ---- convergence: only once every schedule has settled ------------------------------
        state.stable = state.stable + 1 if _settled_small(state, schedule, k, change, load,
                                                          tol, obj_tol) else 0
        if on_iteration is not None:
            on_iteration(state, row)
        if state.stable >= 2 and np.max(f) <= 1e-3:
            return LoopResult(state, True, "converged",
                              f"converged at iteration {k}: change {change:.3g}, objective "
                              f"change over 5 iterations below {obj_tol:g} or design change below {tol:g}")
    message = f"stopped after {iterations} iterations"
    last = state.history[-1]["load"] if state.history else 1.0
    if last < 1.0 and load_adapt:
        message += (f" (adaptive load continuation: the last iteration ran at load factor "
                    f"{last:.4g} of the full load)")
    return LoopResult(state, False, "iterations", message)
