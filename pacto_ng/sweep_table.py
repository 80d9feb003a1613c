"""The table and picture of a sweep (``pacto sweep``): ``sweep.csv``, one row per run read
from its ``summary.json``, ``sweep.png``, and the progress line of a finished run.
"""
from __future__ import annotations

import csv
import io
import math
import os
from pathlib import Path

from .files import atomic_path, atomic_write_text
from .sweep_plan import SweepRun, read_json

COLUMNS = ("model", "load", "objective", "output_displacement", "load_reached", "converged",
           "iterations", "wall_time_s", "folder", "stopped")


def table_row(out: str | os.PathLike, run: SweepRun, error: str | None = None) -> dict:
    """One row of sweep.csv from the run's ``summary.json``.

    A run without a summary (it raised, or never ran) is a row with ``converged = False`` and
    ``stopped = "error"`` (or ``"missing"`` when no error is known).
    """
    summ = read_json(Path(out) / run.folder / "summary.json")
    row = {"model": run.model, "load": run.load, "folder": run.folder}
    if summ is None or "objective" not in summ:
        row.update(objective=None, output_displacement=None, load_reached=None, converged=False,
                   iterations=None, wall_time_s=None, stopped="error" if error else "missing")
        return row
    stopped = summ.get("stopped")
    factor = summ.get("load_factor_reached")
    if isinstance(factor, (int, float)) and factor < 1 - 1e-9:
        stopped = "newton"  # also when only the final analysis of the design failed
    row.update(objective=summ.get("objective"), output_displacement=summ.get("output_displacement"),
               load_reached=summ.get("load_reached"),
               converged=bool(summ.get("converged")) and stopped != "newton",
               iterations=summ.get("iterations"), wall_time_s=summ.get("wall_time_s"),
               stopped=stopped, objective_name=summ.get("objective_name"))
    return row


def collect_table(out: str | os.PathLike, runs, errors: dict | None = None) -> list[dict]:
    """Rows of sweep.csv for ``runs`` (grid order); ``errors`` maps folder -> error text."""
    errors = errors or {}
    return [table_row(out, r, errors.get(r.folder)) for r in runs]


def _cell(val):
    if val is None:
        return ""
    if isinstance(val, bool):
        return "true" if val else "false"
    if isinstance(val, float):
        return repr(val)
    return val


def write_csv(path: str | os.PathLike, rows: list[dict]) -> None:
    """Write the table (``COLUMNS``; empty cells for missing values, converged as true/false)."""
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(COLUMNS)
    for row in rows:
        w.writerow([_cell(row.get(c)) for c in COLUMNS])
    atomic_write_text(path, buf.getvalue())


def plot_sweep(path: str | os.PathLike, rows: list[dict], title: str = "",
               load_unit: str = "") -> None:
    """Output displacement and objective against load (log x), one line per model.

    Runs that did not reach their load (Newton failure) are drawn as open markers at the values
    they report; a quantity the case does not compute is stated in its panel.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    models = list(dict.fromkeys(r["model"] for r in rows))
    for ax, key, label in ((axes[0], "output_displacement", "output displacement"),
                           (axes[1], "objective", "objective")):
        pts = [r for r in rows if isinstance(r.get(key), (int, float)) and math.isfinite(r[key])]
        for i, m in enumerate(models):
            mine = sorted((r for r in pts if r["model"] == m), key=lambda r: r["load"])
            if not mine:
                continue
            color = f"C{i}"
            ax.plot([r["load"] for r in mine], [r[key] for r in mine], "-o", color=color, label=m)
            bad = [r for r in mine if r.get("stopped") in ("newton", "error")]
            if bad:
                ax.plot([r["load"] for r in bad], [r[key] for r in bad], "o", ms=11,
                        mfc="none", color="k", label=f"{m}: load not reached")
        ax.set_xscale("log")
        if pts and all(r[key] > 0 for r in pts):
            ax.set_yscale("log")
        if not pts:
            ax.text(0.5, 0.5, f"no {label} in this case", ha="center", va="center",
                    transform=ax.transAxes)
        else:
            ax.legend(fontsize=8)
        names = sorted({r["objective_name"] for r in pts if r.get("objective_name")})
        ax.set_xlabel(f"load ({load_unit})" if load_unit else "load")
        ax.set_ylabel(f"{label} ({', '.join(names)})" if key == "objective" and names else label)
        ax.grid(True, which="both", alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


def _fmt(val, spec=".4e"):
    return "n/a" if val is None else format(val, spec)


_STOPPED = {"converged": "converged", "iterations": "iteration limit",
            "newton": "Newton failure: load not reached"}


def progress_line(i: int, n: int, row: dict, how: str) -> str:
    """One line for a finished run, e.g. ``[2/4] linear-1e5 (new): objective 5.5e+10, ...``."""
    if row["stopped"] in ("error", "missing"):
        return f"[{i}/{n}] {row['folder']} ({how}): FAILED, no summary"
    return (f"[{i}/{n}] {row['folder']} ({how}): objective {_fmt(row['objective'])}, output "
            f"displacement {_fmt(row['output_displacement'])}, load reached "
            f"{_fmt(row['load_reached'], 'g')} of {row['load']:g}, {row['iterations']} iterations "
            f"({_STOPPED.get(row['stopped'], row['stopped'])}), "
            f"{_fmt(row['wall_time_s'], '.1f')} s")
