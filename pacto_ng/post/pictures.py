"""Pictures of a post-analysis, drawn with matplotlib's Agg canvas (no screen, no change of
the global backend): ``deformed.png`` (:func:`plot_deformed`), ``analysis.png``
(:func:`plot_sweeps`) and ``materials.png`` (:func:`plot_materials`), and the figure they
share (:func:`figure`).  The files of a post-analysis (STL, VTU): :mod:`.export`.
"""
from __future__ import annotations

import numpy as np

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.tri import Triangulation

from ..files import atomic_path
from .export import material_ids, mesh_arrays
from .materials import INTERFACE
from .plots import mirror_line


def figure(figsize):
    """A matplotlib figure of ``figsize`` (inches), constrained layout, on an Agg canvas."""
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _framed(lo, hi):
    """A figure and axes sized to the box ``[lo, hi]`` (m), equal aspect, a 3 % margin."""
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-300)
    fig = figure((7.0, float(np.clip(5.6 * aspect + 1.4, 3.0, 9.0))))
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    pad = 0.03 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return fig, ax


def plot_deformed(path, mesh, u, *, title: str | None = None, dpi: int = 150, mirror=True,
                  contact=None):
    """``deformed.png``: the deformed solid coloured by |u| over the undeformed outline.

    True scale (no magnification), equal axes; the outline is every boundary edge of the
    reference mesh.  ``mirror``: a :class:`~pacto_ng.post.domain.Line` to draw the mirror
    image about too (a part solved on a symmetric half), True for the line of ``mesh``'s own
    straight ``symmetry`` boundary if it has one, False for the half alone.  ``contact``: the
    reference positions ``(n, 2)`` of the walls' vertices in contact, drawn as red dots where
    ``u`` moves them (:meth:`~.sweep_result.Sweep.contact_points`).
    """
    from ngsolve import BND

    pts, blocks = mesh_arrays(mesh)
    uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy()))).reshape(-1, 2)
    tris = [b for t, b in blocks if t == "triangle"]
    for t, b in blocks:
        if t == "quad":
            tris.append(np.r_[b[:, [0, 1, 2]], b[:, [0, 2, 3]]])
    tri = np.vstack(tris)
    mag = np.linalg.norm(uv, axis=1)
    line = mirror_line(mesh, mirror)
    # mirrored, the symmetry boundary is inside the whole part: not drawn
    segs = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                     if line is None or el.mat != "symmetry"]).reshape(-1, 2, 2)
    def_pts = pts + uv
    touch = np.zeros((0, 2)) if contact is None else np.asarray(contact, dtype=float)
    if len(touch):  # where u moves them
        moved = u(mesh(touch[:, 0].copy(), touch[:, 1].copy()))
        touch = touch + np.asarray(moved).reshape(-1, 2)
    if line is not None:  # the mirror image: reflected positions, same |u|
        n = len(pts)
        tri = np.vstack([tri, tri[:, ::-1] + n])
        mag = np.r_[mag, mag]
        segs = np.concatenate([segs, line.reflect(segs)])
        pts = np.vstack([pts, line.reflect(pts)])
        def_pts = np.vstack([def_pts, line.reflect(def_pts)])
        touch = np.vstack([touch, line.reflect(touch)]) if len(touch) else touch
    lo = np.minimum(pts.min(axis=0), def_pts.min(axis=0))
    hi = np.maximum(pts.max(axis=0), def_pts.max(axis=0))
    fig, ax = _framed(lo, hi)
    tc = ax.tripcolor(Triangulation(def_pts[:, 0], def_pts[:, 1], tri), mag, shading="gouraud",
                      cmap="viridis")
    ax.add_collection(LineCollection(segs, colors="k", linewidths=0.8))
    if len(touch):
        ax.plot(touch[:, 0], touch[:, 1], "o", color="red", ms=2.5, ls="none",
                label="walls in contact")
        ax.legend(loc="upper right", fontsize="small", framealpha=0.8)
    # said under the axis (a legend below a wide, flat part ran into the axis label)
    ax.set_xlabel(f"{ax.get_xlabel()}; black: the undeformed outline")
    fig.colorbar(tc, ax=ax, label="|u| (m), deformed solid", shrink=0.9)
    ax.set_title(title or "deformed solid (true scale) over the undeformed outline")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path


_STYLE = {"expected": ("o", "expected (optimisation)"),
          "fixed": ("s", "fixed pressure (deformation independent)"),
          "follower": ("^", "follower pressure"),
          "darcy": ("D", "Darcy pressure (deformation independent)")}


def plot_sweeps(path, sweeps, *, expected=None, title: str | None = None, dpi: int = 150,
                log: bool = False):
    """``analysis.png``: output displacement Δ against pressure.

    Parameters
    ----------
    sweeps : dict ``kind -> Sweep`` or iterable of Sweep
        Non-converged points are left out.
    expected : tuple ``(pressures, deltas)``, optional
        The displacements the optimisation predicted.
    log : bool
        Logarithmic pressure axis, and logarithmic Δ axis when every plotted Δ is positive.
    """
    fig = figure((6.5, 4.5))
    ax = fig.add_subplot()
    if expected is not None:
        pe, de = (np.asarray(a, dtype=float) for a in expected)
        m, lab = _STYLE["expected"]
        ax.plot(pe, de, m, ls="none", mfc="none", ms=8, label=lab)
    items = sweeps.values() if isinstance(sweeps, dict) else sweeps
    for sw in items:
        ok = sw.converged.astype(bool)
        m, lab = _STYLE.get(sw.kind, ("x", sw.kind))
        ax.plot(sw.pressures[ok], sw.delta[ok], marker=m, label=lab)
    if log:
        ax.set_xscale("log")
        ys = np.concatenate([ln.get_ydata() for ln in ax.get_lines()] or [np.zeros(0)])
        if ys.size and np.all(ys > 0):
            ax.set_yscale("log")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("output displacement Δ (m)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(title or "output displacement against pressure")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path


_MATERIAL_COLOURS = {"soft": "#ee8c2c", "stiff": "#2a4fb0"}


def plot_materials(path, mesh, *, title: str | None = None, dpi: int = 150, mirror=True):
    """``materials.png``: the remeshed part's elements coloured by material (soft orange,
    stiff blue, the colours of the run's ``materials.png``), the part's boundary in black and
    the ``interface`` between the materials in red; mirrored like :func:`plot_deformed`."""
    from ngsolve import BND

    pts, _ = mesh_arrays(mesh)
    ids, names = material_ids(mesh)
    name_of = {int(v[0]): k for k, v in names.items()}
    polys = [pts[[v.nr - 1 for v in el.vertices]] for el in mesh.ngmesh.Elements2D()]
    colours = [_MATERIAL_COLOURS.get(name_of[i], "0.6") for i in ids]
    outline = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                        if el.mat != INTERFACE]).reshape(-1, 2, 2)
    inner = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                      if el.mat == INTERFACE]).reshape(-1, 2, 2)
    line = mirror_line(mesh, mirror)
    if line is not None:
        polys = polys + [line.reflect(p) for p in polys]
        colours = colours + colours
        outline = np.concatenate([outline, line.reflect(outline)])
        inner = np.concatenate([inner, line.reflect(inner)])
    allp = np.vstack(polys)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fig, ax = _framed(lo, hi)
    ax.add_collection(PolyCollection(polys, facecolors=colours, edgecolors="none"))
    ax.add_collection(LineCollection(outline, colors="k", linewidths=0.8))
    if len(inner):
        ax.add_collection(LineCollection(inner, colors="r", linewidths=0.8))
    handles = [Patch(color=_MATERIAL_COLOURS.get(n, "0.6"), label=n) for n in names]
    if len(inner):
        handles.append(Patch(color="r", label=INTERFACE))
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.14), frameon=False,
              ncol=len(handles))
    ax.set_title(title or "the remeshed part's materials")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path
