"""Every run ends with its part: made, checked for a seal, analysed, reported.

After the optimisation, :func:`finish_run` makes the part of the reported design
(:func:`~.part.make_part`: threshold, remesh, the chambers checked), analyses it at the run's
load with the run's own model and load type (:class:`~.part_analysis.PartAnalysis`: the
pressure on the wetted walls, fixed or following the deformation, as the run's Darcy load
was) and writes into the run folder:

=================  ===========================================================================
``part.stl``       the part, closed, whole (mirrored about the symmetry lines or planes), in mm
``part.png``       the part deformed at the run's load, true scale, over its undeformed outline
``summary.json``   ``part`` (below) and ``sealed`` added
=================  ===========================================================================

``part`` holds: ``made`` (False with ``why`` when there is no part), the threshold and how it
was chosen, the part's area (2D) or volume (3D) against the design's material, the seal (each
chamber, and where a leaking one opens), the analysis (kind, model, order, elements, the
output displacement Δ at the ports and each port's displacement vector), ``gap`` =
(Δ_part − Δ_design)/|Δ_design| with the design analysed at the part's order on the run's
mesh (``output_displacement_design``, ``design_order``; runs optimise at order 1, whose
elements are stiffer: in 3D the design moves 8–38 % more at order 2), ``gap_to_run``
against the run's own figure (``output_displacement_run`` at ``run_order``), and
``warnings`` (an output point the part does not reach, a port that moves more across its
direction than along it).
The run's last line says in words whether the part works and what to change when it does not.

The part's analysis is of order 2, on triangles of half the design's element size (2D) or on
tetrahedra of the design's element size (3D; ``pacto analyse`` gives the full study).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
from ngsolve import VOL, ElementId

from ..errors import InputError
from ..files import atomic_write_text
from ..physics.contact import SelfContact
from ..physics.equilibrium import NewtonFailure
from ..physics.loads import named_points, point_of
from ..physics.walls import solid_boundaries
from ..resources import duration
from .domain import symmetry_line
from .mirror3d import mirror_surface, symmetry_planes
from .part import Part, make_part, part_ports, present_supports
from .part2d import part_mesh, write_part_stl as write_stl_2d
from .part3d import write_part_stl as write_stl_3d
from .part_analysis import CONTACT_REACH, PartAnalysis
from .part_resources import TIME_LIMIT, contact_seconds
from .pictures import plot_deformed
from .plots3d import deformed_picture
from .runs import at_order, copy_gridfunction, design_delta

#: a part whose output moves further than this from the design's (relative) is not "as
#: designed" (the issue's figure: ±20 %)
GAP_LIMIT = 0.2
#: a linear analysis whose largest displacement passes this share of the part's size (its
#: bounding box's largest side) is beyond small strains and rotations (measured at defaults:
#: the built-in cases' parts at most 0.040, pneunet's; tests/cases/user_finger.py's 1.57)
LINEAR_LIMIT = 0.1
#: the part's element size and displacement order, by dimension
PART_MAXH = {2: 0.5, 3: 1.0}  # times the design's element size
#: order 2 in 3D too: on pa-inverter-3d's part order-1 tetrahedra were 12 points stiffer
#: (gap -20.7 % at order 1, -8.4 % at order 2, -6.5 % at order 2 on 0.7 h)
PART_ORDER = {2: 2, 3: 2}


def finish_run(path, problem, summary: dict, *, quiet: bool = False) -> dict:
    """Make, check and analyse the part of the design ``problem`` holds (a finished run's,
    its final design analysed), write ``part.stl``, ``part.png`` and the ``part`` entry of
    ``path/summary.json``; print the run's last line.  Returns the updated summary."""
    path = Path(path)
    t0 = time.perf_counter()

    def say(what: str) -> None:  # one line per step of the part's making
        if not quiet:
            print(f"  part: {what} ({time.perf_counter() - t0:.1f} s)", flush=True)

    try:
        part, analysis = _part_and_analysis(path, problem, summary, say)
        entry = dict(made=True, **part.summary(), **analysis)
    except InputError as err:
        entry, part = {"made": False, "why": str(err)}, None
    entry["wall_time_s"] = time.perf_counter() - t0
    summary = dict(summary, part=entry, sealed=entry.get("sealed"))
    atomic_write_text(path / "summary.json", json.dumps(summary, indent=1))
    line = last_line(summary, path)
    if not quiet or not _works(entry):
        print(line, flush=True)
    return summary


def _part_and_analysis(path, problem, summary, say):
    """``(Part, analysis entry)``: the part made and written, analysed at the run's load;
    ``say(what)`` reports each step."""
    params, setup = problem.params, problem.setup
    pressure = problem.pressure_block
    part = make_part(problem, setup, maxh=PART_MAXH[problem.mesh.dim] * problem.h,
                     pressure=None if pressure is None else copy_gridfunction(pressure.pressure),
                     p_in=params.load, mesh_time_limit=params.mesh_time_limit)
    write_part_stl(path / "part.stl", part, problem)
    say(f"made, {part.mesh.ne} elements"
        + ("" if part.sealed is None else ", sealed" if part.sealed else ", NOT sealed"))
    if pressure is None or not setup.ports:
        return part, {"analysed": False,
                      "why_not_analysed": "the part is analysed for pressure cases with an "
                                          "output port"}
    return part, _analyse(path, part, problem, summary, say)


def _analyse(path, part: Part, problem, summary, say) -> dict:
    """The part at the run's load (the load it reached) with the run's model and load type."""
    params, setup = problem.params, problem.setup
    load = float(summary.get("load_reached") or params.load)
    order = PART_ORDER[part.dim]
    kind = params.load_type
    ports = part_ports(setup)
    ana, point = _solved(part, problem, (load, kind, order), say=say)
    say(f"analysed at {load:.4g} {problem.case.load_unit} ({kind}, {ana.model}, order {order})"
        + ("" if point.converged else ": no equilibrium"))
    contact, (ana, point) = _with_contact(part, problem, (ana, point), (load, kind, order), say)
    entry = {"analysed": True, "kind": kind, "model": ana.model, "order": order,
             "formulation": ana.formulation, "load": load, "converged": point.converged,
             "load_reached": load * point.load_reached,
             "newton_iterations": point.iterations, "min_J": _num(point.min_j),
             "output_displacement": _num(point.delta),
             "ports": {p.region: {"along": _num(a), "vector": [_num(c) for c in v]}
                       for p, a, v in zip(ports, point.ports, point.vectors)}}
    run_delta = summary.get("output_displacement")
    design = _design_at(problem, order, run_delta)
    if int(problem.params.order) != order:
        say(f"the design analysed at order {order} on its own mesh")
    entry.update(output_displacement_design=design, design_order=order,
                 output_displacement_run=run_delta, run_order=int(params.order))
    entry["gap"] = (None if not point.converged or not design else
                    (point.delta - design) / abs(design))
    entry["gap_to_run"] = (None if not point.converged or not run_delta else
                           (point.delta - run_delta) / abs(run_delta))
    entry["contact"] = contact
    entry["warnings"] = (_warnings(part, problem, ports, point) + _overlap_warning(contact, path)
                         + ([] if point.converged else crushed_at_port(ana, ports)))
    if point.converged and ana.model == "linear":
        entry["warnings"] += beyond_linear(part.mesh, point.max_u)
    if point.converged:
        title = (f"{problem.case.name} part, {load:.3g} {problem.case.load_unit} {kind}, "
                 f"{ana.model} (true scale)")
        u, touch = ana.mech.u, None
        if ana.mech.contact is not None:  # analysed in contact: its walls' vertices marked
            points, pressures = ana.mech.contact.pressures(u.vec)
            touch = points[pressures > 0]
        if part.dim == 2:
            plot_deformed(path / "part.png", part.mesh, u, title=title,
                          mirror=symmetry_line(problem.mesh) or False, contact=touch)
        else:
            deformed_picture(path / "part.png", part.mesh, u, title=title, contact=touch)
    return entry


def _solved(part: Part, problem, loading: tuple, contact: tuple = (), say=None):
    """``(PartAnalysis, SweepPoint)``: the part solved at ``loading`` = (load, kind, order)
    with the run's model, the walls ``contact`` in self-contact; ``say`` gets the progress
    lines of a long load ramp."""
    ana = _analysis(part, problem, loading, contact, say)
    return ana, ana.solve(loading[0])


def _analysis(part: Part, problem, loading: tuple, contact: tuple, say) -> PartAnalysis:
    """The part's :class:`PartAnalysis` of :func:`_solved`, not solved yet."""
    load, kind, order = loading
    setup = problem.setup
    try:
        ana = PartAnalysis(part.mesh, kind, params=problem.params.replace(order=order),
                           supports=present_supports(setup.supports, part.mesh),
                           ports=part_ports(setup), contact=contact)
    except ValueError as err:
        raise InputError(f"the part cannot be analysed: {err}") from None
    ana.mech.on_step = load_ramp_progress(say, load, problem.case.load_unit)
    return ana


#: the part's load ramp says each step it reaches once its analysis has taken this long (s)
PROGRESS_AFTER = 5.0


def load_ramp_progress(say, load: float, unit: str):
    """``on_step(load factor, state)`` of the part's analysis: one line per load step of
    Newton's ramp reached after :data:`PROGRESS_AFTER` seconds (None without ``say``)."""
    if say is None:
        return None
    start = time.perf_counter()

    def step(factor, _state):
        seconds = time.perf_counter() - start
        if seconds >= PROGRESS_AFTER and factor < load:
            say(f"reached {factor:.4g} of {load:.4g} {unit} on the load ramp")
    return step


#: the quadrature order of the walls' probe (:func:`walls_probe`) on a 3D part's faces: one
#: point per face.  On the slotted slab squeezed shut (tests/contact_parts.py, 6098
#: tetrahedra) it found an overlap of 0.0875 m² in 1.0 s against 0.0836 m² in 11.4 s at the
#: contact's order 6; order 2 reported spurious overlaps of 1e-6 m² on the undeformed
#: pneunet-3d part, orders 1 and 6 none (2026-12-06)
PROBE_INTORDER_3D = 1
#: ... and the walls of a 3D part are said to pass through each other where they overlap
#: deeper, on the mean, than this share of the part's largest displacement: pa-inverter-3d's
#: part, whose walls touch as made, overlaps 3.2e-6 m² to 0.11 % of its motion at its load
#: and at three times it (the same area, pressed in with the load: not walls that close);
#: the squeezed slotted slab (tests/contact_parts.py, 1213 tetrahedra, 3 kPa) to 54 % of it
PROBE_DEPTH_3D = 0.01


def _with_contact(part: Part, problem, solved: tuple, loading: tuple, say):
    """``(entry, (PartAnalysis, SweepPoint))``: where the part's walls pass through each
    other at the solved state (:func:`walls_probe`), the part solved again with its walls in
    self-contact, whose figures are then the part's (``entry``: the overlap and Δ without
    contact, whether the part was analysed in contact and whether that solve converged).
    One Newton iteration with contact is timed first: where even the fewest Newton
    iterations a pressure takes with contact (:func:`~.part_resources.contact_seconds`)
    would pass the analyses' time limit, the part is not solved again and the last line says
    what it would take.  ``entry`` is None where the walls do not meet."""
    ana, point = solved
    if not point.converged:
        return None, solved
    walls, u = solid_boundaries(part.mesh), ana.mech.u.vec
    probe = walls_probe(ana, walls)
    if part.dim == 2:
        overlap = probe.overlap(u)
    else:
        overlap, depth = probe.overlap_depth(u)
        if depth <= PROBE_DEPTH_3D * point.max_u:
            overlap = 0.0  # walls that touch as made, pressed a little into each other
    if not overlap > 0.0:
        return None, solved
    entry = {"overlap_without": overlap, "output_displacement_without": _num(point.delta)}
    again = _analysis(part, problem, loading, walls, say)
    low, high = contact_seconds(again.iteration_seconds(), 1)
    entry["analysed"] = bool(low <= TIME_LIMIT)
    said = f"its walls pass through each other there (overlap {overlap:.3g} m²)"
    if not entry["analysed"]:
        entry["estimate"] = f"{duration(low)} to {duration(high)}"
        say(f"{said}: not analysed again with them in contact ({entry['estimate']})")
        return entry, solved
    say(f"{said}: analysed again with them in contact ({duration(low)} to {duration(high)})")
    point = again.solve(loading[0])
    entry["converged"] = bool(point.converged)
    if not point.converged:
        say("no equilibrium with the walls in contact")
        return entry, solved
    return entry, (again, point)


def walls_probe(ana: PartAnalysis, walls) -> SelfContact:
    """The self-contact of the part's ``walls`` (the boundaries of its solid) that probes them
    in the analysis ``ana``: its :meth:`~pacto_ng.physics.contact.SelfContact.overlap` (one
    pairing) or :meth:`~pacto_ng.physics.contact.SelfContact.overlap_depth` (two) of
    ``ana.mech.u.vec`` (a stiffness of 1 / h, which plays no part in them); on the
    displacement's space (of the mixed state too), on a 3D part at :data:`PROBE_INTORDER_3D`."""
    space = ana.mech.u.space
    return SelfContact.on_walls(space, walls, modulus=1.0, penalty=1.0, reach=CONTACT_REACH,
                                thickness=ana.thickness,
                                intorder=PROBE_INTORDER_3D if space.mesh.dim == 3 else None)


def _overlap_warning(contact, path) -> list[str]:
    """The warning for walls that pass through each other and were not analysed in contact."""
    if contact is None or contact.get("converged"):
        return []
    overlap = f"its walls pass through each other in this analysis (overlap " \
              f"{contact['overlap_without']:.3g} m²)"
    if not contact["analysed"]:
        return [overlap + f", not analysed in contact (it would take {contact['estimate']}): "
                          f"'pacto analyse {path} --contact --time-limit S' does"]
    return [overlap + f": 'pacto analyse {path} --contact' sweeps the pressure up to it with "
                      f"them in contact"]


def _design_at(problem, order: int, run_delta):
    """The design's Δ at the part's order (:func:`~.runs.at_order`; the run's own figure
    when it has that order); None when the design has no equilibrium there."""
    if int(problem.params.order) == order:
        return run_delta
    try:
        return _num(design_delta(at_order(problem, order)))
    except NewtonFailure:
        return None


def _num(v):
    return None if v is None or not np.isfinite(v) else float(v)


def beyond_linear(mesh, max_u: float) -> list[str]:
    """A linear analysis whose motion is not small against the part: its figures do not hold
    (the design's neither: it was made with the same model)."""
    points = np.array(mesh.ngmesh.Coordinates())[:, :mesh.dim]
    size = float(np.max(points.max(axis=0) - points.min(axis=0)))
    if not max_u > LINEAR_LIMIT * size:
        return []
    return [f"the part moves up to {max_u:.3g} m, {max_u / size:.0%} of its size "
            f"({size:.3g} m): beyond small strains and rotations, where the linear model's "
            f"figures do not hold (run the case with --model neohookean, or --model auto)"]


def crushed_at_port(ana: PartAnalysis, ports) -> list[str]:
    """Where the part's analysis stopped short of its load with its lowest ``det F`` (at the
    last equilibrium it reached) at a port whose spring acts at one point, within two of
    that element's sizes: the line that says so.  A force at a point has no finite
    displacement, and the part's elements there, finer than the design's, are crushed
    (gripper-silicone's part with its former point spring: docs/benchmarks.md)."""
    low = ana.mech.lowest_jacobian()
    mesh = ana.mesh
    corners = np.array([mesh[v].point for v in mesh[ElementId(VOL, low["element"])].vertices])
    size = max(float(np.linalg.norm(a - b)) for a in corners for b in corners)
    for port in ports:
        if port.spring > 0 and not port.spread and port.region in named_points(mesh):
            if np.linalg.norm(corners.mean(axis=0) - point_of(mesh, port.region)) <= 2 * size:
                return [f"its lowest det F ({low['J']:.2g}, at the last equilibrium) lies at the "
                        f"output '{port.region}', whose spring acts at one point: a force at a "
                        f"point crushes the part's elements there, finer than the design's (a "
                        f"case file can spread it, Spring(..., spread=r), or put it on a named "
                        f"edge of solid: docs/guide.md)"]
    return []


def _warnings(part: Part, problem, ports, point) -> list[str]:
    """What a user must know of the part beyond its figures."""
    out = []
    for region, (src, new) in part.ports.items():
        shift = float(np.linalg.norm(np.subtract(new, src)))
        if region in {p.region for p in ports} and shift > 2.0 * problem.h:
            out.append(f"the part does not reach the output point '{region}': its nearest "
                       f"vertex is {shift:.3g} m away (the output ends in void)")
    if point.converged:
        for port, along, vec in zip(ports, point.ports, point.vectors):
            d = np.asarray(port.direction, dtype=float)
            d /= np.linalg.norm(d)
            v = np.asarray(vec, dtype=float)
            across = float(np.linalg.norm(v - (v @ d) * d))
            if across > abs(along):
                out.append(f"the output '{port.region}' moves more across its direction "
                           f"({across:.3g} m) than along it ({along:.3g} m): the objective "
                           f"leaves that motion free")
    return out


def write_part_stl(path, part: Part, problem):
    """The part, closed and whole (mirrored about the symmetry lines or planes of
    ``problem.mesh``), in mm; ``problem`` needs ``mesh``, ``case.name`` and
    ``params.thickness`` (a run's problem, or :class:`~.finish.Subject`)."""
    name = problem.case.name
    if part.dim == 2:
        line = symmetry_line(problem.mesh)
        t = float(problem.params.thickness)
        write_stl_2d(path, part_mesh(part.mesh, line), t, units="mm",
                     header=f"pacto_ng {name} part, thickness {t * 1e3:g} mm"
                            + (", whole (mirrored)" if line is not None else ""))
    else:
        planes = symmetry_planes(problem.mesh)
        surface = part.pieces[0].surface
        write_stl_3d(path, mirror_surface(surface, planes) if planes else surface, "mm",
                     header=f"pacto_ng {name} part (3D)" + (", whole (mirrored)"
                                                            if planes else ""))


def _works(entry: dict) -> bool:
    return bool(entry.get("made")) and entry.get("sealed") is not False and (
        entry.get("gap") is None or abs(entry["gap"]) <= GAP_LIMIT) and not entry.get("warnings")


def last_line(summary: dict, path) -> str:
    """The run's last line: whether the part works, in words, and what to change."""
    part = summary.get("part") or {}
    if not part.get("made"):
        return f"part: none was made ({part.get('why', 'not asked')}) — {path}"
    head = "part"
    bits = []
    if part.get("sealed") is False:
        chambers = [c for c in part["seal"]["chambers"] if not c["sealed"]]
        where = (f"chamber '{chambers[0]['name']}' is open to '{chambers[0]['boundary']}' near "
                 f"({', '.join(f'{c:.3g}' for c in chambers[0]['opening'])}) m")
        bits.append(f"NOT SEALED: {where}, it will not hold pressure (keep a wall around the "
                    f"inlet: --set inlet_wall=<one element size, m>; or limit the leak: "
                    f"--set leak_max=1e-3)")
    elif part.get("sealed"):
        bits.append("sealed")
    if part.get("analysed"):
        unit = summary.get("load_unit", "")
        if not part["converged"]:
            reached = part.get("load_reached")
            bits.append(f"its {part['kind']} analysis at {part['load']:.4g} {unit} did not "
                        f"converge" + ("" if reached is None else
                                       f" (equilibria up to {reached:.4g} {unit})"))
        else:
            d, e = part["output_displacement"], part["output_displacement_design"]
            text = f"moves {d:.4g} m at {part['load']:.4g} {unit}"
            touch = part.get("contact") or {}
            if touch.get("converged"):
                text += (f" with its walls in contact (passing through each other: "
                         f"{touch['output_displacement_without']:.4g} m)")
            if part.get("gap") is not None:
                text += f" against the design's {e:.4g} m ({100 * part['gap']:+.1f} %)"
                if part.get("run_order", part["order"]) != part["order"]:
                    text += (f" at order {part['order']}, as the part (the run's order-"
                             f"{part['run_order']} analysis: {part['output_displacement_run']:.4g}"
                             f" m)")
                if abs(part["gap"]) > GAP_LIMIT and touch.get("converged"):
                    text += (" — not as designed: its walls touch, which the design's analysis "
                             f"lets pass through each other ('pacto refine {path} --contact' "
                             "refines the part with them in contact)")
                elif abs(part["gap"]) > GAP_LIMIT:
                    robust = (summary.get("parameters") or {}).get("robust")
                    text += (" — not as designed: " + (
                        f"'pacto analyse {path}' tells where the gap comes from" if robust
                        else "--set robust=1 designs hinges the part keeps")
                        + " (docs/guide.md, 'The part')")
            bits.append(text)
    elif part.get("why_not_analysed"):
        bits.append(f"made, not analysed ({part['why_not_analysed']})")
    bits += part.get("warnings", [])
    return f"{head}: " + "; ".join(bits) + f" — {path}/part.stl"
