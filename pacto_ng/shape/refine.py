"""Body-fitted refinement of a part's shape: a descent loop on the mesh deformation that
maximises the part's output ``Δ`` (or its mechanism ratio ``Δ/SE``) with its volume bounded
(and, if asked, ``Δ/SE`` kept from falling and the walls from thinning below a floor), on one
mesh (a caller remeshes between loops).

Problem.  ``min_d f(d) = -J(d)/|J(0)|`` subject to ``c_V(d) = V(d)/V_max - 1 ≤ 0`` and,
with a floor ``r_min``, ``c_r(d) = 1 - (Δ/SE)(d)/r_min ≤ 0`` and, with a wall floor ``T``,
``c_w(d) ≤ 0``, the walls' shortfall below ``(1 + WALL_MARGIN) T``
(:meth:`~pacto_ng.shape.thickness.WallThickness.shortfall`: the squared relative deficit of
the thickness integrated over the boundary, zero where no wall is thinner, with its exact
derivative in the vertices; an order-1 shape space); ``d`` the deformation of
:class:`~pacto_ng.shape.deformation.ShapeSpace`, ``J`` the objective of
:class:`~pacto_ng.shape.gradient.PartResponse`: its output ``Δ`` (``objective="delta"``) or
the runs' mechanism ratio ``Δ/SE`` (``"ratio"``), ``V`` the part's volume (the thickness times
the area in 2D).  The inequalities are treated by the augmented Lagrangian of Rockafellar
(1973, *J. Optim. Theory Appl.* 12, "The multiplier method of Hestenes and Powell applied to
convex programming"; Nocedal and Wright 2006, *Numerical Optimization*, 2nd ed., ch. 17):
the merit

    M(d; λ) = f(d) + Σ_i (max(0, λ_i + μ_i c_i(d))² - λ_i²) / (2μ_i),

with the multipliers ``λ_i ≥ 0`` (start 0) and the penalties ``μ_i`` (each doubled, up to
:data:`PENALTY_MAX`, after an accepted step whose violation is above :data:`VIOLATION` and
not half the last one's: Nocedal and Wright, §17.4); its shape derivative is
``dM = df + Σ_i max(0, λ_i + μ_i c_i) dc_i``.  Each step (one descent step per multiplier
update, a common simplification in shape optimisation, where an exact inner minimisation is
too dear):

1. the state and adjoint on the current shape, ``dJ``, ``dV`` and (a floor active)
   ``d(Δ/SE)`` (a second adjoint)
   (:meth:`~pacto_ng.shape.gradient.PartResponse.gradient`,
   :meth:`~pacto_ng.shape.deformation.ShapeSpace.derivative`);
2. the descent field ``θ``, the Riesz representative of ``-dM``
   (:class:`~pacto_ng.shape.riesz.RieszMap`; ``dM(θ) < 0``), scaled to a largest coefficient
   of 1, so that (order-1 shape space) the step ``s`` is the largest move of a vertex
   coordinate;
3. the step control: ``s`` no larger than the trial step with ``min det(I + ∇₀d) ≥ q_min``
   (:func:`~pacto_ng.shape.riesz.step_length`); below ``quality_step`` (default
   ``min_step``) the loop stops with the status ``mesh_quality``: the mesh needs remeshing
   (:func:`~pacto_ng.shape.remesh.remesh_moved`), which a caller does and then goes on;
4. the trial shape ``d + sθ`` is accepted if the merit at the same ``λ`` decreases (a plain
   decrease), else ``s`` is halved (a trial whose Newton solve fails is rejected too, and
   one where two walls cross each other across a void: no element folds there, but
   the walls of a chamber or a slot have no element between them,
   :func:`~pacto_ng.shape.remesh.crossing_walls`, or, with ``min_wall``, one with a wall
   thinner than that, :class:`~pacto_ng.shape.thickness.WallThickness`: the shortfall
   constraint steers the descent away from the floor, this refusal keeps it); below
   ``min_step`` the status is ``no_descent`` (when the wall floor refused a trial, the
   walls' penalty is first made ten times stiffer, up to :data:`PENALTY_MAX`, and the step
   taken again from a new direction).  The trial step of the next iteration is twice
   the accepted one, at most ``step_max``;
   with a box ``bounds`` (the run's design domain), every trial shape is projected into it
   before anything is measured: each vertex's moved position ``x0 + d + sθ`` is clipped
   coordinate by coordinate into ``[low, high]`` (the projection onto a box, exact and
   componentwise), so the step is taken along the projection arc
   ``P(d + sθ)`` of a projected-gradient method (Bertsekas 1999, *Nonlinear Programming*,
   2nd ed., §2.3, with a plain decrease in place of Armijo's rule); the step control of 3
   and the accept test act on the projected trial, and a vertex on the box's side slides
   along it.  Held dofs are never moved by the projection.  The direction of step 2 is
   that of the active set: the vertex coordinates on a side of the box that the field ``θ``
   would move out are held (zero in ``θ``) and ``θ`` solved again on the other dofs (the
   Riesz problem restricted, still a descent direction; Bertsekas 1982, *SIAM J. Control
   Optim.* 20, "Projected Newton methods for optimization problems with simple
   constraints"): the field then slides along the side instead of pressing the elements
   behind a clipped vertex flat.  Order-1 shape spaces only: there the dofs are the vertex
   displacements (component ``k`` of vertex ``i`` is dof ``k·nv + i``), and the vertices,
   with them every straight edge, stay in the box (a curved edge of the reference mesh
   could bulge past a side by its own curvature: the bound is on the vertices);
5. the multiplier update ``λ_i ← max(0, λ_i + μ_i c_i)`` at the accepted shape, then the
   penalties' (above).

The loop stops after ``steps`` accepted steps (status ``steps``) or when the merit changes by
less than ``rtol`` relative to ``max(1, |M|)`` with the constraints met to ``vtol``
(``converged``).  The bound is met only approximately while ``λ`` settles: measured on the
plate with a pressurised hole of the tests (μ = 1000), 0.05 % above a bound of 95 % of the
start after 5 steps, 0.6 % above a bound of 100 % after 8; with μ = 100, 3 % above the
latter.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..physics.equilibrium import NewtonFailure
from .deformation import ShapeSpace, volume, volume_integrals
from .remesh import crossing_walls
from .thickness import WallThickness
from .gradient import PartResponse
from .riesz import Quality, RieszMap, step_length

STATUSES = ("converged", "steps", "mesh_quality", "no_descent")
#: a constraint violation above this (relative) that does not halve from one accepted step
#: to the next doubles that constraint's penalty μ, up to :data:`PENALTY_MAX`
VIOLATION = 1e-3
PENALTY_MAX = 1e4
#: a vertex coordinate within this share of the box's size of one of its sides is on it
ACTIVE_TOL = 1e-9
#: with a wall floor ``T``, the descent is steered to keep every wall above ``(1 +
#: WALL_MARGIN) T`` (the shortfall constraint), and a trial with a wall below ``T`` is refused
WALL_MARGIN = 0.1


@dataclass
class RefineResult:
    """The outcome of :func:`refine`: ``status`` (one of :data:`STATUSES`), the final
    deformation's coefficients ``shape`` (the space is left at it), its ``delta``, ``value``
    (the objective ``J``) and ``volume``, the last ``multipliers`` (by constraint: ``volume``,
    ``ratio``, ``wall``) and the ``history``: one dict per accepted shape (step 0 the start)
    with ``step``, ``delta``, ``value``, ``ratio`` (``Δ/SE``, NaN unless needed), ``volume``,
    ``det`` (the lowest ``det(I + ∇₀d)``), ``length`` (the step ``s``), ``wall`` (the thinnest),
    ``merit`` and ``merit_before`` (at the step's multipliers), ``multipliers``, ``trials``."""

    status: str
    shape: np.ndarray
    delta: float
    value: float
    volume: float
    multipliers: dict
    history: list[dict] = field(default_factory=list)
    penalties: dict = field(default_factory=dict)


class _Loop:
    """The state of one refinement: the current shape and its measures, merit and
    multipliers (see the module)."""

    def __init__(self, response: PartResponse, space: ShapeSpace, riesz: RieszMap, *,
                 bounds=None, limits: dict, penalty, multipliers=None,
                 scale: float | None = None, objective: str = "delta",
                 min_wall: float | None = None):
        self.response, self.space, self.riesz = response, space, riesz
        # the walls' thickness (an order-1 space: WallThickness) and its floor, if any
        self.walls = WallThickness(space.mesh) if space.vertex_dofs else None
        self.min_wall = min_wall or 0.0
        self.objective, self.limits = objective, dict(limits)
        if self.min_wall:
            if self.walls is None:
                raise ValueError("refine: a wall floor needs an order-1 shape space")
            self.limits["wall"] = (1.0 + WALL_MARGIN) * self.min_wall
        self.box = None if bounds is None else _Box(space, bounds)
        self.quality = Quality(space)
        # μ per constraint: a number for all, or a dict (an earlier refinement's)
        self.penalties = (dict(penalty) if isinstance(penalty, dict)
                          else dict.fromkeys(self.limits, float(penalty)))
        self.violations = {}
        self.thickness = response.thickness
        self.multipliers = dict.fromkeys(self.limits, 0.0) | dict(multipliers or {})
        self.shape = space.deformation.vec.FV().NumPy().copy()
        self.measures = self.evaluate(self.shape)
        self.scale = abs(self.value) if scale is None else float(scale)
        if not self.scale > 0:
            raise ValueError("refine: the objective is zero on the starting shape")
        self.state = response.state.vec.CreateVector()
        self.state.data = response.state.vec

    @property
    def value(self) -> float:
        return self.measures[self.objective]

    def evaluate(self, shape, ramp: bool = True) -> dict:
        """The measures ``delta``, ``volume`` and (when the objective or a limit needs it)
        ``ratio`` on the shape ``shape`` (the mesh is left at it); ``ramp`` False: the
        equilibrium from the last one's at the full load only (a trial shape: if that fails,
        the step is too long, and a ramp from zero would cost tens of Newton iterations)."""
        self.space.set(shape)
        out = {"delta": self.response.solve(ramp=ramp),
               "volume": volume(self.space.mesh, self.thickness)}
        if "ratio" in (self.objective, *self.limits):
            out["ratio"] = self.response.value("ratio")
        if "wall" in self.limits:
            out["wall"] = self.walls.shortfall(self.space.points_at(shape),
                                               self.limits["wall"])[0]
        return out

    def constraints(self, measures: dict) -> dict:
        """``c_i ≤ 0`` of each limit: ``V/V_max - 1``, ``1 - (Δ/SE)/r_min`` and the walls'
        shortfall (:meth:`~pacto_ng.shape.thickness.WallThickness.shortfall`, never
        negative: the constraint is met when it is zero)."""
        out = {}
        for name, bound in self.limits.items():
            if name == "wall":
                out[name] = measures[name]
                continue
            ratio = measures[name] / bound
            out[name] = ratio - 1.0 if name == "volume" else 1.0 - ratio
        return out

    def merit(self, measures: dict) -> float:
        """``M`` at the current multipliers."""
        total = -measures[self.objective] / self.scale
        for name, c in self.constraints(measures).items():
            lam, mu = self.multipliers[name], self.penalties[name]
            total += (max(0.0, lam + mu * c) ** 2 - lam * lam) / (2 * mu)
        return total

    def update(self) -> None:
        """The multiplier update ``λ_i ← max(0, λ_i + μ c_i)`` at the accepted shape."""
        for name, c in self.constraints(self.measures).items():
            mu = self.penalties[name]
            self.multipliers[name] = max(0.0, self.multipliers[name] + mu * c)
            # a violation that does not halve from one step to the next: a stiffer penalty
            # (Nocedal and Wright 2006, §17.4; at most PENALTY_MAX)
            if c > VIOLATION and c > 0.5 * self.violations.get(name, math.inf):
                self.penalties[name] = min(PENALTY_MAX, 2.0 * mu)
            self.violations[name] = max(c, 0.0)

    def direction(self) -> np.ndarray:
        """``θ`` for ``-dM`` at the current (accepted, solved) shape, largest coefficient 1.
        The objective's and the Δ/SE floor's terms are one weighted gradient (one adjoint,
        one shape derivative: :meth:`~pacto_ng.shape.gradient.PartResponse.gradient`)."""
        weights, g = {self.objective: 1.0 / self.scale}, 0.0
        for name, c in self.constraints(self.measures).items():
            weight = max(0.0, self.multipliers[name] + self.penalties[name] * c)
            if weight == 0:
                continue
            if name == "volume":  # dc = dV / V_max
                g = g - weight * self.space.derivative(
                    volume_integrals(self.thickness)) / self.limits[name]
            elif name == "wall":
                g = g - weight * self.wall_derivative()
            else:  # dc = -d(Δ/SE) / r_min
                weights[name] = weights.get(name, 0.0) + weight / self.limits[name]
        g = g + self.response.gradient(self.space, weights)
        theta = self.riesz(g)
        if self.box is not None:
            active = self.box.active(self.shape, theta)
            if np.any(active):
                theta = self.riesz(g, hold=active)
        largest = float(np.max(np.abs(theta)))
        if not largest > 0:
            raise ValueError("refine: the shape derivative vanishes on the free dofs")
        return theta / largest

    def wall_derivative(self) -> np.ndarray:
        """The shape derivative of the walls' shortfall at the current shape, on the dofs
        (component ``k`` of vertex ``i`` is dof ``k·nv + i``), held dofs zeroed."""
        _, grad = self.walls.shortfall(self.space.points_at(self.shape), self.limits["wall"])
        out = grad.T.reshape(-1).copy()
        out[self.space.held] = 0.0
        return out

    def crossing(self, values) -> bool:
        """Whether two walls of the shape ``values`` cross each other (2D and 3D, an order-1
        space: :func:`~pacto_ng.shape.remesh.crossing_walls`; no element folds, but walls facing
        each other across a void can pass through each other)."""
        if not self.space.vertex_dofs:
            return False
        return crossing_walls(self.space.mesh, self.space.points_at(values)) > 0

    def thinnest(self, values) -> float:
        """The thinnest wall of the shape ``values``, along the facets' normals or across a 2D
        neck (:meth:`~pacto_ng.shape.thickness.WallThickness.neck`); NaN for order > 1."""
        if self.walls is None:
            return math.nan
        ray = float(self.walls(points := self.space.points_at(values)).min())
        return min(ray, self.walls.neck(points, ray))

    def project(self, values) -> np.ndarray:
        """``values`` projected into the box (unchanged without one)."""
        return values if self.box is None else self.box.project(values)

    def search(self, theta, length: float, min_step: float, q_min: float,
               quality_step: float):
        """Step control and backtracking from the trial step ``length``: ``(status, s, q,
        trials)``, status None for an accepted step (the loop's shape moved to it).  Every
        trial shape (projected into the box, if any) is measured before it is solved: none
        below ``q_min`` is accepted; a step the quality bounds below ``quality_step`` stops
        the loop (``mesh_quality``)."""
        s, q = step_length(lambda values: self.quality(self.project(values)), self.shape,
                           theta, length, q_min=q_min)
        if s < quality_step and s < length:  # the quality bounds the step, not the trial
            return "mesh_quality", s, q, 0
        before, trials, walled = self.merit(self.measures), 0, False
        # a shape thinner than the floor (a part made so) may not thin further
        floor = min(self.min_wall, self.thinnest(self.shape)) if self.min_wall else 0.0
        while s >= min_step:
            trial = self.project(self.shape + s * theta)
            q = self.quality(trial)
            thin = bool(floor) and self.thinnest(trial) < floor
            walled |= thin
            if q >= q_min and not self.crossing(trial) and not thin:
                trials += 1
                try:
                    measures = self.evaluate(trial, ramp=False)
                except (NewtonFailure, ValueError):  # no equilibrium, or no strain (SE = 0)
                    measures = None
                if measures is not None and self.merit(measures) < before:
                    self.shape, self.measures = trial, measures
                    self.state.data = self.response.state.vec
                    return None, s, q, trials
                self.response.state.vec.data = self.state  # the next solve starts from the last
            s *= 0.5
        self.evaluate(self.shape)
        return "wall_floor" if walled else "no_descent", s, q, trials

    def stiffen_wall(self) -> bool:
        """The walls' penalty μ ten times stiffer (at most :data:`PENALTY_MAX`), so that the
        next direction thickens the thinnest walls; False when it is at its largest."""
        mu = self.penalties.get("wall", PENALTY_MAX)
        if mu >= PENALTY_MAX:
            return False
        self.penalties["wall"] = min(PENALTY_MAX, 10.0 * mu)
        return True

    def record(self, step: int, length: float, det: float, merits: tuple[float, float],
               trials: int) -> dict:
        """The history entry of the current shape; ``merits`` before and after the step."""
        return {"step": step, "delta": self.measures["delta"], "value": self.value,
                "ratio": self.measures.get("ratio", math.nan),
                "volume": self.measures["volume"], "det": det, "length": length,
                "wall": self.thinnest(self.shape),
                "merit_before": merits[0], "merit": merits[1],
                "multipliers": dict(self.multipliers), "penalties": dict(self.penalties),
                "trials": trials}


def refine(response: PartResponse, space: ShapeSpace, *, volume_max: float,
           ratio_min: float | None = None, steps: int = 20, step: float = 0.02,
           step_max: float | None = None, min_step: float | None = None, q_min: float = 0.3,
           penalty=1000.0, rtol: float = 1e-5, vtol: float = 1e-3,
           alpha: float = 1.0, kind: str = "elasticity", bounds=None, multipliers=None,
           scale: float | None = None, quality_step: float | None = None,
           objective: str = "delta", min_wall: float | None = None,
           say: Callable[[str], None] | None = None) -> RefineResult:
    """Maximise ``J`` (``objective``: ``"delta"`` for ``Δ``, ``"ratio"`` for ``Δ/SE``) with
    ``t|Ω| ≤ volume_max`` (and ``Δ/SE ≥ ratio_min``, if given) by descent on the shape (see
    the module).

    ``response`` and ``space`` on the same mesh, ``space`` at the starting deformation;
    ``step`` the first trial step and ``step_max`` the largest (default ``4 step``), both in
    lengths of the mesh; ``min_step`` (default ``step / 1024``); ``q_min`` the lowest
    Jacobian allowed; ``penalty`` the starting ``μ`` (a number, or one per constraint as
    ``RefineResult.penalties`` gives them); ``alpha`` and ``kind`` those of the
    :class:`~pacto_ng.shape.riesz.RieszMap`; ``bounds`` ``(low, high)``, the lowest and
    highest corner of a box (one coordinate per dimension of the mesh) that every vertex of
    the part is kept in: each trial shape is projected into it (step 4 of the module; an
    order-1 ``space`` only); ``multipliers`` the starting ``λ`` (``{"volume": λ, "ratio":
    λ}``, default 0) and ``scale`` the ``|J(0)|`` of the objective (default: this start's
    ``|J|``), both to go on from an earlier refinement of the same part on another mesh;
    ``quality_step`` (default ``min_step``) the step below which a step bounded by the
    mesh's quality stops the loop with the status ``mesh_quality`` (a caller that remeshes
    then gives a larger one: small steps that the quality bound allows make little
    progress); ``min_wall`` the thinnest wall a trial shape may have (an order-1
    ``space``: :class:`~pacto_ng.shape.thickness.WallThickness`): the descent is steered to
    keep the walls above ``(1 + WALL_MARGIN) min_wall`` (the constraint ``c_w``, its
    multiplier ``"wall"``) and a trial with a wall below ``min_wall`` (or, a shape already
    thinner, below its thinnest wall) is refused; ``say``
    receives one line per step."""
    if space.mesh is not response.mesh:
        raise ValueError("the shape space and the response must be on the same mesh")
    mus = penalty.values() if isinstance(penalty, dict) else (penalty,)
    if not (volume_max > 0 and step > 0 and min(mus) > 0 and 0 < q_min < 1 and steps >= 0
            and (ratio_min is None or ratio_min > 0)):
        raise ValueError("refine: volume_max, ratio_min, step and penalty must be positive, "
                         "q_min in (0, 1) and steps non-negative")
    step_max = 4.0 * step if step_max is None else float(step_max)
    min_step = step / 1024.0 if min_step is None else float(min_step)
    quality_step = min_step if quality_step is None else float(quality_step)
    limits = {"volume": float(volume_max)} | ({} if ratio_min is None
                                              else {"ratio": float(ratio_min)})
    loop = _Loop(response, space, RieszMap(space, alpha=alpha, kind=kind), bounds=bounds,
                 limits=limits, penalty=penalty, multipliers=multipliers, scale=scale,
                 objective=objective, min_wall=min_wall)
    start = loop.merit(loop.measures)
    history = [loop.record(0, 0.0, loop.quality(loop.shape), (start, start), 0)]
    status, length = "steps", float(step)
    for k in range(1, steps + 1):
        while True:
            theta = loop.direction()
            before = loop.merit(loop.measures)
            stop, s, q, trials = loop.search(theta, length, min_step, q_min, quality_step)
            if stop != "wall_floor":
                break
            if not loop.stiffen_wall():
                stop = "no_descent"
                break
            _say(say, f"the wall floor refused step {k}: its penalty {loop.penalties['wall']:g}")
        if stop is not None:
            status = stop
            _say(say, f"step {k}: stopped ({stop}; step {s:.3g}, lowest det {q:.3f})")
            break
        after = loop.merit(loop.measures)
        loop.update()
        history.append(loop.record(k, s, q, (before, after), trials))
        _say(say, _line(k, loop, (after, q, s, trials)))
        length = min(2.0 * s, step_max)
        if (abs(after - before) <= rtol * max(1.0, abs(after))
                and max(loop.constraints(loop.measures).values()) <= vtol):
            status = "converged"
            break
    m = loop.measures
    return RefineResult(status, loop.shape.copy(), m["delta"], loop.value, m["volume"],
                        dict(loop.multipliers), history, dict(loop.penalties))


def _line(k: int, loop: _Loop, figures) -> str:
    """The progress line of step ``k``; ``figures`` ``(merit, lowest det, step, trials)``."""
    m, (merit, q, s, trials) = loop.measures, figures
    ratio = f", Δ/SE {m['ratio']:.6g}" if "ratio" in m else ""
    wall = f", thinnest wall {loop.thinnest(loop.shape):.4g}" if loop.min_wall else ""
    return (f"step {k}: Δ {m['delta']:.6g}{ratio}, volume {m['volume']:.6g} (bound "
            f"{loop.limits['volume']:.6g}){wall}, merit {merit:.6g}, lowest det {q:.3f}, step "
            f"{s:.3g} ({trials} trial{'s' if trials > 1 else ''})")


class _Box:
    """The projection of an order-1 shape space's coefficients that keeps every vertex's
    moved position ``x0 + d`` in the box ``bounds = (low, high)`` (held dofs untouched)."""

    def __init__(self, space: ShapeSpace, bounds):
        mesh, dim = space.mesh, space.mesh.dim
        low, high = (np.asarray(b, dtype=float).reshape(-1) for b in bounds)
        if low.shape != (dim,) or high.shape != (dim,) or not np.all(low <= high):
            raise ValueError(f"refine: bounds must be (low, high) with {dim} coordinates "
                             f"each and low <= high")
        if not space.vertex_dofs:
            raise ValueError("refine: bounds need an order-1 shape space (its dofs the "
                             "vertex displacements)")
        # dof k·nv + i is component k of vertex i (VectorH1 of order 1: tests/shape)
        self.dofs = np.arange(dim * mesh.nv).reshape(dim, mesh.nv).T
        self.points = np.array([v.point for v in mesh.vertices], dtype=float)[:, :dim]
        self.low, self.high, self.held = low, high, space.held[self.dofs]
        self.tol = ACTIVE_TOL * float(np.max(high - low))

    def active(self, values, theta) -> np.ndarray:
        """The dof mask of the active set at the shape ``values``: the vertex coordinates on
        a side of the box (to :data:`ACTIVE_TOL` of its size) that ``theta`` moves out."""
        moved = self.points + np.asarray(values, dtype=float)[self.dofs]
        step = np.asarray(theta, dtype=float)[self.dofs]
        out = (((moved >= self.high - self.tol) & (step > 0))
               | ((moved <= self.low + self.tol) & (step < 0)))
        mask = np.zeros(len(values), dtype=bool)
        mask[self.dofs[out]] = True
        return mask

    def project(self, values) -> np.ndarray:
        """The coefficients with every free vertex coordinate clipped into the box."""
        out = np.array(values, dtype=float)
        moved = self.points + out[self.dofs]
        clipped = np.clip(moved, self.low, self.high) - self.points
        out[self.dofs] = np.where(self.held, out[self.dofs], clipped)
        return out


def _say(say: Callable[[str], None] | None, line: str) -> None:
    if say is not None:
        say(line)
