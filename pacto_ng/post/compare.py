"""``pacto compare``: designs of several runs side by side, and their analysis curves.

2D runs: the designs' ρ̄, their thresholded outlines over each other and the analysis curves;
3D runs (:mod:`.compare3d`): the same for the 3D views, each design's ρ̄ = 0.5 iso-surface with
one camera and its mid-depth cut, the outlines on that cut, the curves.  Either way the table
of :func:`compare_table` is printed: one row per run.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.tri import Triangulation
from netgen.meshing import NgException
from netgen.occ import OCCException

from ..case import mesh_for
from ..errors import InputError
from ..files import atomic_path
from .compare3d import common_box, design_key, draw_designs, draw_outlines, read_design
from .domain import symmetry_line
from .pictures import figure
from .post3d import is_3d
from .report import fmt_value
from .runs import load_run


# ------------------------------------------------------------------------------------------
# pacto compare
def _design_triangles(vtu):
    """Points (n, 2), triangles (m, 3) with merged duplicate vertices, and the per-triangle
    ρ̄ of a run's design.vtu (NGSolve writes every element with its own vertices)."""
    import pyvista as pv

    g = pv.read(str(vtu))
    val = np.asarray(g.point_data[design_key(g, vtu)], dtype=float)
    pts = np.asarray(g.points)[:, :2]
    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    _, first, inv = np.unique(np.round(pts / scale, 9), axis=0, return_index=True,
                              return_inverse=True)
    inv = inv.ravel()
    tris, rho = [], []
    for ctype, conn in g.cells_dict.items():
        conn = np.asarray(conn)
        if conn.shape[1] == 3:
            t = conn
        elif conn.shape[1] == 4:
            t = np.r_[conn[:, [0, 1, 2]], conn[:, [0, 2, 3]]]
        else:
            continue
        tris.append(inv[t])
        rho.append(val[t].mean(axis=1))
    return pts[first], np.vstack(tris), np.concatenate(rho)


def _boundary_segments(vtu):
    import pyvista as pv

    g = pv.read(str(vtu))
    e = g.extract_feature_edges(boundary_edges=True, non_manifold_edges=False,
                                feature_edges=False, manifold_edges=False)
    lines = np.asarray(e.lines).reshape(-1, 3)[:, 1:]
    return np.asarray(e.points)[:, :2][lines]


def run_symmetry(run):
    """The symmetry line of a run's mesh (:func:`~pacto_ng.post.domain.symmetry_line`), from
    the case's mesh rebuilt; None when it has none or cannot be rebuilt."""
    try:
        mesh = mesh_for(run.case, run.params).mesh
    except (InputError, NgException, OCCException, RuntimeError):
        # the case's geometry or mesh refused (InputError), or Netgen / OCC failed: a picture
        # without its mirror image, not an error
        return None
    return symmetry_line(mesh)


def _mirrored_design(pts, tri, rho, line):
    """The design triangles with their mirror image about ``line`` appended."""
    if line is None:
        return pts, tri, rho
    n = len(pts)
    return (np.vstack([pts, line.reflect(pts)]), np.vstack([tri, tri[:, ::-1] + n]),
            np.concatenate([rho, rho]))


def _labels(runs) -> list[str]:
    """``case model load`` per run, with the folder name where two would read the same."""
    base = [f"{r.case.name} {r.params.model} {r.load:.3g} {r.case.load_unit}" for r, _ in runs]
    return [b + (f" ({r.path.name})" if base.count(b) > 1 else "")
            for b, (r, _) in zip(base, runs)]


#: the runs' colours, in order (the 11th run takes the first again)
_COLOURS = ["tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown",
            "tab:pink", "tab:gray", "tab:olive", "tab:cyan"]
#: the analysis curves' marker and line style per kind
_STYLE = {"expected": ("o", "--"), "darcy": ("s", "-"), "fixed": ("x", ":"),
          "follower": ("^", "-.")}


def compare_runs(folders, *, out=None, quiet: bool = False, mirror: bool = True) -> int:
    """``pacto compare``: the designs side by side, their thresholded outlines over each other
    (thesis Fig. 6.7) and, where ``analysis/analysis.json`` exists, their analysis curves in
    one picture (thesis Figs 6.10/6.12); the table of :func:`compare_table` printed.  A 2D run
    solved on a symmetric half is drawn whole (mirrored about its mesh's straight
    ``symmetry`` boundary) unless ``mirror`` is False; 3D runs: :mod:`.compare3d`."""
    runs = _read_runs(folders)
    dst = _destination(out)
    labels = _labels(runs)
    dims = {3 if is_3d(r) else 2 for r, _ in runs}
    if len(dims) > 1:
        raise InputError("compare: the runs are 2D and 3D; compare runs of one dimension")
    fig = _figure_3d(runs, labels) if dims == {3} else _figure_2d(runs, labels, mirror)
    with atomic_path(dst) as tmp:
        fig.savefig(str(tmp), dpi=130)
    if not quiet:
        print("\n".join(compare_table(runs)))
        print(f"picture: {dst}")
    return 0


def _figure_2d(runs, labels, mirror):
    """The 2D figure: the designs' ρ̄, the outlines over each other, the curves."""
    n = len(runs)
    lines = [run_symmetry(r) if mirror else None for r, _ in runs]
    designs = [_mirrored_design(*_design_triangles(r.path / "design.vtu"), ln)
               for (r, _), ln in zip(runs, lines)]
    allp = np.vstack([d[0] for d in designs])
    w, h = np.ptp(allp, axis=0)
    aspect = h / max(w, 1e-300)
    ncol = min(n, 3)
    nrow = -(-n // ncol)
    top_h = nrow * (4.2 * aspect + 0.7)
    fig = figure((12.0, top_h + 4.6))
    top, bottom = fig.subfigures(2, 1, height_ratios=[top_h, 4.6])
    _draw_designs(top, runs, designs, labels, nrow, ncol)
    # outlines over each other (thesis Fig. 6.7)
    ax, curves = _bottom_axes(bottom, runs)
    _draw_outlines(ax, runs, designs, lines, labels, allp)
    if curves is not None:
        _draw_curves(curves, runs)
    return fig


def _figure_3d(runs, labels):
    """The 3D figure (:mod:`.compare3d`): per run its iso-surface (one camera for all) and
    its mid-depth cut, then the outlines on the cuts over each other, the curves."""
    designs = [read_design(r.path / "design.vtu") for r, _ in runs]
    box = common_box(designs)
    n = len(runs)
    ncol = min(n, 3)
    nrow = -(-n // ncol)
    aspect = (box[3] - box[2]) / max(box[1] - box[0], 1e-300)
    width = 12.0 / ncol  # inches of one run's panels
    top_h = nrow * (width * (0.5 + aspect) + 1.4)  # the iso-surface's view, the cut's
    bottom_h = max(4.6, 5.5 * aspect + 1.8)
    fig = figure((12.0, top_h + bottom_h))
    top, bottom = fig.subfigures(2, 1, height_ratios=[top_h, bottom_h])
    colours = [_COLOURS[i % 10] for i in range(n)]
    draw_designs(top, designs, box, [_run_title(r, lab) for (r, _), lab in zip(runs, labels)],
                 colours, ncol)
    ax, curves = _bottom_axes(bottom, runs)
    draw_outlines(ax, [r.path for r, _ in runs], designs, box, labels, colours)
    if curves is not None:
        _draw_curves(curves, runs)
    return fig


def _bottom_axes(bottom, runs):
    """The outlines' axes and the curves' (None when no run was analysed)."""
    if any(a is not None for _, a in runs):
        return bottom.add_subplot(1, 2, 1), bottom.add_subplot(1, 2, 2)
    return bottom.add_subplot(1, 1, 1), None


def _run_title(run, label) -> str:
    """A design's title: its label, and Δ and the volume fraction when the run has them."""
    s = run.summary
    delta = s.get("output_displacement")
    return label + ("" if delta is None else
                    f"\nΔ = {delta:.3g} m, volume {s.get('volume_fraction', float('nan')):.3f}")


def _read_runs(folders) -> list:
    """``(run, analysis.json's content or None)`` per folder; InputError without a design."""
    if len(folders) < 1:
        raise InputError("compare: give at least one run folder")
    runs = []
    for f in folders:
        run = load_run(f, "compare")
        if not (run.path / "design.vtu").exists():
            raise InputError(f"compare: '{f}' has no design.vtu")
        ana = run.path / "analysis" / "analysis.json"
        runs.append((run, json.loads(ana.read_text()) if ana.exists() else None))
    return runs


def _destination(out) -> Path:
    """The picture's path (default ``compare.png``), its folder created."""
    dst = Path(out) if out else Path("compare.png")
    if dst.suffix.lower() != ".png":
        raise InputError(f"--out: '{dst}' must end in .png")
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"--out: cannot create '{dst.parent}' ({err.strerror})") from None
    return dst


def _draw_designs(top, runs, designs, labels, nrow, ncol) -> None:
    """The designs' ρ̄ side by side, each titled by its run (and Δ, volume)."""
    for i, ((run, ana), (pts, tri, rho)) in enumerate(zip(runs, designs)):
        ax = top.add_subplot(nrow, ncol, i + 1)
        ax.tripcolor(Triangulation(pts[:, 0], pts[:, 1], tri), facecolors=rho, cmap="gray_r",
                     vmin=0.0, vmax=1.0)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(_run_title(run, labels[i]), fontsize=9, color=_COLOURS[i % 10])


def _draw_outlines(ax, runs, designs, lines, labels, allp) -> None:
    """The thresholded outlines over each other: the remeshed part's boundary where the run
    was analysed, else the ρ̄ = 0.5 contour of the nodal (area-weighted) density."""
    for i, ((run, ana), (pts, tri, rho)) in enumerate(zip(runs, designs)):
        c = _COLOURS[i % 10]
        rem = run.path / "analysis" / "remeshed.vtu"
        if rem.exists():
            segs = _boundary_segments(rem)
            if lines[i] is not None:
                segs = np.concatenate([segs, lines[i].reflect(segs)])
            ax.add_collection(LineCollection(segs, colors=c, linewidths=1.2))
        else:
            t = Triangulation(pts[:, 0], pts[:, 1], tri)
            nod = np.zeros(len(pts))
            cnt = np.zeros(len(pts))
            e1, e2 = pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]
            area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
            for k in range(3):
                np.add.at(nod, tri[:, k], area * rho)
                np.add.at(cnt, tri[:, k], area)
            ax.tricontour(t, nod / np.maximum(cnt, 1e-300), levels=[0.5], colors=[c],
                          linewidths=1.2)
        ax.plot([], [], color=c, label=labels[i])
    ax.set_xlim(allp[:, 0].min(), allp[:, 0].max())
    ax.set_ylim(allp[:, 1].min(), allp[:, 1].max())
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("thresholded designs (remeshed outline, else ρ̄ = 0.5)", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08), frameon=False)


def _draw_curves(ax, runs) -> None:
    """The analysis curves Δ(p) of the runs that have one: expected and each re-analysis."""
    allpos = True
    for i, (run, ana) in enumerate(runs):
        if ana is None:
            continue
        c = _COLOURS[i % 10]
        P = np.array([r["pressure"] for r in ana["pressures"]])
        series = {"expected": [r["expected"] for r in ana["pressures"]]}
        for k in ana["settings"]["kinds"]:
            series[k] = [r[k]["delta"] for r in ana["pressures"]]
        for k, vals in series.items():
            v = np.array([np.nan if x is None else x for x in vals], dtype=float)
            ok = np.isfinite(v)
            if not ok.any():
                continue
            allpos &= bool(np.all(v[ok] > 0))
            m, ls = _STYLE.get(k, ("+", "-"))
            ax.plot(P[ok], v[ok], marker=m, ls=ls, color=c,
                    mfc="none" if k == "expected" else c)
    for k, (m, ls) in _STYLE.items():
        ax.plot([], [], marker=m, ls=ls, color="k", mfc="none" if k == "expected" else "k",
                label=k)
    ax.set_xscale("log")
    if allpos:
        ax.set_yscale("log")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("output displacement Δ (m)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, title="colour: run", title_fontsize=8)
    models = sorted({a["settings"]["model"] for _, a in runs if a is not None})
    ax.set_title(f"expected (optimisation) and the parts' re-analyses ({', '.join(models)})",
                 fontsize=9)


#: the re-analyses whose gap the table shows, in this order
_GAP_KINDS = ("darcy", "fixed", "follower")


def compare_table(runs) -> list[str]:
    """The table ``pacto compare`` prints: a header, then one row per run: its folder (the
    whole path where two share a name), case, model, load, mesh (dimension and elements),
    volume fraction, Δ and, for every kind some run was analysed with, the gap at its
    largest pressure (``—``: not analysed)."""
    kinds = [k for k in _GAP_KINDS if any(_gaps(a).get(k) is not None for _, a in runs)]
    head = ["run", "case", "model", "load", "mesh", "volume", "Δ (m)"] + [f"gap {k}"
                                                                        for k in kinds]
    names = [r.path.name for r, _ in runs]
    rows = []
    for (run, ana), name in zip(runs, names):
        s = run.summary
        mesh = s.get("mesh") if isinstance(s.get("mesh"), dict) else {}
        gaps = _gaps(ana)
        rows.append([name if names.count(name) == 1 else str(run.path), run.case.name,
                     run.params.model, f"{run.load:.3g} {run.case.load_unit}",
                     f"{mesh.get('dim', '?')}D, {mesh.get('elements', '?')} el.",
                     fmt_value(s.get("volume_fraction"), ".3f"),
                     fmt_value(s.get("output_displacement"), ".4g")]
                    + ["—" if gaps.get(k) is None else f"{100 * gaps[k]:+.1f} %" for k in kinds])
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    left = 3  # run, case, model: left-aligned; the numbers right-aligned
    return ["  ".join(c.ljust(w) if i < left else c.rjust(w)
                      for i, (c, w) in enumerate(zip(r, widths))).rstrip()
            for r in [head] + rows]


def _gaps(ana) -> dict:
    """``{kind: gap}`` at the largest pressure of an analysis.json (none: not analysed, or a
    part as built)."""
    return (ana or {}).get("gap_at_largest_pressure") or {}
