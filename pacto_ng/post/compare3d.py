"""``pacto compare`` of 3D runs: the views of :mod:`.plots3d` side by side (:mod:`.compare`
draws the figure and the analysis curves).

Per run, the ρ̄ = 0.5 iso-surface of its design (the nodal, volume-weighted mean of the element
densities, as design.png) rendered off-screen with the same camera and axes for every run (the
box of all the designs), and its mid-depth cut (the plane z = the middle of its bounding box,
as design.png's) coloured by ρ̄ with axes in metres; then the thresholded designs' outlines on
that cut over each other: the analysed part's (``analysis/remeshed.vtu``) cut where the run was
analysed, else the cut's ρ̄ = 0.5 line.  A 3D run is drawn as it was solved (a symmetric half
is not mirrored).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.tri import Triangulation

from ..errors import InputError
from .plots3d import (coordinate_text, nodal_field, oblique, plotter, render, show_axes,
                      size_of)

#: pixels of one run's iso-surface view
VIEW = (800, 500)


def design_key(g, vtu) -> str:
    """The name of the design's ρ̄ in ``g``, a run's design.vtu ``vtu`` (``rho_bar1`` for two
    materials); InputError naming ``vtu`` when it has none."""
    for key in ("rho_bar", "rho_bar1"):
        if key in g.point_data:
            return key
    raise InputError(f"compare: '{vtu}' has no rho_bar field")


@dataclass
class Design3D:
    """A 3D run's design: its grid (point data ``rho_bar``, nodal), the mid-depth z, and the
    cut there (triangles with ``rho_bar``)."""

    grid: object
    z: float
    cut: object

    @property
    def cut_title(self) -> str:
        return f"cut at z = {coordinate_text(self.z, size_of(self.grid.bounds))} m"


def read_design(vtu) -> Design3D:
    """A run's design.vtu (NGSolve writes every element with its own vertices and its ρ̄ on
    them) with the duplicate vertices merged and ρ̄ smoothed to them, and its mid-depth cut."""
    import pyvista as pv

    g = pv.read(str(vtu))
    val = np.asarray(g.point_data[design_key(g, vtu)], dtype=float)
    pts = np.asarray(g.points, dtype=float)
    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    _, first, inv = np.unique(np.round(pts / scale, 9), axis=0, return_index=True,
                              return_inverse=True)
    inv = inv.ravel()
    cells, types, rho = [], [], []
    for ctype, conn in g.cells_dict.items():
        conn = np.asarray(conn)
        cells.append(np.c_[np.full(len(conn), conn.shape[1]), inv[conn]].ravel())
        types.append(np.full(len(conn), ctype, dtype=np.uint8))
        rho.append(val[conn].mean(axis=1))
    grid = pv.UnstructuredGrid(np.concatenate(cells), np.concatenate(types), pts[first])
    grid.point_data["rho_bar"] = nodal_field(grid, np.clip(np.concatenate(rho), 0.0, 1.0))
    z = 0.5 * (grid.bounds[4] + grid.bounds[5])
    return Design3D(grid, z, _slice(grid, z))


def _slice(grid, z):
    centre = np.array(grid.center, dtype=float)
    centre[2] = z
    return grid.slice(normal="z", origin=centre).triangulate()


def common_box(designs) -> np.ndarray:
    """The bounding box ``(x0, x1, y0, y1, z0, z1)`` of all ``designs``."""
    b = np.array([d.grid.bounds for d in designs], dtype=float)
    return np.r_[b[:, 0].min(), b[:, 1].max(), b[:, 2].min(), b[:, 3].max(), b[:, 4].min(),
                 b[:, 5].max()]


def iso_image(design: Design3D, box) -> tuple[np.ndarray, bool]:
    """The ρ̄ = 0.5 iso-surface of ``design`` inside the grey ``box`` (the same for every run:
    the same camera), seen obliquely with the axes in metres: ``(RGB array, whether the
    surface exists)``."""
    import pyvista as pv

    p = plotter(window=VIEW)
    p.add_mesh(pv.Box(bounds=box).outline(), color="grey")
    surface = design.grid.contour([0.5], scalars="rho_bar")
    if surface.n_points:
        p.add_mesh(surface, color="lightsteelblue", smooth_shading=True)
    show_axes(p, box, font_size=16)  # shown at about half its size
    oblique(p)
    return cropped(render(p)), bool(surface.n_points)


def cropped(img, pad: int = 8) -> np.ndarray:
    """``img`` (RGB) without the rows and columns of its background colour (its corner
    pixel's) around the picture, ``pad`` pixels of them kept."""
    ink = np.any(img != img[0, 0], axis=-1)
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if not rows.size:
        return img
    r0, r1 = max(rows[0] - pad, 0), min(rows[-1] + pad + 1, img.shape[0])
    c0, c1 = max(cols[0] - pad, 0), min(cols[-1] + pad + 1, img.shape[1])
    return img[r0:r1, c0:c1]


def _cut_triangulation(cut):
    faces = np.asarray(cut.faces).reshape(-1, 4)[:, 1:]
    pts = np.asarray(cut.points, dtype=float)
    return Triangulation(pts[:, 0], pts[:, 1], faces)


def draw_designs(top, designs, box, titles, colours, ncol) -> None:
    """Per run two panels: its iso-surface (:func:`iso_image`) and its mid-depth cut
    coloured by ρ̄ (x, y in metres), titled by ``titles`` in the run's colour."""
    nrow = -(-len(designs) // ncol)
    images = [iso_image(d, box) for d in designs]
    cuts = []
    for i, (d, (img, found)) in enumerate(zip(designs, images)):
        r, c = 2 * (i // ncol), i % ncol
        ax = top.add_subplot(2 * nrow, ncol, r * ncol + c + 1)
        ax.imshow(img)
        ax.set_axis_off()
        ax.set_title(titles[i] + ("\nρ̄ = 0.5 iso-surface" if found else
                                  "\nno ρ̄ = 0.5 iso-surface (ρ̄ does not cross 0.5)"),
                     fontsize=9, color=colours[i])
        ax = top.add_subplot(2 * nrow, ncol, (r + 1) * ncol + c + 1)
        cuts.append(ax)
        tpc = ax.tripcolor(_cut_triangulation(d.cut), np.asarray(d.cut.point_data["rho_bar"]),
                           shading="gouraud", cmap="gray_r", vmin=0.0, vmax=1.0)
        _frame(ax, box)
        ax.set_title(f"ρ̄ on the {d.cut_title}", fontsize=9, color=colours[i])
    top.colorbar(tpc, ax=cuts, label="ρ̄ on the cut", shrink=0.8)


def _frame(ax, box) -> None:
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def part_cut_segments(vtu, z) -> np.ndarray:
    """The outline (segments (n, 2, 2), x and y) of the analysed part ``vtu`` cut at ``z``:
    the cut's boundary edges; none when the plane misses the part."""
    import pyvista as pv

    g = pv.read(str(vtu))
    centre = np.array(g.center, dtype=float)
    centre[2] = z
    cut = g.slice(normal="z", origin=centre)
    if not cut.n_cells:
        return np.zeros((0, 2, 2))
    e = cut.extract_feature_edges(boundary_edges=True, non_manifold_edges=False,
                                  feature_edges=False, manifold_edges=False)
    lines = np.asarray(e.lines).reshape(-1, 3)[:, 1:]
    return np.asarray(e.points)[:, :2][lines]


def draw_outlines(ax, folders, designs, box, labels, colours) -> None:
    """The thresholded designs on their mid-depth cuts over each other: the analysed part's
    cut (``FOLDER/analysis/remeshed.vtu``), else the cut's ρ̄ = 0.5 line."""
    for i, (folder, d) in enumerate(zip(folders, designs)):
        rem = Path(folder) / "analysis" / "remeshed.vtu"
        if rem.exists():
            ax.add_collection(LineCollection(part_cut_segments(rem, d.z), colors=colours[i],
                                             linewidths=1.2))
        else:
            rho = np.asarray(d.cut.point_data["rho_bar"])
            if rho.min() < 0.5 < rho.max():
                ax.tricontour(_cut_triangulation(d.cut), rho, levels=[0.5],
                              colors=[colours[i]], linewidths=1.2)
        ax.plot([], [], color=colours[i], label=labels[i])
    _frame(ax, box)
    zs = sorted({d.cut_title for d in designs})
    ax.set_title("thresholded designs (analysed part, else ρ̄ = 0.5), " + "; ".join(zs),
                 fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.18), frameon=False)

