"""Following an equilibrium path past a pressure maximum: the load factor as an unknown, a
displacement functional prescribed (displacement control by a bordered Newton method).

A chamber that balloons passes a pressure maximum: beyond it, equilibria at a prescribed
pressure are lost (Newton's ramp stalls) although the actuator goes on deforming under a
falling pressure.  Prescribing instead a displacement functional ``c · x`` (e.g. the output
port's Δ, or the mean normal motion of the chamber wall) and solving for the load factor ``s``
with it follows the path through the maximum, as long as ``c · x`` grows along it (Crisfield
1991, *Non-linear finite element analysis of solids and structures*, vol. 1, §9.3,
"displacement control").

The problem object is the one :mod:`~pacto_ng.physics.newton` uses (``residual(x, out, s)``,
affine in ``s``; ``assemble_tangent``, ``solve_tangent``, ``admissible``, ``load_norm`` and
``free``).  One iteration at the state ``(x, s)`` with ``R = R(x, s)`` and
``f = ∂R/∂s = R(x, s + 1) - R(x, s)`` solves with the one factorised tangent ``K``

    ``K a = R``,   ``K b = f``,   ``ds = (c·a - c·x + target) / (c·b)``,   ``dx = a - ds b``

and steps to ``(x - α dx, s - α ds)`` (``α`` halved until the state is admissible): the
linearisation ``R - K dx - f ds = 0`` with ``c · (x - dx) = target``.  The constraint is linear,
so it holds after every full step; the iteration stops when ``|R|`` on the free dofs is below
Newton's ``rtol`` times the load norm at ``s``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..parallel import free_norm
from .newton import NewtonSettings


@dataclass
class PathPoint:
    """An equilibrium on the path: the control ``c · x``, the load factor and its state."""

    control: float
    load: float
    iterations: int
    state: np.ndarray = field(repr=False)


#: the control is held when ``|c·x - target| <= CONTROL_RTOL |target|`` (a full step meets
#: it to round-off; a shortened one leaves the rest to the next iteration)
CONTROL_RTOL = 1e-10


class PathFailure(RuntimeError):
    """No equilibrium at a control value, even after cutting the control increment."""


def solve_controlled(problem, x, load: float, c, target: float, s: NewtonSettings):
    """Newton for ``(x, s)`` with ``c · x = target`` from the state ``x`` (updated in place)
    and load factor ``load``: ``(converged, load factor, iterations, why)``."""
    r, f, a, b, trial = (x.CreateVector() for _ in range(5))

    def res_at(vec, lam):
        problem.residual(vec, r, lam)
        return free_norm(r, problem.free)

    res = res_at(x, load)
    for it in range(s.max_iter + 1):
        ref = problem.load_norm(load) if load else problem.load_norm(1.0)
        if not np.isfinite(res):
            return False, load, it, "non-finite residual"
        held = abs(c.InnerProduct(x) - target) <= CONTROL_RTOL * abs(target)
        if res <= s.rtol * ref and held:
            return True, load, it, ""
        if it == s.max_iter:
            break
        problem.residual(x, f, load + 1.0)
        f.data -= r  # ∂R/∂s: the residual is affine in the load factor
        problem.assemble_tangent(x, load)
        problem.solve_tangent(r, a)
        problem.solve_tangent(f, b)
        cb = c.InnerProduct(b)
        if cb == 0.0 or not np.isfinite(cb):
            return False, load, it + 1, "the control does not move with the load"
        dload = (c.InnerProduct(a) - c.InnerProduct(x) + target) / cb
        a.data -= dload * b  # dx
        alpha = 1.0
        for _ in range(s.max_backtracks + 1):
            trial.data = x - alpha * a
            if problem.admissible(trial):
                new = res_at(trial, load - alpha * dload)
                if np.isfinite(new):
                    break
            alpha *= 0.5
        else:
            return False, load, it + 1, "every step length inverted an element (det F <= 0)"
        x.data = trial
        load, res = load - alpha * dload, new
    return False, load, s.max_iter, (f"no convergence in {s.max_iter} iterations "
                                     f"(residual {res / ref:.2e} of the load)")


def trace(problem, x, c, step: float, s: NewtonSettings, *, load: float = 0.0, stop,
          max_points: int = 100, max_step: float | None = None,
          on_point=None) -> list[PathPoint]:
    """Equilibria along the path from the state ``x`` at load factor ``load`` (``x`` updated
    in place to the last equilibrium), the control ``c · x`` raised by ``step`` at first, until
    ``stop(point)`` is true or ``max_points`` are found.  The increment grows by ``s.grow``
    after a step that took at most ``s.easy`` iterations (up to ``max_step``, default
    8 ``step``) and is halved after a failed one (down to ``s.min_increment`` of ``step``);
    each step starts from the secant through the last two equilibria where that state is
    admissible.  Returns the :class:`PathPoint` of every step; ``on_point(point)`` gets each
    as it is found.  PathFailure when a step cannot be cut further (the points found so far
    in ``.points``)."""
    max_step = 8.0 * step if max_step is None else max_step
    points, history = [], [(c.InnerProduct(x), float(load), x.FV().NumPy().copy())]
    inc = step
    while len(points) < max_points:
        here = history[-1]
        goal = here[0] + inc
        lam = _predict(problem, history, goal, x)
        ok, lam, it, why = solve_controlled(problem, x, lam, c, goal, s)
        if not ok:
            x.FV().NumPy()[:] = here[2]
            inc *= 0.5
            if abs(inc) < s.min_increment * abs(step):
                failure = PathFailure(f"no equilibrium beyond the control {here[0]:.6g} "
                                      f"(load factor {here[1]:.6g}): {why}")
                failure.points = points
                raise failure
            continue
        history.append((goal, lam, x.FV().NumPy().copy()))
        del history[:-2]
        point = PathPoint(goal, lam, it, history[-1][2].copy())
        points.append(point)
        if on_point is not None:
            on_point(point)
        if stop(point):
            break
        if it <= s.easy:
            inc = min(abs(inc) * s.grow, abs(max_step)) * np.sign(step)
    return points


def _predict(problem, history, goal: float, x) -> float:
    """Put the secant predictor's state for the control ``goal`` into ``x`` (the last
    equilibrium's state where only one is known, or where the secant's is not admissible);
    its load factor."""
    (c1, l1, x1), (c2, l2, x2) = history[-2] if len(history) > 1 else history[-1], history[-1]
    x.FV().NumPy()[:] = x2
    if c2 == c1:
        return l2
    w = (goal - c2) / (c2 - c1)
    x.FV().NumPy()[:] = x2 + w * (x2 - x1)
    if not problem.admissible(x):
        x.FV().NumPy()[:] = x2
        return l2
    return l2 + w * (l2 - l1)


def load_maximum(points) -> tuple[float, float] | None:
    """``(control, load)`` at the largest load factor along the path ``points``
    (:class:`PathPoint`), where the load falls after it: the maximum of the parabola through
    the largest and its two neighbours; None where the largest is the first or the last."""
    controls = np.array([q.control for q in points], dtype=float)
    loads = np.array([q.load for q in points], dtype=float)
    top = int(np.argmax(loads)) if len(loads) else 0
    if not 0 < top < len(loads) - 1:
        return None
    a, b, c = np.polyfit(controls[top - 1:top + 2], loads[top - 1:top + 2], 2)
    at = -b / (2.0 * a) if a < 0 else controls[top]
    return float(at), float(np.polyval([a, b, c], at))
