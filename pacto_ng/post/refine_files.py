"""The files of ``pacto refine RUN`` (:mod:`.refine_run`): history.csv, summary.json,
refined.vtu, refined.png and refined.stl, written into ``RUN/refine/``."""
from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np
from ngsolve import BND, VOL

from ..files import atomic_path, atomic_write_text
from .domain import symmetry_line
from .grid import mesh_to_pyvista
from .mirror3d import mirror_surface, symmetry_planes
from .part2d import part_mesh, write_part_stl
from .part3d import write_part_stl as write_surface_stl
from .plots3d import plotter as offscreen_plotter

#: the columns of history.csv
COLUMNS = ("step", "mesh", "delta", "ratio", "volume", "det", "length", "wall", "merit")
#: a coordinate within this share of the part's size of zero is drawn as zero
SNAP = 1e-9
FILES = ("history.csv", "summary.json", "refined.vtu", "refined.png", "refined.stl")


def moved_points(space, response) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(reference vertices, the shape's motion, u)`` at the part's vertices, each (n, dim).

    Both fields are read at the reference vertices with the deformation unset: a finite
    element function moves with the mesh, so its value at a reference vertex is its value at
    that vertex moved (the NGSolve notes, "Shape derivatives")."""
    mesh = space.mesh
    ref = np.array([v.point for v in mesh.vertices], dtype=float)
    mesh.UnsetDeformation()
    try:
        where = mesh(*(ref[:, k] for k in range(mesh.dim)))
        motion = np.asarray(space.deformation(where), dtype=float).reshape(len(ref), -1)
        u = np.asarray(response.u(where), dtype=float).reshape(len(ref), -1)
    finally:
        mesh.SetDeformation(space.deformation)
    return ref, motion, u


def write_refinement(out: Path, run, refined, summary: dict, frame) -> None:
    """history.csv, summary.json, refined.vtu and refined.png into ``out``; ``refined`` is
    ``(the part as made, ShapeSpace, PartResponse, RefineResult)`` (the last three on the
    refined part's mesh), ``frame`` ``(the design domain's bounds, the clamp's regions)`` for
    the picture."""
    import meshio

    first, space, response, result = refined
    mesh = space.mesh

    out.mkdir(parents=True, exist_ok=True)
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(COLUMNS)
    for row in result.history:
        writer.writerow([row["step"]] + [f"{row[c]:.10g}" for c in COLUMNS[1:]])
    atomic_write_text(out / "history.csv", text.getvalue())
    atomic_write_text(out / "summary.json", json.dumps(summary, indent=1))
    ref, motion, u = moved_points(space, response)
    moved = ref + motion
    cells = np.array([[v.nr for v in el.vertices] for el in mesh.Elements(VOL)])
    pad = lambda a: np.column_stack([a, np.zeros(len(a))]) if mesh.dim == 2 else a  # noqa: E731
    kind = "triangle" if mesh.dim == 2 else "tetra"
    with atomic_path(out / "refined.vtu") as tmp:
        meshio.write(str(tmp), meshio.Mesh(pad(moved), [(kind, cells)],
                                           point_data={"u": pad(u), "moved": pad(motion)}),
                     file_format="vtu")
    with atomic_path(out / "refined.png") as tmp:
        if mesh.dim == 2:
            before = (np.array([v.point for v in first.vertices], dtype=float), _edges(first))
            plot_outlines(tmp, before, (moved, _edges(mesh)), summary, run.case.name,
                          domain=frame[0], clamp=frame[1])
        else:
            plot_surfaces(tmp, mesh_to_pyvista(first), _grid(moved, cells), motion, summary,
                          run.case.name)


def _edges(mesh) -> list:
    """``[([a, b], region)]``: the boundary segments of a 2D mesh by their vertex numbers."""
    return [([v.nr for v in el.vertices], el.mat) for el in mesh.Elements(BND)]


def plot_outlines(path, before, after, summary: dict, name: str, *, domain=None,
                  clamp=()) -> None:
    """The part's outline before (grey) and after (blue; the pressure walls red, the clamp
    black: it does not move) the refinement, true scale, in metres, in the run's design
    domain (``domain``: its lowest and highest corner; dotted).  ``before`` and ``after``
    are ``(vertices, boundary segments)`` (:func:`_edges`) of the part as made and refined
    (remeshed, it may have other vertices)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.transforms import offset_copy

    fig, ax = plt.subplots(figsize=(8, 6))
    styles = {"before": ("0.55", 0.8, "before (the part as made)"),
              "pressure": ("tab:red", 1.6, "after: the pressure walls"),
              "clamp": ("black", 2.6, "the clamp (held)"),
              "after": ("tab:blue", 1.6, "after: the other walls")}
    (ref, edges0), (moved, edges) = before, after
    groups = {"before": [ref[[a, b], :2] for (a, b), _ in edges0]}
    for (a, b), region in edges:
        key = ("pressure" if region == "pressure" else "clamp" if region in clamp else
               "after")
        groups.setdefault(key, []).append(moved[[a, b], :2])
    for key, segments in groups.items():  # one collection per kind: thousands of segments
        colour, width, label = styles[key]
        ax.add_collection(LineCollection(segments, colors=colour, linewidths=width,
                                         label=label))
    ax.autoscale_view()
    if domain is not None:
        (x0, y0), (x1, y1) = domain[0][:2], domain[1][:2]
        ax.plot([x0, x1, x1, x0, x0], [y0, y0, y1, y1, y0], color="0.3", lw=0.8, ls=":",
                label="the run's design domain")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    # below the x label whatever the axes' height (a flat part's is small)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=3, fontsize=8,
              bbox_transform=offset_copy(ax.transAxes, fig=fig, y=-30, units="points"))
    s = summary
    ax.set_title(f"{name} part refined (status {s['status']}, {s['steps']} steps): Δ "
                 f"{s['delta_before']:.4g} → {s['delta_after']:.4g} m "
                 f"({100 * s['gain']:+.1f} %)\nvolume {s['volume_after']:.4g} m³ (bound "
                 f"{s['volume_bound']:.4g}), {s['load_type']} {s['load']:.3g} "
                 f"{s['load_unit']}, {s['model']}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, format="png", dpi=130, bbox_inches="tight")
    plt.close(fig)


def write_stl(path: Path, mesh, thickness: float, name: str) -> None:
    """The refined part (``mesh``: its independent remesh) as ``pacto export`` writes a part,
    whole (mirrored across the case's symmetry line or planes), a closed binary STL in mm:
    in 2D extruded by the thickness, in 3D its boundary surface."""
    header = f"pacto_ng refined part of {name}"
    with atomic_path(path) as tmp:
        if mesh.dim == 2:
            write_part_stl(tmp, part_mesh(mesh, symmetry_line(mesh)), thickness, units="mm",
                           header=header)
        else:
            surface = mesh_to_pyvista(mesh).extract_surface(algorithm="dataset_surface").triangulate()
            write_surface_stl(tmp, mirror_surface(surface, symmetry_planes(mesh)), "mm",
                              header)


def _grid(points, cells):
    """The tetrahedra ``cells`` on ``points`` (m) as a pyvista UnstructuredGrid."""
    import pyvista as pv

    flat = np.column_stack([np.full(len(cells), 4), cells]).ravel()
    types = np.full(len(cells), pv.CellType.TETRA, dtype=np.uint8)
    return pv.UnstructuredGrid(flat, types, np.asarray(points, dtype=float))


def plot_surfaces(path, before, after, motion, summary: dict, name: str) -> None:
    """refined.png of a 3D part: the part as made (left) and refined (right, coloured by how
    far the refinement moved each point, mm), their surfaces from the same camera, with
    axes in metres; ``before`` and ``after`` pyvista grids, ``motion`` (n, 3) at the points
    of ``after``."""
    size = float(np.max(np.ptp(np.asarray(after.points), axis=0)))
    for grid in (before, after):  # round-off shown as a coordinate (e.g. -1.1e-18) reads 0
        points = np.array(grid.points)
        points[np.abs(points) < SNAP * size] = 0.0
        grid.points = points
    after.point_data["moved (mm)"] = 1e3 * np.linalg.norm(motion, axis=1)
    plotter = offscreen_plotter((1, 2), (1400, 600))
    for column, (grid, what) in enumerate(((before, "the part as made"),
                                           (after, "refined: the motion (mm)"))):
        plotter.subplot(0, column)
        surface = grid.extract_surface(algorithm="dataset_surface")
        if column:
            plotter.add_mesh(surface, scalars="moved (mm)", cmap="viridis",
                             smooth_shading=True, scalar_bar_args={"title": "moved (mm)"})
        else:
            plotter.add_mesh(surface, color="lightgrey", smooth_shading=True)
        plotter.show_bounds(xtitle="x (m)", ytitle="y (m)", ztitle="z (m)", fmt="%.3g",
                            font_size=9, n_zlabels=2)
        plotter.add_text(what, font_size=10)
        plotter.view_isometric()
    plotter.link_views()
    s = summary
    plotter.subplot(0, 0)
    plotter.add_text(f"{name}: delta {s['delta_before']:.4g} -> {s['delta_after']:.4g} m "
                     f"({100 * s['gain']:+.1f} %), status {s['status']}", position="lower_left",
                     font_size=9)
    plotter.screenshot(str(path))
    plotter.close()
