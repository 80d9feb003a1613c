"""Newton's method with a J > 0 guard, step cutting and adaptive load increments.

The problem object supplies ``residual(vec, out, load)``, ``assemble_tangent(vec, load)``,
``solve_tangent(rhs, out)``, ``admissible(vec)`` and ``free`` (a numpy mask of free dofs).  A
step that makes the state inadmissible (``det F <= 0`` where the energy needs ``J > 0``, or a
non-finite residual) is halved, never accepted.  Load increments grow after easy steps and are
cut after a failure; the last converged state is kept, so a failure reports how far it got.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class NewtonSettings:
    rtol: float = 1e-10  # residual norm relative to the full external load
    max_iter: int = 30
    max_backtracks: int = 8
    initial_increment: float = 1.0  # first load increment (fraction of the target)
    min_increment: float = 1.0 / 1024
    grow: float = 1.5
    easy: int = 4  # a step converging in <= easy iterations lets the increment grow
    max_steps: int = 200

    def __post_init__(self):
        if not 0 < self.initial_increment <= 1:
            raise ValueError("initial_increment must lie in (0, 1]")
        if self.rtol <= 0 or self.max_iter < 1:
            raise ValueError("rtol must be positive and max_iter >= 1")


@dataclass
class NewtonResult:
    converged: bool
    iterations: int = 0  # Newton iterations summed over all load steps
    load_reached: float = 0.0  # the largest load factor at which equilibrium was found
    steps: int = 0  # accepted load increments
    reason: str = ""
    residual: float = float("nan")
    history: list = field(default_factory=list)


def _norm_free(vec, free):
    a = vec.FV().NumPy()
    return float(np.linalg.norm(a[free]))


def newton_step_solve(problem, u, load, ref, s: NewtonSettings, linear=False):
    """Newton iterations at a fixed load factor.  Returns (converged, iterations, reason, res)."""
    r = u.CreateVector()
    du = u.CreateVector()
    trial = u.CreateVector()
    problem.residual(u, r, load)
    res = _norm_free(r, problem.free)
    if not np.isfinite(res):
        return False, 0, "non-finite residual at the start of the step", res
    tol = s.rtol * ref
    it = 0
    prev = np.inf
    while res > tol:
        if res < 1e-7 * ref and res > 0.5 * prev:
            break  # stagnation at the round-off floor, far below any meaningful tolerance
        prev = res
        if it >= s.max_iter:
            return False, it, f"no convergence in {s.max_iter} iterations (residual {res:.2e})", res
        problem.assemble_tangent(u, load)
        problem.solve_tangent(r, du)
        alpha = 1.0
        for _ in range(s.max_backtracks + 1):
            trial.data = u - alpha * du
            if problem.admissible(trial):
                problem.residual(trial, r, load)
                new = _norm_free(r, problem.free)
                if np.isfinite(new):
                    break
            alpha *= 0.5
        else:
            return False, it + 1, "every step length inverted an element (det F <= 0)", res
        u.data = trial
        res = new
        it += 1
        if linear and res <= max(tol, 1e-10 * ref):
            break
    return True, it, "", res


def solve_with_continuation(problem, u, target: float, s: NewtonSettings, *, warm: bool,
                            linear: bool = False) -> NewtonResult:
    """Bring ``u`` to equilibrium at load factor ``target``.

    With ``warm`` the current ``u`` (the previous design's equilibrium at the same load) is
    tried first at the full load; otherwise, or if that fails, the load is ramped from zero.
    """
    ref = problem.load_norm(target)
    if ref == 0.0:
        u[:] = 0.0
        return NewtonResult(True, 0, target, 0, "no load", 0.0)
    result = NewtonResult(False)
    if warm:
        saved = u.CreateVector()
        saved.data = u
        ok, it, why, res = newton_step_solve(problem, u, target, ref, s, linear)
        result.iterations += it
        if ok:
            result.converged, result.load_reached, result.steps, result.residual = True, target, 1, res / ref
            result.history.append((target, it))
            return result
        u[:] = 0.0
    else:
        u[:] = 0.0
    load, inc = 0.0, s.initial_increment * target
    saved = u.CreateVector()
    while load < target * (1 - 1e-12):
        if result.steps >= s.max_steps:
            result.reason = f"more than {s.max_steps} load steps"
            break
        trial_load = min(load + inc, target)
        saved.data = u
        ok, it, why, res = newton_step_solve(problem, u, trial_load, ref, s, linear)
        result.iterations += it
        if ok:
            load = trial_load
            result.steps += 1
            result.history.append((load, it))
            result.residual = res / ref
            if it <= s.easy:
                inc *= s.grow
        else:
            u.data = saved
            inc *= 0.5
            result.reason = why
            if inc < s.min_increment * target:
                result.reason = (f"load increment fell below {s.min_increment:g} of the target at "
                                 f"load factor {load / target:.4g}: {why}")
                break
    result.load_reached = load
    result.converged = load >= target * (1 - 1e-12)
    if result.converged:
        result.reason = ""
    return result
