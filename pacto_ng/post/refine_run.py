"""``pacto refine RUN``: the part of a finished 2D pressure run, its shape refined.

What it does for a user: the run's part is made exactly as ``pacto analyse RUN`` makes it
(:func:`~.part.make_part` at threshold 0.5, lowered until the part reaches every output; half
the design's element size; displacement order 2), loaded as the run's own part is (the run's
model, the wall pressure at the load the run reached on the wetted walls ``pressure``, fixed
or following the deformation as the run's ``load_type``, the run's output ports and their
springs), and its boundary is then moved to make the output displacement Δ larger without
adding material (:func:`~pacto_ng.shape.refine.refine`: the volume bounded by the part's own
starting volume, which is what the design promised; every vertex kept in the bounding box of
the run's design domain, so that the part is no larger than the domain the user gave; a moved
mesh, no remeshing, the elements kept from folding).  The clamp, the output ports and the
case's symmetry lines do not move (a symmetry line slides along itself).

Written into ``RUN/refine/`` (refused when it exists, unless ``--overwrite``, which replaces
these files and nothing else):

=================  ===========================================================================
``history.csv``    one row per accepted shape (step 0 the part as made): step, delta (m),
                   volume (m³: area times thickness), det (the lowest Jacobian of the mesh's
                   motion), length (the step, m), merit
``summary.json``   status, Δ before and after, volume before, after and its bound, the lowest
                   Jacobian, steps, model, load type, load, the part's settings, warnings
                   (the refined part reaching out of the run's design domain beyond
                   round-off: the refinement keeps it in, so none is expected), wall time
``refined.vtu``    the refined part (points at their moved positions, m) with ``u`` (the
                   displacement at the run's load) and ``moved`` (the shape's motion)
``refined.png``    the part's outline before and after the refinement, in metres
=================  ===========================================================================

The statuses are those of :func:`~pacto_ng.shape.refine.refine`: ``steps`` (the asked steps
done), ``converged``, ``mesh_quality`` (the mesh would fold: remeshing would be needed) and
``no_descent``.  3D runs, runs without a pressure load or an output port, and output springs
on a boundary port are refused with one line.
"""
from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path

import numpy as np
from ngsolve import BND, VOL

from ..errors import InputError
from ..files import atomic_path, atomic_write_text
from ..physics.equilibrium import NewtonFailure
from ..physics.mechanics import Supports
from ..shape import PartResponse, ShapeSpace, refine, volume
from .analysis_options import analysis_params
from .finish import say
from .part import make_part, part_ports, present_supports
from .part_stage import PART_MAXH, PART_ORDER
from .post3d import is_3d
from .runs import copy_gridfunction, load_run, rebuild

#: the refinement's steps when ``--steps`` is not given
STEPS = 20
#: the first trial step of the boundary's motion, in the part's element sizes (maxh): the
#: largest is four times it (:func:`~pacto_ng.shape.refine.refine`), so that a step moves the
#: boundary by a few elements at most and a thin wall is not crossed in one step
STEP_SHARE = 1.0
#: the augmented Lagrangian's penalty μ on the relative volume excess
#: (:func:`~pacto_ng.shape.refine.refine`)
PENALTY = 1000.0
#: the columns of history.csv
COLUMNS = ("step", "delta", "volume", "det", "length", "merit")
#: the share of the design domain's size beyond which a refined vertex is reported out of
#: the domain (round-off only: the refinement clips the vertices into the domain's box)
OUTSIDE_TOL = 1e-9
FILES = ("history.csv", "summary.json", "refined.vtu", "refined.png")


def refine_run(folder, *, steps: int = STEPS, quiet: bool = False,
               overwrite: bool = False) -> int:
    """``pacto refine RUN``: the run's part made, its shape refined for a larger Δ at no more
    volume, the results written into ``RUN/refine/`` (the module docstring).  Returns the exit
    code (0); bad input is an InputError (one line, exit 2)."""
    t0 = time.perf_counter()
    run, out, setup, kind = _checked(folder, steps, overwrite)
    load = float(run.summary.get("load_reached") or run.load)
    say(quiet, f"refine {run.path}: {run.case.name}, model {run.params.model}, {kind} "
               f"pressure {load:g} {run.case.load_unit}, {steps} steps")
    problem = rebuild(run)
    if problem.mesh.dim != 2:
        raise InputError("refine: 3D parts are not refined yet")
    part, maxh = _part(run, problem, setup)
    params = analysis_params(run.params, None, PART_ORDER[2])
    response, space = _response(part.mesh, params, setup, load, kind)
    size = _size(part.mesh)
    bound = volume(part.mesh, response.thickness)
    domain = _bounds(problem.mesh)
    say(quiet, f"  the part: {part.mesh.ne} elements, maxh {maxh:.4g} m, order "
               f"{params.order}, volume {bound:.4g} m³ (the bound)")
    try:
        result = refine(response, space, volume_max=bound, steps=steps,
                        step=STEP_SHARE * maxh, penalty=PENALTY, alpha=1.0 / size ** 2,
                        bounds=(domain[0][:2], domain[1][:2]),
                        say=None if quiet else (lambda line: print("  " + line, flush=True)))
    except NewtonFailure as err:
        raise InputError(f"refine: the part has no equilibrium at the run's load on its "
                         f"starting shape ({err})") from None
    except ValueError as err:
        raise InputError(str(err)) from None
    settings = dict(threshold=part.threshold, threshold_note=part.choice.get("note"),
                    maxh=maxh, order=params.order, elements=part.mesh.ne, part_size=size)
    summary = _summary(run, result, bound, kind, load, settings)
    summary["warnings"] = _leaves(part.mesh, space, response, domain)
    for line in summary["warnings"]:
        say(quiet, f"  warning: {line}")
    summary["wall_time_s"] = time.perf_counter() - t0
    _write(out, run, part.mesh, (space, response, result), summary,
           (domain, setup.supports.clamp))
    d0, d1 = summary["delta_before"], summary["delta_after"]
    print(f"refined: Δ {d0:.4g} → {d1:.4g} m ({100 * summary['gain']:+.1f} %) at volume "
          f"{result.volume:.4g} m³ (bound {bound:.4g} m³), status {result.status} — {out}",
          flush=True)
    return 0


def _checked(folder, steps: int, overwrite: bool):
    """``(Run, RUN/refine, Setup, load type)`` of a run the command applies to; InputError
    (one line) otherwise, before anything is rebuilt."""
    if steps < 0:
        raise InputError(f"--steps: must be 0 or more, got {steps}")
    run = load_run(folder, "refine")
    if is_3d(run):
        raise InputError("refine: 3D parts are not refined yet")
    out = run.path / "refine"
    if out.exists() and not overwrite:
        raise InputError(f"refine: '{out}' exists (an earlier refinement): add --overwrite to "
                         f"replace its files")
    setup = run.case.make_setup(run.params)
    kind = run.params.load_type
    if setup.pressure is None or kind not in ("fixed", "follower"):
        raise InputError(f"refine: case '{run.case.name}' has no wall pressure to refine for "
                         f"(the refinement applies to pressure cases, fixed or follower)")
    if not setup.ports:
        raise InputError(f"refine: case '{run.case.name}' has no output port")
    return run, out, setup, kind


def _leaves(mesh, space, response, domain) -> list[str]:
    """A warning when the refined part reaches out of the run's design domain (``domain``:
    its lowest and highest corner) by more than :data:`OUTSIDE_TOL` of the domain's size:
    the refinement keeps every vertex in the domain's box, so this is a check only."""
    ref, motion, _ = moved_points(mesh, space, response)
    moved = ref + motion
    low, high = domain[0][:2], domain[1][:2]
    out = np.maximum(np.maximum(low - moved, moved - high), 0.0)
    far = float(np.max(out))
    if not far > OUTSIDE_TOL * float(np.max(high - low)):
        return []
    at = moved[int(np.argmax(np.max(out, axis=1)))]
    return [f"the refined part reaches {far:.3g} m out of the run's design domain (at "
            f"({at[0]:.3g}, {at[1]:.3g}) m)"]


def _part(run, problem, setup):
    """``(Part, maxh)``: the run's part as ``pacto analyse RUN`` makes it at its defaults."""
    maxh = PART_MAXH[2] * float(problem.h)
    part = make_part(problem, setup, threshold=0.5, maxh=maxh, threshold2=0.5, connect=True,
                     pressure=copy_gridfunction(problem.pressure_block.gfp), p_in=run.load,
                     mesh_time_limit=run.params.mesh_time_limit)
    return part, maxh


def _response(mesh, params, setup, load: float, kind: str):
    """``(PartResponse, ShapeSpace)`` of the part: the run's supports, ports and pressure;
    the clamp and the ports held, the symmetry lines held in their normal component."""
    supports = present_supports(setup.supports, mesh)
    ports = part_ports(setup)
    regions = set(mesh.GetBoundaries()) | set(mesh.GetBBoundaries())
    held = tuple(dict.fromkeys(supports.clamp + tuple(p.region for p in ports
                                                      if p.region in regions)))
    hold = Supports(clamp=held, fix_x=supports.fix_x, fix_y=supports.fix_y)
    try:
        response = PartResponse(mesh, params=params, supports=supports, ports=ports,
                                pressure=load, kind=kind)
        space = ShapeSpace(mesh, hold=hold)
    except ValueError as err:
        raise InputError(f"refine: the part cannot be refined: {err}") from None
    return response, space


def _bounds(mesh) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest vertex coordinates of ``mesh`` (m)."""
    points = np.array([v.point for v in mesh.vertices])
    return points.min(axis=0), points.max(axis=0)


def _size(mesh) -> float:
    """The part's size: its bounding box's largest side (m)."""
    low, high = _bounds(mesh)
    return float(np.max(high - low))


def _summary(run, result, bound: float, kind: str, load: float, settings: dict) -> dict:
    """summary.json's content."""
    first = result.history[0]
    d0, d1 = float(first["delta"]), float(result.delta)
    return {"run": str(run.path), "case": run.case.name, "status": result.status,
            "delta_before": d0, "delta_after": d1, "gain": (d1 - d0) / abs(d0),
            "volume_before": float(first["volume"]), "volume_after": float(result.volume),
            "volume_bound": bound, "volume_vs_bound": result.volume / bound - 1.0,
            "lowest_det": float(min(h["det"] for h in result.history)),
            "steps": len(result.history) - 1, "multiplier": float(result.multiplier),
            "model": run.params.model, "load_type": kind, "load": load,
            "load_unit": run.case.load_unit, "units": {"delta": "m", "volume": "m³"},
            "part": settings}


def moved_points(mesh, space, response) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(reference vertices, the shape's motion, u)`` at the part's vertices, each (n, 2).

    Both fields are read at the reference vertices with the deformation unset: a finite
    element function moves with the mesh, so its value at a reference vertex is its value at
    that vertex moved (the NGSolve notes, "Shape derivatives")."""
    ref = np.array([v.point for v in mesh.vertices], dtype=float)
    mesh.UnsetDeformation()
    try:
        where = mesh(ref[:, 0], ref[:, 1])
        motion = np.asarray(space.deformation(where), dtype=float).reshape(len(ref), -1)
        u = np.asarray(response.u(where), dtype=float).reshape(len(ref), -1)
    finally:
        mesh.SetDeformation(space.deformation)
    return ref, motion, u


def _write(out: Path, run, mesh, refined, summary: dict, frame) -> None:
    """history.csv, summary.json, refined.vtu and refined.png into ``out``; ``refined`` is
    ``(ShapeSpace, PartResponse, RefineResult)``, ``frame`` ``(the design domain's bounds,
    the clamp's regions)`` for the picture."""
    import meshio

    space, response, result = refined

    out.mkdir(parents=True, exist_ok=True)
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(COLUMNS)
    for row in result.history:
        writer.writerow([row["step"]] + [f"{row[c]:.10g}" for c in COLUMNS[1:]])
    atomic_write_text(out / "history.csv", text.getvalue())
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=1))
    ref, motion, u = moved_points(mesh, space, response)
    moved = ref + motion
    triangles = np.array([[v.nr for v in el.vertices] for el in mesh.Elements(VOL)])
    pad = lambda a: np.column_stack([a, np.zeros(len(a))])  # noqa: E731
    with atomic_path(out / "refined.vtu") as tmp:
        meshio.write(str(tmp), meshio.Mesh(pad(moved), [("triangle", triangles)],
                                           point_data={"u": pad(u), "moved": pad(motion)}),
                     file_format="vtu")
    edges = [([v.nr for v in el.vertices], el.mat) for el in mesh.Elements(BND)]
    with atomic_path(out / "refined.png") as tmp:
        plot_outlines(tmp, ref, moved, edges, summary, run.case.name, domain=frame[0],
                      clamp=frame[1])


def plot_outlines(path, ref, moved, edges, summary: dict, name: str, *, domain=None,
                  clamp=()) -> None:
    """The part's outline before (grey) and after (blue; the pressure walls red, the clamp
    black: it does not move) the refinement, true scale, in metres, in the run's design
    domain (``domain``: its lowest and highest corner; dotted)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    drawn = set()
    colours = {"pressure": "tab:red", "clamp": "black", "after": "tab:blue"}
    labels = {"pressure": "after: the pressure walls", "clamp": "the clamp (held)",
              "after": "after: the other walls"}
    for (a, b), region in edges:
        ax.plot(ref[[a, b], 0], ref[[a, b], 1], color="0.55", lw=0.8,
                label=None if "before" in drawn else "before (the part as made)")
        drawn.add("before")
    for (a, b), region in edges:
        key = ("pressure" if region == "pressure" else "clamp" if region in clamp else
               "after")
        ax.plot(moved[[a, b], 0], moved[[a, b], 1], lw=2.6 if key == "clamp" else 1.6,
                color=colours[key], label=None if key in drawn else labels[key])
        drawn.add(key)
    if domain is not None:
        (x0, y0), (x1, y1) = domain[0][:2], domain[1][:2]
        ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.3", lw=0.8, ls=":",
                label="the run's design domain")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=8)
    s = summary
    ax.set_title(f"{name} part refined (status {s['status']}, {s['steps']} steps): Δ "
                 f"{s['delta_before']:.4g} → {s['delta_after']:.4g} m "
                 f"({100 * s['gain']:+.1f} %)\nvolume {s['volume_after']:.4g} m³ (bound "
                 f"{s['volume_bound']:.4g}), {s['load_type']} {s['load']:.3g} "
                 f"{s['load_unit']}, {s['model']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=130)
    plt.close(fig)
