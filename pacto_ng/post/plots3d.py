"""Pictures of a 3D run, rendered off-screen with pyvista: design.png and pressure.png.

design.png has two views side by side: the ρ̄ = 0.5 iso-surface of the design (the nodal,
volume-weighted mean of the element densities) seen obliquely, and the cut at mid-depth (the
plane z = the middle of the bounding box, through the chambers of a Box case) coloured by ρ̄.
pressure.png is p / P_in on the same cut with the ρ̄ = 0.5 line drawn on it.

Rendering needs no display: VTK opens an EGL window where there is no X server (checked here
with VTK 9.7 from the ``vtk`` wheel, whose EGL render window works without a DISPLAY);
:func:`_plotter` asks for it directly so that VTK does not first try X and log a warning.
"""
from __future__ import annotations

import os

import numpy as np

from ..files import atomic_path
from .grid import area_weighted_nodal, cell_volumes, mesh_to_pyvista

WINDOW = (1200, 500)  #: pixels of design.png (two views) and pressure.png


def _plotter(shape=(1, 1)):
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    return pv.Plotter(off_screen=True, shape=shape, window_size=WINDOW, border=False)


def nodal_field(grid, values) -> np.ndarray:
    """Volume-weighted mean of the element ``values`` around every point of ``grid``."""
    return area_weighted_nodal(grid, np.asarray(values, dtype=float), cell_volumes(grid))


def _mid_depth(grid):
    lo, hi = np.asarray(grid.bounds[4:6], dtype=float)
    return 0.5 * (lo + hi)


def _cut(grid):
    """The plane z = mid-depth through ``grid`` (its point data interpolated)."""
    centre = np.array(grid.center, dtype=float)
    centre[2] = _mid_depth(grid)
    return grid.slice(normal="z", origin=centre)


def _screenshot(plotter, path):
    with atomic_path(path) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()


def design_picture(path, mesh, rho, title: str = "") -> None:
    """design.png of a 3D design: the ρ̄ = 0.5 iso-surface and the mid-depth cut coloured by
    ρ̄ (module docstring); ``rho`` one value per element in NGSolve's order."""
    grid = mesh_to_pyvista(mesh)
    rho = np.clip(np.asarray(rho, dtype=float), 0.0, 1.0)
    grid.point_data["rho_bar"] = nodal_field(grid, rho)
    p = _plotter((1, 2))
    p.subplot(0, 0)
    p.add_mesh(grid.outline(), color="grey")
    surface = grid.contour([0.5], scalars="rho_bar")
    words = "rho_bar = 0.5 iso-surface"  # VTK's text font has no ρ̄
    if surface.n_points:
        p.add_mesh(surface, color="lightsteelblue", smooth_shading=True)
    else:
        words += " (none: rho_bar does not cross 0.5)"
    p.add_text(f"{title}\n{words}" if title else words, font_size=9)
    p.view_isometric()
    p.subplot(0, 1)
    p.add_mesh(grid.outline(), color="grey")
    p.add_mesh(_cut(grid), scalars="rho_bar", cmap="gray_r", clim=(0, 1),
               scalar_bar_args={"title": "rho_bar"})
    p.add_text(f"cut at z = {_mid_depth(grid):.4g} m", font_size=9)
    p.view_xy()
    _screenshot(p, path)


def pressure_picture(path, mesh, p_rel, rho, title: str = "") -> None:
    """pressure.png of a 3D design: ``p_rel`` (p / P_in at the mesh's vertices) on the
    mid-depth cut, with the cut's ρ̄ = 0.5 line (``rho`` per element)."""
    grid = mesh_to_pyvista(mesh)
    grid.point_data["p"] = np.asarray(p_rel, dtype=float)
    grid.point_data["rho_bar"] = nodal_field(grid, np.clip(np.asarray(rho, dtype=float), 0, 1))
    cut = _cut(grid)
    p = _plotter()
    p.add_mesh(grid.outline(), color="grey")
    p.add_mesh(cut, scalars="p", cmap="coolwarm", clim=(0, 1),
               scalar_bar_args={"title": "p / P_in"})
    line = cut.contour([0.5], scalars="rho_bar")
    if line.n_points:
        p.add_mesh(line, color="black", line_width=2)
    p.add_text(f"{title}\np / P_in at z = {_mid_depth(grid):.4g} m, rho_bar = 0.5 line",
               font_size=9)
    p.view_xy()
    _screenshot(p, path)


def deformed_picture(path, mesh, u, title: str = "") -> None:
    """The deformed part of a 3D analysis: its surface moved by ``u`` (a vector field on
    ``mesh``, true scale) coloured by |u| over the undeformed surface's feature edges, seen
    obliquely and from above (+z), with the axes in metres."""
    grid = mesh_to_pyvista(mesh)
    pts = np.asarray(grid.points, dtype=float)
    uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy())))
    grid.point_data["u_mag"] = np.linalg.norm(uv.reshape(-1, 3), axis=1)
    edges = grid.extract_surface(algorithm="dataset_surface").extract_feature_edges()
    moved = grid.copy()
    moved.points = pts + uv.reshape(-1, 3)
    surface = moved.extract_surface(algorithm="dataset_surface")
    p = _plotter((1, 2))
    for col, view in enumerate(("isometric", "xy")):
        p.subplot(0, col)
        p.add_mesh(edges, color="black", line_width=1)
        p.add_mesh(surface, scalars="u_mag", cmap="viridis", show_scalar_bar=col == 1,
                   scalar_bar_args={"title": "displacement (m)", "fmt": "%.3g"})
        p.show_bounds(xtitle="x (m)", ytitle="y (m)", ztitle="z (m)", font_size=8,
                      fmt="%.3g")
        getattr(p, f"view_{view}")()
        p.add_text(title if col == 0 and title else
                   "from above: the undeformed outline in black", font_size=9)
    _screenshot(p, path)
