"""A new design's equilibrium reached from the last design's, along the straight path between
the two designs (and their load factors).

An optimiser's step changes a design by up to its move limit in every variable; with a
projection of β 32-64 that turns elements from void to solid and back.  Newton from the last
equilibrium at the full load then may diverge on a large-deformation model, and a load ramp
from zero costs 8-16 load steps (Wang cantilever-3d, about 100 Newton iterations against 6 for
a warm start that works, docs/studies.md "The design path").  Along the path instead, every
point starts from an equilibrium of a design near its own: the fields are blended,
``(1 - t) old + t new``, and the load factor with them, and :func:`~pacto_ng.physics.newton.
ramp_load` steps ``t`` from 0 to 1 as it steps a load (halving a step that fails, growing one
that converges easily).  Any ``t = 1`` it reaches is an equilibrium of the new design: the
path changes the cost, not the result.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .newton import NewtonResult, NewtonSettings, ramp_load

#: the path gives up (a load ramp from zero takes over) when its step falls below this
#: fraction of the path, or after this many Newton iterations: where Newton meets a wall
#: along it (a Neo-Hookean cantilever-3d's void crushing, 2026-12-07) the path spent 84-117
#: iterations before failing; those that arrived took up to 22 on cantilever-3d (Wang)
PATH_MIN_STEP = 1.0 / 64
PATH_MAX_ITER = 60


class DesignPath:
    """The equilibrium problem of :class:`~pacto_ng.physics.equilibrium.Equilibrium` ``eq``
    along the path from the field values ``old`` at load factor ``loads[0]`` to ``new`` at
    ``loads[1]`` (``values``: the new fields as the forward pass was given them, set as they
    are at ``t = 1``): Newton's ``load`` argument is the path's parameter ``t``."""

    def __init__(self, eq, old: list, new: tuple[list, tuple], loads: tuple[float, float]):
        self.eq, self.old, (self.new, self.values), self.loads = eq, old, new, loads
        self.free = eq.free
        self._t = None

    def at(self, t: float) -> float:
        """Set the fields at ``t`` (once per ``t``); the load factor there."""
        if t != self._t:
            self.eq.set_fields(*(self.values if t == 1.0 else
                                 [(1.0 - t) * a + t * b for a, b in zip(self.old, self.new)]))
            self._t = t
        return self.loads[0] + t * (self.loads[1] - self.loads[0])

    def residual(self, vec, out, t):
        self.eq.residual(vec, out, self.at(t))

    def assemble_tangent(self, vec, t):
        self.eq.assemble_tangent(vec, self.at(t))

    def solve_tangent(self, rhs, out):
        self.eq.solve_tangent(rhs, out)

    def admissible(self, vec) -> bool:
        return self.eq.admissible(vec)


def field_values(fields) -> list:
    """Copies of the values of the block's fields (:class:`~pacto_ng.physics.mechanics.Field`)."""
    return [f.gf.vec.FV().NumPy().copy() for f in fields]


def follow(eq, u, old: list, new: tuple[list, tuple], loads: tuple[float, float],
           s: NewtonSettings) -> NewtonResult:
    """Bring ``u``, an equilibrium at the fields ``old`` and load factor ``loads[0]``, to one
    at ``new`` (the values' copies, :func:`field_values`, and the values given) and
    ``loads[1]`` along the path (its first step half of it: the caller's warm start was the
    whole).  The fields are left at the new ones either way; on failure ``u`` holds the path's
    last equilibrium and ``reason`` says why."""
    path = DesignPath(eq, old, new, loads)
    path.at(1.0)
    ref = eq.load_norm(loads[1])
    result = NewtonResult(False)
    if not np.isfinite(ref) or ref == 0.0:
        result.reason = "no finite load at the new design"
        return result
    steps = replace(s, min_increment=max(s.min_increment, PATH_MIN_STEP),
                    max_total_iter=PATH_MAX_ITER)
    ramp_load(path, u, (0.0, 1.0, ref), 0.5, steps, (False, None, None), result)
    path.at(1.0)
    # the path's t is no load factor: the load reached is the target's or none, and its first
    # step no load ramp's first increment
    result.load_reached = loads[1] if result.converged else 0.0
    result.ramp_first = None
    return result
