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

Where the prescribed functional turns back along the path (a snap-back: Δ falls while the part
goes on deforming), no equilibrium lies beyond the largest ``c · x`` and displacement control
stalls.  The path is then followed by arc length (Riks' normal plane, Crisfield 1991, §9.3.2,
with the load's weight ψ = 0, the "cylindrical" choice of §9.4.4): each step prescribes the
state's advance ``t · (x - x₂) = l`` along the unit secant ``t`` through the last two
equilibria ``x₁``, ``x₂``; the same bordered iteration with ``c = t``.  The secant follows the
path through a maximum of the load and through a turning point of any one functional alike.

A problem with self-contact (a ``contact`` that is not None, and ``pairs_mismatch(x, s)``:
:class:`~pacto_ng.physics.equilibrium.Equilibrium`) is paired anew at the path's start and
at each of its equilibria, and each point solved again with the control held until the pairs
hold (:func:`~pacto_ng.physics.contact.settle`): a dome pressed through its snap onto the
floor beneath it lands there (tests/physics/test_contact_path.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..parallel import free_norm
from .contact import PairsUnsettled, settle
from .newton import NewtonSettings


@dataclass
class PathPoint:
    """An equilibrium on the path: the control ``c · x``, the load factor and its state."""

    control: float
    load: float
    iterations: int
    state: np.ndarray = field(repr=False)
    by_arc: bool = False  # reached by arc length (the control may have turned back)


#: the control is held when ``|c·x - target| <= CONTROL_RTOL |target|`` (a full step meets
#: it to round-off; a shortened one leaves the rest to the next iteration)
CONTROL_RTOL = 1e-10


#: a step is taken for a jump to another branch of the path, and cut, where the state moves
#: more than JUMP times as far per unit control as on the last step (by arc length: more than
#: JUMP times the arc length, a correction more than 60° off the secant).  As the control
#: approaches a turning point its rate grows without bound, so displacement control cuts its
#: steps there down to the floor and hands over to arc length.
JUMP = 2.0


class PathFailure(RuntimeError):
    """No equilibrium at a control value, even after cutting the control increment."""


def solve_controlled(problem, x, load: float, c, target: float, s: NewtonSettings, *,
                     tol: float | None = None):
    """Newton for ``(x, s)`` with ``c · x = target`` from the state ``x`` (updated in place)
    and load factor ``load``: ``(converged, load factor, iterations, why)``.  The constraint
    holds within ``tol`` (default CONTROL_RTOL ``|target|``)."""
    tol = CONTROL_RTOL * abs(target) if tol is None else tol
    r, f, a, b, trial = (x.CreateVector() for _ in range(5))

    def res_at(vec, lam):
        problem.residual(vec, r, lam)
        return free_norm(r, problem.free)

    res = res_at(x, load)
    for it in range(s.max_iter + 1):
        ref = problem.load_norm(load) if load else problem.load_norm(1.0)
        if not np.isfinite(res):
            return False, load, it, "non-finite residual"
        held = abs(c.InnerProduct(x) - target) <= tol
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


class _Unsolved(Exception):
    """A point of the path not reached (with contact: one of its solves); the message says
    why."""

    def __init__(self, iterations: int, why: str):
        super().__init__(why)
        self.iterations = iterations


def _solve_point(problem, x, load: float, c, target: float, s: NewtonSettings, *,
                 tol: float | None = None):
    """:func:`solve_controlled`, and where the problem has contact, paired anew at the
    equilibrium and solved again until the pairs hold (the module): the same result."""
    if getattr(problem, "contact", None) is None:
        return solve_controlled(problem, x, load, c, target, s, tol=tol)

    def solve() -> int:
        nonlocal load
        ok, load, it, why = solve_controlled(problem, x, load, c, target, s, tol=tol)
        if not ok:
            raise _Unsolved(it, why)
        return it

    try:
        iterations = settle(solve, lambda: problem.pairs_mismatch(x, load), s.rtol)
    except _Unsolved as err:
        return False, load, err.iterations, str(err)
    except PairsUnsettled as err:
        return False, load, 0, str(err)
    return True, load, iterations, ""


def trace(problem, x, c, step: float, s: NewtonSettings, *, load: float = 0.0, stop,
          max_points: int = 100, max_step: float | None = None, on_point=None,
          arc: bool = True, dofs=slice(None)) -> list[PathPoint]:
    """Equilibria along the path from the state ``x`` at load factor ``load`` (``x`` updated
    in place to the last equilibrium), the control ``c · x`` raised by ``step`` at first, until
    ``stop(point)`` is true or ``max_points`` are found.  The increment grows by ``s.grow``
    after a step that took at most ``s.easy`` iterations (up to ``max_step``, default
    8 ``step``) and is halved after a failed one (down to ``s.min_increment`` of ``step``);
    each step starts from the secant through the last two equilibria where that state is
    admissible.  Where the control cannot be raised further (it turns back along the path)
    and ``arc``, the path goes on by arc length (:func:`_by_arc_length`).  Returns the
    :class:`PathPoint` of every step; ``on_point(point)`` gets each as it is found.
    PathFailure when a step cannot be cut further (the points found so far in ``.points``).
    ``dofs`` (an index of the state vector) are the entries whose motion measures the path:
    the displacement's of a mixed state, whose pressure field (in pascals) would otherwise
    outweigh the displacement (in metres) in every length and secant."""
    max_step = 8.0 * step if max_step is None else max_step
    if getattr(problem, "contact", None) is not None:
        problem.pairs_mismatch(x, load)  # the pairs of the path's start
    points, history = [], [(c.InnerProduct(x), float(load), x.FV().NumPy().copy())]
    inc, rate = step, None  # the increment; the last step's state change per unit control
    longest = 0.0  # the longest step of the state
    while len(points) < max_points:
        here = history[-1]
        goal = here[0] + inc
        lam = _predict(problem, history, goal, x)
        ok, lam, it, why = _solve_point(problem, x, lam, c, goal, s)
        moved = float(np.linalg.norm((x.FV().NumPy() - here[2])[dofs])) / abs(inc)
        if ok and rate is not None and moved > JUMP * rate:
            ok, why = False, "the state jumped (to another branch of the path)"
        if not ok:
            x.FV().NumPy()[:] = here[2]
            inc *= 0.5
            if abs(inc) >= s.min_increment * abs(step):
                continue
            if arc and len(history) > 1:
                return _by_arc_length(problem, x, c, history, s, stop=stop, points=points,
                                      max_points=max_points, on_point=on_point, longest=longest,
                                      dofs=dofs)
            raise _failure(f"no equilibrium beyond the control {here[0]:.6g} (load factor "
                           f"{here[1]:.6g}): {why}", points)
        rate, longest = moved, max(longest, moved * abs(inc))
        if _accept(history, points, goal, lam, it, x, on_point, stop):
            break
        if it <= s.easy:
            inc = min(abs(inc) * s.grow, abs(max_step)) * np.sign(step)
    return points


def _by_arc_length(problem, x, c, history, s: NewtonSettings, *, stop, points, max_points,
                   on_point, longest: float = 0.0, dofs=slice(None)) -> list[PathPoint]:
    """Go on along the path from the last two equilibria of ``history`` ((control, load,
    state) each) by arc length (see the module): each step advances the state by ``l`` along
    the unit secant through the last two, ``l`` the last step's length at first, grown and
    halved as :func:`trace` does its increment (up to 8 times the first or ``longest``, the
    longest step before, whichever is longer; at least ``s.min_increment`` of the first).
    Appends to ``points`` (the control ``c · x`` still recorded, ``by_arc`` set) until
    ``stop(point)`` or ``max_points``; returns them.  PathFailure when a step cannot be cut
    further.  Lengths and the secant's direction are of the entries ``dofs`` (:func:`trace`);
    the predictor extrapolates every entry."""
    first = float(np.linalg.norm((history[-1][2] - history[-2][2])[dofs]))
    length, t, most = first, x.CreateVector(), max(8.0 * first, longest)
    while len(points) < max_points:
        (_, l1, x1), (_, l2, x2) = history[-2], history[-1]
        secant = x2 - x1
        span = np.linalg.norm(secant[dofs])
        t[:] = 0.0
        t.FV().NumPy()[dofs] = secant[dofs] / span
        along = t.InnerProduct(x)  # x holds x2 here
        w = length / span
        x.FV().NumPy()[:] = x2 + w * secant  # the secant's predictor, where admissible
        lam = l2 + w * (l2 - l1)
        if not problem.admissible(x):
            x.FV().NumPy()[:], lam = x2, l2
        ok, lam, it, why = _solve_point(problem, x, lam, t, along + length, s,
                                        tol=CONTROL_RTOL * (abs(along) + length))
        if ok and np.linalg.norm((x.FV().NumPy() - x2)[dofs]) > JUMP * length:
            ok, why = False, "the state jumped (to another branch of the path)"
        if not ok:
            x.FV().NumPy()[:] = x2
            length *= 0.5
            if length < s.min_increment * first:
                raise _failure(f"no equilibrium by arc length beyond the control "
                               f"{history[-1][0]:.6g} (load factor {l2:.6g}): {why}", points)
            continue
        if _accept(history, points, c.InnerProduct(x), lam, it, x, on_point, stop, True):
            break
        if it <= s.easy:
            length = min(length * s.grow, most)
    return points


def _accept(history, points, control: float, load: float, iterations: int, x, on_point,
            stop, by_arc: bool = False) -> bool:
    """Record the equilibrium held in ``x`` at ``control`` and ``load``: into ``history`` (its
    last two kept) and as a :class:`PathPoint` into ``points``, given to ``on_point``;
    whether ``stop`` says the path is done."""
    history.append((control, load, x.FV().NumPy().copy()))
    del history[:-2]
    point = PathPoint(control, load, iterations, history[-1][2].copy(), by_arc=by_arc)
    points.append(point)
    if on_point is not None:
        on_point(point)
    return stop(point)


def _failure(message: str, points) -> PathFailure:
    """A PathFailure carrying the ``points`` found before it."""
    failure = PathFailure(message)
    failure.points = points
    return failure


def rising(problem, x, load: float, c) -> float:
    """``+1`` or ``-1``: the sign of the control's change where the path from the equilibrium
    ``x`` at ``load`` goes on with the load rising, ``-sign(c · K⁻¹ ∂R/∂s)`` (the tangent:
    ``K dx + ∂R/∂s ds = 0``); ``+1`` where the control does not move with the load."""
    r, f, b = (x.CreateVector() for _ in range(3))
    problem.residual(x, r, load)
    problem.residual(x, f, load + 1.0)
    f.data -= r
    problem.assemble_tangent(x, load)
    problem.solve_tangent(f, b)
    return -1.0 if c.InnerProduct(b) > 0.0 else 1.0


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


def retraces(loads, volumes) -> bool:
    """Whether a path of a closed chamber's pressure ``loads`` and volume ``volumes`` (one
    each per point, in order) turns back on itself at its first pressure maximum: the volume
    falls with the pressure right after it.  Past a true maximum the volume goes on growing
    (the pressure is the energy's conjugate of the chamber's volume, whose curve is smooth
    there).  False where a volume is not known (None)."""
    if len(loads) < 2 or None in volumes:
        return False
    tops = [i for i in range(1, len(loads) - 1)
            if loads[i] >= loads[i - 1] and loads[i] > loads[i + 1]]
    top = tops[0] if tops else int(np.argmax(loads))
    return top + 1 < len(loads) and volumes[top + 1] < volumes[top]


#: the load along a path counts as having fallen past a maximum once it is this share below
#: the largest before (the wiggles of arc length round a maximum are far smaller)
DROP = 0.02


def climbs_again(loads) -> bool:
    """Whether the load along a path (``loads``, one per point in order) fell past a
    maximum, by more than :data:`DROP` of it, and rises again at the last point: past the
    valley, where the path is stable under the load again (e.g. walls that came to rest on
    each other), so that Newton can ramp the load on from there."""
    top = fell = 0.0
    for a in loads[:-1]:
        top = max(top, a)
        fell = fell or a < (1.0 - DROP) * top
    return bool(fell) and len(loads) > 1 and loads[-1] > loads[-2]


def load_maximum(points) -> tuple[float, float] | None:
    """``(control, load)`` at the first maximum of the load factor along the path ``points``
    (:class:`PathPoint`), a point whose load is above its neighbours': the maximum of the
    parabola through it and its two neighbours (the point itself where the control turns
    back among them); None where the load never falls."""
    controls = np.array([q.control for q in points], dtype=float)
    loads = np.array([q.load for q in points], dtype=float)
    tops = [i for i in range(1, len(loads) - 1)
            if loads[i] >= loads[i - 1] and loads[i] > loads[i + 1]]
    if not tops:
        return None
    top = tops[0]
    near = controls[top - 1:top + 2]
    if not (np.all(np.diff(near) > 0) or np.all(np.diff(near) < 0)):
        return float(controls[top]), float(loads[top])
    a, b, c = np.polyfit(near, loads[top - 1:top + 2], 2)
    at = -b / (2.0 * a) if a < 0 else controls[top]
    return float(at), float(np.polyval([a, b, c], at))
