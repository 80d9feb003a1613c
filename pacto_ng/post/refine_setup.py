"""What a refinement of a finished run's part is set up from (:mod:`.refine_run`,
:mod:`.refine_check`): the run checked for what a refinement needs (a wall pressure, an
output port, an objective the refinement takes), its part made as ``pacto analyse`` makes it,
the loading (the run's, or another: :class:`Loading`), and on any mesh of the part its
:class:`~pacto_ng.shape.gradient.PartResponse` and :class:`~pacto_ng.shape.deformation.
ShapeSpace` with the run's supports and ports (:func:`shape_response`)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..errors import InputError
from ..physics.walls import solid_boundaries
from ..shape import PartResponse, ShapeSpace, volume
from .analysis_options import analysis_params
from .finish import say
from .part import make_part, part_ports, present_supports
from .part_stage import PART_MAXH, PART_ORDER
from .runs import copy_gridfunction, rebuild

#: the run objectives refined, each with whether its mechanism ratio Δ/SE is held: the
#: refinement raises Δ, and for a mechanism (a run minimising -Δ/SE) keeps Δ/SE at least
#: the part's own, so that the run's objective is not worsened either (raising Δ/SE alone
#: stiffens the part and lowers Δ: -15 % on pneunet, -5 % on pa-inverter, measured)
REFINED = {"mechanism": True, "output": False}


@dataclass(frozen=True)
class Loading:
    """What a user may change of the run's loading for the refinement (None: the run's own):
    the material ``model``, the inlet pressure ``load`` and its ``kind`` (``fixed`` or
    ``follower``); ``contact``: the part's walls in frictionless self-contact
    (:mod:`pacto_ng.shape.contact_term`)."""

    model: str | None = None
    load: float | None = None
    kind: str | None = None
    contact: bool = False


def refinement(run, quiet: bool, what: str, loading: Loading = Loading()):
    """``(Part, Job)``: the part of the finished run ``run`` (:func:`~.runs.load_run`) as
    ``pacto analyse`` makes it, and what its refinement shares on every mesh, at the run's
    loading or ``loading``; InputError (one line) for a run the refinement does not apply
    to.  Prints the set-up's lines (``what``: the task, e.g. "20 steps")."""
    if loading.load is not None and not (math.isfinite(loading.load) and loading.load > 0):
        raise InputError(f"--load: must be a positive pressure, got {loading.load:g}")
    setup, kind, objective = _checked(run, loading.kind)
    load = loading.load or float(run.summary.get("load_reached") or run.load)
    problem = rebuild(run)
    dim = problem.mesh.dim
    params = analysis_params(run.params, loading.model, PART_ORDER[dim])
    walls = ", the walls in self-contact" if loading.contact else ""
    say(quiet, f"refine {run.path}: {run.case.name}, model {params.model}, {kind} "
               f"pressure {load:g} {run.case.load_unit}{walls}, {what}")
    part, maxh = _part(run, problem, setup)
    job = Job(setup, params, load, kind, maxh, _bounds(problem.mesh), REFINED[objective],
              loading.contact)
    say(quiet, f"  the part: {part.mesh.ne} elements, maxh {maxh:.4g} m, order "
               f"{job.params.order}, volume {volume(part.mesh, job.thickness(dim)):.4g} m³ "
               f"(the bound)")
    return part, job


@dataclass(frozen=True)
class Job:
    """What every mesh of one refinement shares: the case's set-up, the analysis parameters,
    the load and its kind, the part's element size and the run's design domain (its lowest
    and highest corner)."""

    setup: object
    params: object
    load: float
    kind: str
    maxh: float
    domain: tuple
    hold_ratio: bool
    contact: bool = False  # the part's walls in self-contact (--contact)

    def thickness(self, dim: int) -> float:
        """The part's thickness: the run's for a 2D part (its volume is thickness × area),
        1 in 3D."""
        return float(self.params.thickness) if dim == 2 else 1.0


def shape_response(mesh, job: Job):
    """``(PartResponse, ShapeSpace)`` of the part: the run's supports, ports and pressure;
    the clamp and the ports held (a port's spring spread about it with its support), the
    symmetry lines held in their normal component; with
    ``job.contact`` every boundary of the solid in self-contact."""
    supports = present_supports(job.setup.supports, mesh)
    ports = part_ports(job.setup)
    regions = set(mesh.GetBoundaries()) | set(mesh.GetBBoundaries())
    held = tuple(dict.fromkeys(supports.clamp + tuple(p.region for p in ports
                                                      if p.region in regions)))
    hold = replace(supports, clamp=held)
    try:
        response = PartResponse(mesh, params=job.params, supports=supports, ports=ports,
                                pressure=job.load, kind=job.kind)
        supports_of_springs = tuple(sp.support(mesh) for p in ports for sp in p.springs())
        space = ShapeSpace(mesh, hold=hold,
                           near=tuple(b for b in supports_of_springs if b is not None))
        if job.contact:
            response.use_contact(space, solid_boundaries(mesh))
    except ValueError as err:
        raise InputError(f"refine: the part cannot be refined: {err}") from None
    return response, space


def _checked(run, kind: str | None):
    """``(Setup, load type, the run's objective)`` of a run the refinement applies to, the
    load type ``kind`` or the run's; InputError (one line) otherwise, before anything is
    rebuilt."""
    setup = run.case.make_setup(run.params)
    if kind is not None and kind not in ("fixed", "follower"):
        raise InputError(f"--load-type: must be fixed or follower, got '{kind}'")
    kind = kind or run.params.load_type
    reason = refuses(run, setup, kind)
    if reason:
        raise InputError(f"refine: {reason}")
    return setup, kind, run.params.objective or setup.objective


def refuses(run, setup=None, kind: str | None = None) -> str | None:
    """Why the refinement does not apply to the finished run ``run`` (its case's ``setup``,
    the load type ``kind``; both the run's by default), or None when it does: it refines a
    pressure case (fixed or follower) with an output port for Δ or Δ/SE."""
    setup = setup or run.case.make_setup(run.params)
    kind = kind or run.params.load_type
    if setup.pressure is None or kind not in ("fixed", "follower"):
        return (f"case '{run.case.name}' has no wall pressure to refine for (the refinement "
                f"applies to pressure cases, fixed or follower)")
    if not setup.ports:
        return f"case '{run.case.name}' has no output port"
    objective = run.params.objective or setup.objective
    if objective not in REFINED:
        return (f"the run's objective '{objective}' is not refined (the refinement takes "
                f"{' and '.join(REFINED)})")
    return None


def _part(run, problem, setup):
    """``(Part, maxh)``: the run's part as ``pacto analyse RUN`` makes it at its defaults."""
    maxh = PART_MAXH[problem.mesh.dim] * float(problem.h)
    part = make_part(problem, setup, threshold=0.5, maxh=maxh, threshold2=0.5, connect=True,
                     pressure=copy_gridfunction(problem.pressure_block.pressure), p_in=run.load,
                     mesh_time_limit=run.params.mesh_time_limit)
    return part, maxh


def _bounds(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest vertex coordinates of ``mesh`` (m)."""
    points = np.array([v.point for v in mesh.vertices])
    return points.min(axis=0), points.max(axis=0)


def part_size(mesh) -> float:
    """The part's size: its bounding box's largest side (m)."""
    low, high = _bounds(mesh)
    return float(np.max(high - low))
