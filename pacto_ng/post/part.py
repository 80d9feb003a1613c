"""The part of a design: thresholded, remeshed body-fitted, its chambers checked for a seal.

One entry point, :func:`make_part`, for 2D and 3D; only "make the part" and "remesh it" differ
by dimension:

* 2D: the threshold is chosen by :func:`~.threshold_choice.choose_threshold` (lowered until
  the part kept on the clamp holds every output point, where a grey joint would cut it off),
  the iso-line of the nodal density is traced (:func:`~.threshold.threshold`) and meshed with
  Netgen triangles on the case's own geometry (:func:`~.remesh.remesh`); a part Netgen cannot
  mesh is retried a little below the threshold;
* 3D: the iso-surface of the nodal density is clipped, smoothed (:func:`~.part3d.part3d`) and
  meshed with Netgen tetrahedra (:func:`~.remesh3d.remesh_part`); a part that misses an
  output face or point is made again at lower thresholds.

Both carry the case's boundary and point names over (the supports, ports and springs act on
the part by name) and name the wetted chamber walls ``pressure`` (the wetting rule of
:mod:`.remesh`).  Every pressure part's chambers are checked on the design it was cut from
(:func:`~.seal.check_seal`: the void of the thresholded nodal field, the very field the part
is cut from, must not lead from an inlet to a zero-pressure boundary).  The remeshed part is
not checked again: its boundary names cannot tell a chamber beyond an inlet on the domain's
edge (whose wall meets the zero-pressure boundary at the domain's corner, sealed) from an open
one, and the remesh follows the clipped iso-line to within its spline tolerance.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..physics.loads import Port
from ..physics.mechanics import Supports
from .materials import material_areas
from .part3d import boundary_surface, part3d, void_regions
from .post3d import RHO2, split_materials, stiff_sampler
from .remesh3d import PRESSURE, remesh_part
from .remesh import remesh
from .runs import design_density, domain_of, materials_of
from .seal import Seal, design_seal, inlet_names
from .threshold import threshold as threshold_2d
from .threshold_choice import choose_threshold

#: a 2D part Netgen cannot mesh is retried at thresholds this much lower, this many times
MESH_RETRY_STEP, MESH_RETRIES = 0.005, 4
#: a 3D part that misses an output is made again at thresholds this much lower, down to
THRESHOLD_STEP_3D, THRESHOLD_FLOOR_3D = 0.05, 0.3


@dataclass
class Part:
    """A body-fitted part of a design (:func:`make_part`).

    Attributes
    ----------
    mesh : ngsolve.Mesh
        Triangles (2D) or tetrahedra (3D) of the solid: material ``solid`` (or ``soft`` and
        ``stiff``), boundaries named as the case's where they lie on its boundaries, the wetted
        chamber walls ``pressure``, the rest ``free``; the case's named points on their nearest
        vertices.
    dim : int
    threshold : float
        The density threshold the part was cut at.
    choice : dict
        What was asked, what was used and why (``requested``, ``used``, ``lowered``, ``note``).
    measure, design_measure : float
        The part's area (2D) or volume (3D), and the design's material ``Σ a ρ̄``.
    wetted : float
        Length (2D) or area (3D) of the ``pressure`` boundary.
    seal : Seal or None
        The chambers of the thresholded design (None: no pressure load).
    ports : dict
        Named point -> ``(source position, the part's vertex)``.
    pieces : object
        What the part was made of: 2D ``(Thresholded, Remeshed)``, 3D ``(Part3D, Remeshed3D)``.
    """

    mesh: object
    dim: int
    threshold: float
    choice: dict
    measure: float
    design_measure: float
    wetted: float
    seal: Seal | None
    geometry: str
    materials: str | None
    pieces: tuple
    ports: dict = field(default_factory=dict)

    @property
    def sealed(self) -> bool | None:
        """Every chamber closed off (None without a pressure load)."""
        return None if self.seal is None else self.seal.sealed

    def summary(self) -> dict:
        """The part as JSON: threshold and its choice, measures, seal, materials, mesh."""
        unit = "m²" if self.dim == 2 else "m³"
        return {"threshold": self.threshold, "threshold_note": self.choice.get("note"),
                "measure_unit": unit, "measure": self.measure,
                "design_measure": self.design_measure,
                "measure_vs_design": self.measure / self.design_measure - 1.0
                if self.design_measure > 0 else None,
                "wetted": self.wetted, "sealed": self.sealed,
                "seal": None if self.seal is None else self.seal.to_json(),
                "elements": self.mesh.ne,
                "geometry": self.geometry, "materials": self.materials,
                "material_measures": material_areas(self.mesh) if self.materials else None}

def part_ports(setup) -> tuple[Port, ...]:
    """The output ports of a set-up for a part's analysis: each with the springs of the
    set-up on its region along its direction as its own spring (Δ = Σ weight · d·u, as the
    optimisation reads it), spread as the set-up's port or spring is (the larger spread)."""
    out = []
    for port in setup.ports:
        d = np.asarray(port.direction, dtype=float)
        d = d / np.linalg.norm(d)
        k, spread = float(port.spring), float(port.spread)
        for s in setup.springs:
            sd = np.asarray(s.direction, dtype=float)
            sd = sd / np.linalg.norm(sd)
            if s.region == port.region and abs(abs(sd @ d) - 1.0) < 1e-12:
                k += float(s.stiffness)
                spread = max(spread, float(s.spread))
        out.append(Port(port.region, tuple(map(float, port.direction)), k, float(port.weight),
                        spread))
    return tuple(out)


def present_supports(supports: Supports, mesh) -> Supports:
    """The supports restricted to the regions the part has: a part need not touch every
    support of its domain (e.g. a symmetry plane)."""
    names = set(mesh.GetBoundaries()) | set(mesh.GetBBoundaries())
    if mesh.dim == 3:
        names |= set(mesh.GetBBBoundaries())
    keep = lambda group: tuple(n for n in group if n in names)  # noqa: E731
    return Supports(**{k: keep(v) for k, v in dataclasses.asdict(supports).items()})


def make_part(problem, setup, *, threshold=0.5, maxh: float | None = None,
              threshold2: float = 0.5, connect: bool = True, pressure=None,
              p_in: float | None = None, mesh_time_limit: float = 300.0) -> Part:
    """The part of the design ``problem`` holds (its ρ̄, analysed or not) for ``setup``.

    Parameters
    ----------
    problem : Problem
        The run's problem with the design's values (``rho_bar``; two materials ``rho_bar1``,
        ``rho_bar2``).
    setup : Setup
        The case's set-up: clamp, ports, passive regions, pressure boundaries.
    threshold : float or "volume"
        The density threshold (2D only: ``volume``, the volume-preserving one).
    maxh : float, optional
        The part's element size (default half the design's).
    threshold2 : float
        Two materials: where ρ̄2 makes the stiff material.
    connect : bool
        Lower the threshold until the part holds every output (a grey joint kept).
    pressure, p_in
        The design's Darcy pressure field and the inlet pressure, for the wetting rule.

    Raises
    ------
    InputError
        No part: nothing solid on the clamp, Netgen cannot mesh it.
    """
    rho = design_density(problem).copy()
    maxh = 0.5 * problem.h if maxh is None else float(maxh)
    ports = part_ports(setup)
    try:
        if problem.mesh.dim == 2:
            part = _part_2d(problem, setup, rho, threshold, maxh, threshold2, connect,
                            pressure, p_in, ports)
        else:
            part = _part_3d(problem, setup, rho, threshold, maxh, threshold2, connect,
                            pressure, p_in, ports, mesh_time_limit)
    except ValueError as err:
        raise InputError(str(err)) from None
    if setup.pressure is not None:
        # a part with no wetted wall is a part (its Darcy analysis still applies; the wall
        # pressure analyses refuse it, PartAnalysis)
        part.seal = design_seal(problem, setup, part.threshold,
                                exclude=part.choice.get("exclude", ()))
    return part


def _part_2d(problem, setup, rho, requested, maxh, threshold2, connect, pressure, p_in, ports):
    shape, exclude = domain_of(problem, setup)
    choice, th = choose_threshold(problem.mesh, rho, requested, [p.region for p in ports],
                                  setup.supports.clamp, connect=connect, exclude=exclude)
    th = reach_boundary_ports(problem.mesh, rho, choice, th, [p.region for p in ports],
                              setup.supports.clamp, connect=connect, exclude=exclude)
    choice["exclude"] = tuple(exclude)
    stiff, _ = materials_of(problem, setup, problem.params, threshold2, exclude)
    wet = dict(pressure=pressure, p_in=p_in, wet_boundaries=inlet_names(problem, setup))
    used = choice["used"]
    candidates = [t for t in (used - k * MESH_RETRY_STEP for k in range(MESH_RETRIES + 1))
                  if t > 0.0]
    for attempt, t in enumerate(candidates):
        if attempt:
            th = threshold_2d(problem.mesh, rho, t, exclude=exclude)
        try:
            rm = remesh(th, maxh, clamp=setup.supports.clamp, domain=shape, stiff=stiff, **wet)
            break
        except ValueError as err:
            if not str(err).startswith("Netgen could not mesh") or attempt + 1 == len(candidates):
                raise
    if t != used:
        choice.update(used=t, mesh_retries=attempt)
        choice["note"] += f"; Netgen could not mesh the part at {used:.4g}, meshed at {t:.4g}"
    return Part(rm.mesh, 2, t, choice, rm.area, float(problem.field.areas @ rho),
                rm.wetted_length, None, rm.geometry, rm.materials, (th, rm), rm.ports)


def reach_boundary_ports(mesh, rho, choice: dict, th, regions, clamp, *, connect: bool = True,
                         exclude=(), floor: float = 0.1, resolution: float = 0.005):
    """2D: the output ports on a *boundary* of ``mesh`` (an edge port: its mean is read),
    which :func:`~.threshold_choice.choose_threshold` does not check (it checks named
    points), must be touched by the part kept on ``clamp``.  When the part at the chosen
    threshold ``th`` misses one, the threshold is lowered by bisection, down to ``floor`` and
    to within ``resolution``, to the largest value at which every such port is touched (a
    lower threshold only adds solid, so the named points stay in the part).  ``choice`` (the
    record) is updated in place: ``boundary_ports`` (port -> touched), and ``used``,
    ``lowered`` and ``note`` when lowered.  Returns the Thresholded at the threshold used;
    ValueError when even ``floor`` misses a port (and ``connect``)."""
    edges = [r for r in regions if r in set(mesh.GetBoundaries())]
    if not edges:
        return th
    clamp = set(clamp)

    def missed(cand):
        kept = [c for c in cand.components if not clamp or c.names & clamp]
        return [r for r in edges if not any(r in c.names for c in kept)]

    miss = missed(th)
    if miss and connect:
        low = threshold_2d(mesh, rho, floor, exclude=exclude)
        if missed(low):
            raise ValueError(f"the part on the clamp does not reach the output boundary "
                             f"'{missed(low)[0]}' (thresholds {choice['used']:g} down to "
                             f"{floor:g})")
        lo, hi, start = floor, choice["used"], choice["used"]
        while hi - lo > resolution:
            mid = 0.5 * (lo + hi)
            cand = threshold_2d(mesh, rho, mid, exclude=exclude)
            if missed(cand):
                hi = mid
            else:
                lo, low = mid, cand
        choice["note"] += (f"; lowered to {lo:.4g} from {start:.4g}: there the part on the "
                           f"clamp does not reach the output boundary "
                           + ", ".join(f"'{r}'" for r in miss))
        th, miss = low, []
        choice.update(used=lo, lowered=True, part_area=th.area)
    elif miss:
        choice["note"] += (f"; the part on the clamp does not reach the output boundary "
                           f"'{miss[0]}' (not lowered: --keep-threshold)")
    choice["boundary_ports"] = {r: r not in miss for r in edges}
    points = choice.get("reaches_output")
    choice["reaches_output"] = not miss if points is None else bool(points and not miss)
    return th


def _part_3d(problem, setup, rho, requested, maxh, threshold2, connect, pressure, p_in, ports,
             mesh_time_limit):
    if requested == "volume":
        raise ValueError("--threshold volume is a 2D option: give a number in (0, 1)")
    mesh, start = problem.mesh, float(requested)
    exclude = void_regions(mesh, setup)
    two = setup.materials == 2
    wanted = [p.region for p in ports]
    ladder = [start] + ([t for t in np.arange(start - THRESHOLD_STEP_3D,
                                              THRESHOLD_FLOOR_3D - 1e-9, -THRESHOLD_STEP_3D)]
                        if connect else [])
    for t in ladder:
        solid = part3d(mesh, rho, float(t), clamp=setup.supports.clamp, exclude=exclude,
                       fields={RHO2: problem.values["rho_bar2"]} if two else None)
        unsmoothed = boundary_surface(solid.solid)
        if two:
            solid.solid = split_materials(solid.solid, threshold2)
        rm = remesh_part(solid.surface, mesh, maxh, problem.h, clamp=setup.supports.clamp,
                         exclude=exclude,
                         wet_boundaries=inlet_names(problem, setup),
                         pressure=pressure, p_in=p_in, timeout=mesh_time_limit,
                         stiff_at=stiff_sampler(solid.solid, threshold2) if two else None,
                         unsmoothed=unsmoothed)
        missing = [r for r in wanted if r not in rm.areas and r not in rm.ports]
        if not missing:
            break
    if missing:
        raise ValueError(f"the part does not reach the output '{missing[0]}' (thresholds "
                         f"{start:g} down to {ladder[-1]:.3g})")
    t = float(t)
    note = f"threshold {start:g}" + ("" if t == start else
                                    f" lowered to {t:.3g}: above it the part misses an output")
    if rm.maxh != maxh:
        note += f"; Netgen could not mesh the part at maxh {maxh:.4g}, meshed at {rm.maxh:.4g}"
    if rm.surface == "unsmoothed":
        solid.surface = unsmoothed  # the STL is the surface analysed
    if rm.surface != "remeshed":
        which = "smoothed" if rm.surface == "kept" else "unsmoothed"
        note += (f"; Netgen could not remesh the part's surface: its {which} iso-surface "
                 "kept as the boundary, the volume filled")
    choice = {"requested": requested, "used": t, "lowered": t != start, "note": note,
              "exclude": tuple(exclude)}
    volumes = problem.field.areas  # element volumes in 3D
    return Part(rm.mesh, 3, t, choice, rm.volume, float(volumes @ rho),
                rm.areas.get(PRESSURE, 0.0), None, "surface", rm.materials, (solid, rm),
                rm.ports)
