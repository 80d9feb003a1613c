"""Pictures of a 3D run, rendered off-screen with pyvista: design.png and pressure.png.

design.png has two views side by side: the ρ̄ = 0.5 iso-surface of the design (the nodal,
volume-weighted mean of the element densities) seen obliquely, and the cut at mid-depth (the
plane z = the middle of the bounding box, through the chambers of a Box case) coloured by
each element's own ρ̄, as the optimiser holds it (on a structured mesh of hexahedra the cut
lies :data:`CUT_SHIFT` of the part's size above mid-depth, inside one layer of elements whose
faces meet there).  On tetrahedra the cut elements are slivers of every shape, but the nodal
mean would show every interface as a grey band: the cantilever-3d design of greyness 0.026
read as grey all along its web (2026-12-06).
pressure.png is p / P_in on the same cut with the ρ̄ = 0.5 line drawn on it.  Every view has
its axes in metres, as the 2D pictures (:func:`show_axes`: the bounding box's edges labelled
x (m), y (m), z (m); a view from above labels x and y only), and a cut's title gives its
coordinate rounded to the part's size (:func:`coordinate_text`: no round-off shown as a
coordinate).  :func:`render` gives a plotter's picture as an RGB array (``pacto compare``
puts several side by side).

Rendering needs no display: VTK opens an EGL window where there is no X server (checked here
with VTK 9.7 from the ``vtk`` wheel, whose EGL render window works without a DISPLAY);
:func:`plotter` asks for it directly so that VTK does not first try X and log a warning.
"""
from __future__ import annotations

import os

import numpy as np

from ..files import atomic_path
from .grid import area_weighted_nodal, cell_volumes, mesh_to_pyvista

WINDOW = (1200, 500)  #: pixels of design.png (two views) and pressure.png
#: a coordinate within this fraction of the part's size of a round value is that value
ROUND_RTOL = 1e-9
#: the cut's shift above mid-depth, as a fraction of the part's size
CUT_SHIFT = 1e-6


def plotter(shape=(1, 1), window=WINDOW):
    """An off-screen pyvista plotter of ``shape`` subplots, ``window`` pixels (module
    docstring: no display needed)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    return pv.Plotter(off_screen=True, shape=shape, window_size=window, border=False)


def _rounded(value: float, size: float, digits: int) -> float:
    """``value`` rounded to 10^-``digits`` of the decade of ``size`` (> 0); 0 within
    :data:`ROUND_RTOL` of ``size``."""
    step = 10.0 ** (np.floor(np.log10(size)) - digits)
    rounded = round(value / step) * step
    return 0.0 if abs(rounded) < ROUND_RTOL * size else float(f"{rounded:.6g}")


def coordinate_text(value: float, size: float) -> str:
    """``value`` (m) rounded to a thousandth of ``size`` (the part's size, m) for a title:
    a cut at 5.384e-08 m through a part of 0.02 m reads ``0``, at 0.0123456 m ``0.01235``."""
    value, size = float(value), abs(float(size))
    if size == 0.0 or not np.isfinite(size):
        return f"{value:.4g}"
    return f"{_rounded(value, size, 3):.6g}"


def size_of(bounds) -> float:
    """The largest edge (m) of a bounding box ``(x0, x1, y0, y1, z0, z1)``."""
    b = np.asarray(bounds, dtype=float).reshape(3, 2)
    return float(np.ptp(b, axis=1).max())


def rounded_bounds(bounds) -> list[float]:
    """The box the axes label: ``bounds`` rounded to a hundredth of the decade of the box's
    size (no -6.06e-20 on an axis; a part 0.2 m long whose face at z = 0 moved by -0.4 mm:
    0)."""
    size = size_of(bounds)
    if size == 0.0 or not np.isfinite(size):
        return [float(b) for b in bounds]
    return [_rounded(float(b), size, 2) for b in bounds]


def show_axes(p, bounds, *, top: bool = False, font_size: int = 12) -> None:
    """The axes of the current view of ``p``: the box ``bounds`` with its edges labelled in
    metres, x (m), y (m) and z (m) (``top``, a view from above: x and y only)."""
    p.show_bounds(bounds=rounded_bounds(bounds), xtitle="x (m)", ytitle="y (m)",
                  ztitle="z (m)", n_xlabels=3, n_ylabels=3, n_zlabels=2, fmt="%.3g",
                  font_size=font_size, location="outer", ticks="outside", show_zaxis=not top,
                  show_zlabels=not top, color="black")


def bar(title: str, **kw) -> dict:
    """The scalar bar's arguments: upright at the right of the view (clear of the x axis)."""
    return dict(title=title, vertical=True, position_x=0.86, position_y=0.12, width=0.05,
                height=0.66, title_font_size=14, label_font_size=12, n_labels=5, **kw)


def oblique(p) -> None:
    """The isometric view of the current view of ``p``, zoomed out so that the axes' titles
    stay in the picture."""
    p.view_isometric()
    p.camera.zoom(0.85)


def render(p) -> np.ndarray:
    """The picture of plotter ``p`` as an RGB array; ``p`` closed."""
    img = np.asarray(p.screenshot(return_img=True))
    p.close()
    return img


def nodal_field(grid, values) -> np.ndarray:
    """Volume-weighted mean of the element ``values`` around every point of ``grid``."""
    return area_weighted_nodal(grid, np.asarray(values, dtype=float), cell_volumes(grid))


def _mid_depth(grid):
    lo, hi = np.asarray(grid.bounds[4:6], dtype=float)
    return 0.5 * (lo + hi)


def _cut(grid):
    """The plane z = mid-depth through ``grid`` (its point data interpolated)."""
    centre = np.array(grid.center, dtype=float)
    centre[2] = _mid_depth(grid) + CUT_SHIFT * size_of(grid.bounds)
    return grid.slice(normal="z", origin=centre)


def cut_title(grid) -> str:
    """``cut at z = ... m``: the mid-depth cut's coordinate (:func:`coordinate_text`)."""
    return f"cut at z = {coordinate_text(_mid_depth(grid), size_of(grid.bounds))} m"


def _screenshot(plotter, path):
    with atomic_path(path) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()


def design_picture(path, grid, rho, title: str = "") -> None:
    """design.png of a 3D design: the ρ̄ = 0.5 iso-surface and the mid-depth cut coloured by
    ρ̄ (module docstring); ``grid`` the mesh as a pyvista grid
    (:func:`~pacto_ng.post.grid.mesh_to_pyvista`), ``rho`` one value per cell."""
    rho = np.clip(np.asarray(rho, dtype=float), 0.0, 1.0)
    grid.point_data["rho_nodal"] = nodal_field(grid, rho)
    grid.cell_data["rho_bar"] = rho  # the cut shows the elements' own values, not an average
    p = plotter((1, 2))
    p.subplot(0, 0)
    p.add_mesh(grid.outline(), color="grey")
    surface = grid.contour([0.5], scalars="rho_nodal")
    words = "rho_bar = 0.5 iso-surface"  # VTK's text font has no ρ̄
    if surface.n_points:
        p.add_mesh(surface, color="lightsteelblue", smooth_shading=True)
    else:
        words += " (none: rho_bar does not cross 0.5)"
    p.add_text(f"{title}\n{words}" if title else words, font_size=9)
    show_axes(p, grid.bounds)
    oblique(p)
    p.subplot(0, 1)
    p.add_mesh(grid.outline(), color="grey")
    p.add_mesh(_cut(grid), scalars="rho_bar", preference="cell", cmap="gray_r", clim=(0, 1),
               scalar_bar_args=bar("rho_bar"))
    p.add_text(cut_title(grid), font_size=9)
    show_axes(p, grid.bounds, top=True)
    p.view_xy()
    p.camera.zoom(0.85)  # room for the scalar bar right of the x axis's last label
    _screenshot(p, path)


def pressure_picture(path, grid, p_rel, rho, title: str = "") -> None:
    """pressure.png of a 3D design: ``p_rel`` (p / P_in at the vertices of ``grid``, the mesh
    as a pyvista grid) on the mid-depth cut, with the cut's ρ̄ = 0.5 line (``rho`` per
    cell)."""
    grid.point_data["p"] = np.asarray(p_rel, dtype=float)
    grid.point_data["rho_bar"] = nodal_field(grid, np.clip(np.asarray(rho, dtype=float), 0, 1))
    cut = _cut(grid)
    p = plotter()
    p.add_mesh(grid.outline(), color="grey")
    p.add_mesh(cut, scalars="p", cmap="coolwarm", clim=(0, 1),
               scalar_bar_args=bar("p / P_in"))
    line = cut.contour([0.5], scalars="rho_bar")
    if line.n_points:
        p.add_mesh(line, color="black", line_width=2)
    words = f"p / P_in on the {cut_title(grid)}, rho_bar = 0.5 line"
    p.add_text(f"{title}\n{words}" if title else words, font_size=9)
    show_axes(p, grid.bounds, top=True)
    p.view_xy()
    p.camera.zoom(1.4)  # the one view fills the picture's height, its labels kept
    _screenshot(p, path)


def deformed_picture(path, mesh, u, title: str = "", contact=None) -> None:
    """The deformed part of a 3D analysis: its surface moved by ``u`` (a vector field on
    ``mesh``, true scale) coloured by |u| over the undeformed surface's feature edges, seen
    obliquely and from above (+z), with the axes in metres; ``contact``: the reference
    positions ``(n, 3)`` of the walls' vertices in contact, drawn as red dots where ``u``
    moves them."""
    import pyvista as pv

    grid = mesh_to_pyvista(mesh)
    pts = np.asarray(grid.points, dtype=float)
    uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy())))
    grid.point_data["u_mag"] = np.linalg.norm(uv.reshape(-1, 3), axis=1)
    edges = grid.extract_surface(algorithm="dataset_surface").extract_feature_edges()
    moved = grid.copy()
    moved.points = pts + uv.reshape(-1, 3)
    surface = moved.extract_surface(algorithm="dataset_surface")
    both = np.r_[pts, moved.points]
    touch = None
    if contact is not None and len(contact):
        at = np.asarray(contact, dtype=float)
        shift = np.asarray(u(mesh(at[:, 0].copy(), at[:, 1].copy(), at[:, 2].copy())))
        touch = pv.PolyData(at + shift.reshape(-1, 3))
    box = np.c_[both.min(axis=0), both.max(axis=0)].ravel()  # deformed and undeformed
    p = plotter((1, 2))
    for col, view in enumerate(("isometric", "xy")):
        p.subplot(0, col)
        p.add_mesh(edges, color="black", line_width=1)
        p.add_mesh(surface, scalars="u_mag", cmap="viridis", show_scalar_bar=col == 1,
                   scalar_bar_args=bar("displacement (m)", fmt="%.3g"))
        if touch is not None:
            p.add_mesh(touch, color="red", point_size=6, render_points_as_spheres=True)
        show_axes(p, box, top=view == "xy")
        if view == "xy":
            p.view_xy()
            p.camera.zoom(0.85)  # room for the scalar bar
        else:
            oblique(p)
        words = ("from above: the undeformed outline in black"
                 + ("; red: walls in contact" if touch is not None else ""))
        p.add_text(title if col == 0 and title else words, font_size=9)
    _screenshot(p, path)
