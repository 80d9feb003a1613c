"""Pictures of a run: the physical density (design.png) and the convergence history.

A 3D run's design.png and pressure.png are drawn by :mod:`pacto_ng.post.plots3d` (off-screen
pyvista: the ρ̄ = 0.5 iso-surface and a cut at mid-depth); convergence.png is the same.

A case solved on a symmetric half (a straight boundary named ``symmetry``, any line: it is
computed from that boundary's vertices, :func:`~pacto_ng.post.domain.symmetry_line`) is drawn
whole: the half and its mirror image.  ``mirror=False`` draws the half alone; a mesh without a
straight ``symmetry`` boundary is drawn as it is.
"""
from __future__ import annotations

import numpy as np

from ..files import atomic_path
from .domain import Line, symmetry_line
from .domain import mirror as reflect
from .grid import mesh_to_pyvista
from .plots3d import design_picture, pressure_picture


def element_polygons(mesh) -> list[np.ndarray]:
    pts = np.array([v.point for v in mesh.vertices])
    return [pts[[v.nr for v in el.vertices]] for el in mesh.Elements()]


def mirror_line(mesh, mirror=True):
    """The symmetry line to mirror the pictures of ``mesh`` about: None with ``mirror=False``
    or when the mesh has no straight ``symmetry`` boundary; ``mirror`` may also be a
    :class:`~pacto_ng.post.domain.Line` (used as it is)."""
    if isinstance(mirror, Line):
        return mirror
    return symmetry_line(mesh) if mirror else None


def picture_polygons(mesh, values, mirror=True):
    """The element polygons of ``mesh`` and their per-element ``values`` (first axis), with
    the mirror images about the symmetry line appended (see the module docstring).

    Returns
    -------
    polygons : list of ndarray (k, 2)
    values : ndarray
        ``values`` repeated for the mirror images.
    line : Line or None
        The line mirrored about.
    """
    line = mirror_line(mesh, mirror)
    polys = [p[:, :2] for p in element_polygons(mesh)]
    values = np.asarray(values)
    if line is None:
        return polys, values, None
    return reflect(polys, line), np.concatenate([values, values]), line


def picture_triangulation(mesh, values, mirror=True):
    """The vertex triangulation of ``mesh`` (quads split) and per-vertex ``values``, with the
    mirror image appended: ``(Triangulation, values, line)``."""
    from matplotlib.tri import Triangulation

    tri = _triangulation(mesh)
    values = np.asarray(values)
    line = mirror_line(mesh, mirror)
    if line is None:
        return tri, values, None
    pts = np.c_[tri.x, tri.y]
    img = line.reflect(pts)
    n = len(pts)
    both = np.vstack([pts, img])
    tris = np.vstack([tri.triangles, tri.triangles[:, ::-1] + n])
    return Triangulation(both[:, 0], both[:, 1], tris), np.concatenate([values, values]), line


def _size(allpts):
    w = np.ptp(allpts[:, 0])
    h = np.ptp(allpts[:, 1])
    return (8, max(2.0, 8 * h / w))


def density_png(path, drawn, title: str | None = None, mirror=True):
    """design.png: the density ``drawn.shown`` (``drawn``: :class:`pacto_ng.outputs.Drawn`; 2D:
    grey polygons, mirrored about the symmetry line; 3D:
    :func:`~pacto_ng.post.plots3d.design_picture`)."""
    mesh, rho = drawn.mesh, np.asarray(drawn.shown)
    if mesh.dim == 3:
        design_picture(path, mesh_to_pyvista(mesh), rho, title=title or (
            f"{drawn.name} - {drawn.model}, volume {drawn.volume:.3f}"))
        return
    polys, rho, line = picture_polygons(mesh, rho, mirror)
    density_polygons_png(path, polys, rho, title or (
        f"{drawn.name} — {drawn.model}, ρ̄ (volume {drawn.volume:.3f})"
        + ("" if line is None else ", mirrored about the symmetry line")))


def density_polygons_png(path, polys, rho, title: str) -> None:
    """The densities ``rho`` of the element polygons ``polys`` (2D), grey from 0 to 1."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    allpts = np.concatenate(polys)
    fig, ax = plt.subplots(figsize=_size(allpts))
    pc = PolyCollection(polys, array=rho, cmap="gray_r", edgecolors="face", linewidths=0.1)
    pc.set_clim(0, 1)
    ax.add_collection(pc)
    ax.set_xlim(allpts[:, 0].min(), allpts[:, 0].max())
    ax.set_ylim(allpts[:, 1].min(), allpts[:, 1].max())
    ax.set_aspect("equal")
    ax.set_title(title)
    fig.colorbar(pc, ax=ax, fraction=0.03)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120)
    plt.close(fig)


def convergence_png(path, history: list, objective_name: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    it = [h["iteration"] for h in history]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(it, [h["objective"] for h in history], "b-", label=objective_name)
    ax.set_xlabel("iteration")
    ax.set_ylabel(objective_name, color="b")
    ax2 = ax.twinx()
    ax2.plot(it, [h["volume"] for h in history], "r--", label="volume fraction")
    ax2.set_ylabel("volume fraction", color="r")
    ax.set_title("convergence")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def _triangulation(mesh):
    """matplotlib Triangulation of the mesh vertices (quads split into two triangles)."""
    from matplotlib.tri import Triangulation

    pts = np.array([v.point for v in mesh.vertices])
    tris = []
    for el in mesh.Elements():
        vs = [v.nr for v in el.vertices]
        tris.append(vs[:3])
        if len(vs) == 4:
            tris.append([vs[0], vs[2], vs[3]])
    return Triangulation(pts[:, 0], pts[:, 1], np.array(tris))


def nodal_average(mesh, values, areas) -> np.ndarray:
    """Area-weighted average of element values at each vertex."""
    num = np.zeros(mesh.nv)
    den = np.zeros(mesh.nv)
    for el, val, a in zip(mesh.Elements(), values, areas):
        for v in el.vertices:
            num[v.nr] += a * val
            den[v.nr] += a
    return num / np.maximum(den, 1e-300)


def pressure_png(path, drawn, title: str | None = None, mirror=True):
    """The Darcy pressure field with the ρ̄ = 0.5 contour of the design drawn on it (as thesis
    Figs 6.9 and 6.18): colours p / P_in at the vertices, black line the contour of the
    nodal average of the element densities ``drawn.solid`` weighted by ``drawn.areas`` (the
    total solid for two materials); a 3D run: :func:`pacto_ng.post.plots3d.pressure_picture`.
    ``drawn.leak``: the design's Q/(Kv P_in), summary.json's ``leak``
    (:func:`pacto_ng.outputs.leak`), quoted in the title (None: not quoted)."""
    mesh, rho, pv, p_in = drawn.mesh, np.asarray(drawn.solid), drawn.p_rel, drawn.p_in
    quoted = "" if drawn.leak is None else f"leak Q/(Kv P_in) = {drawn.leak:.3g}"
    if mesh.dim == 3:
        pressure_picture(path, mesh_to_pyvista(mesh), pv, rho, title=title or (
            f"{drawn.name} (P_in = {p_in:g} Pa)" + (f", {quoted}" if quoted else "")))
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rho_n = nodal_average(mesh, rho, drawn.areas)
    tri, both, line = picture_triangulation(mesh, np.c_[pv, rho_n], mirror)
    pv, rho_n = both[:, 0], both[:, 1]
    x, y = tri.x, tri.y
    fig, ax = plt.subplots(figsize=_size(np.c_[x, y]))
    tpc = ax.tripcolor(tri, pv, shading="gouraud", cmap="coolwarm", vmin=0.0, vmax=1.0)
    if rho_n.min() < 0.5 < rho_n.max():
        ax.tricontour(tri, rho_n, levels=[0.5], colors="k", linewidths=1.0)
    ax.set_xlim(x.min(), x.max())
    ax.set_ylim(y.min(), y.max())
    ax.set_aspect("equal")
    ax.set_title(title or f"{drawn.name} — p / P_in (P_in = {p_in:g} Pa), "
                 f"ρ̄ = 0.5 contour" + (f"\n{quoted}" if quoted else ""), fontsize=10)
    fig.colorbar(tpc, ax=ax, fraction=0.03, label="p / P_in")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120)
    plt.close(fig)


def materials_png(path, drawn, title: str | None = None, mirror=True):
    """Two-material design (``drawn.materials``, 2D): void white, soft material (ρ̄2 = 0)
    orange, stiff (ρ̄2 = 1) blue; each element's colour is mixed by ρ̄2 and faded to white by
    ρ̄1."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    r1, r2 = (np.clip(np.asarray(r), 0, 1)[:, None] for r in drawn.materials)
    soft, stiff = np.array([0.93, 0.55, 0.13]), np.array([0.12, 0.30, 0.70])
    colours = (1 - r1) * 1.0 + r1 * ((1 - r2) * soft + r2 * stiff)
    polys, colours, _ = picture_polygons(drawn.mesh, colours, mirror)
    allpts = np.concatenate(polys)
    fig, ax = plt.subplots(figsize=_size(allpts))
    ax.add_collection(PolyCollection(polys, facecolors=colours, edgecolors="face", linewidths=0.1))
    ax.set_xlim(allpts[:, 0].min(), allpts[:, 0].max())
    ax.set_ylim(allpts[:, 1].min(), allpts[:, 1].max())
    ax.set_aspect("equal")
    ax.legend(handles=[Patch(color=soft, label="material 1 (soft)"),
                       Patch(color=stiff, label="material 2 (stiff)")],
              loc="upper right", fontsize=8)
    ax.set_title(title or f"{drawn.name} — ρ̄1 (solid) mixed by ρ̄2 (stiff fraction)")
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=120)
    plt.close(fig)
