"""Determinism: the same command twice gives bit-identical results, with one thread and with two.

    python -m benchmarks.determinism [--out DIR]

Runs each command four times (PACTO_THREADS=1 twice, PACTO_THREADS=2 twice), each in its own
process and folder, and compares every run's summary.json objective figures and history.csv
bit for bit: within one thread count, and across the two counts.  Prints one line per command
and comparison: the largest difference (relative to its figure's or column's magnitude; the
wall-time column is left out) and the final objective's relative difference.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

COMMANDS = {
    "pa-inverter linear 60x40": ["run", "pa-inverter", "--nelx", "60", "--nely", "40",
                                 "--set", "iterations=30"],
    "pa-inverter neohookean 30x20": ["run", "pa-inverter", "--model", "neohookean", "--nelx",
                                     "30", "--nely", "20", "--set", "iterations=15"],
    "cantilever triangles": ["run", "cantilever", "--maxh", "0.04", "--set", "iterations=20"],
}
FIGURES = ("objective", "volume", "delta", "compliance", "strain_energy", "output_displacement")


def _run(argv: list[str], out: Path, threads: int) -> None:
    env = {**os.environ, "PACTO_THREADS": str(threads)}
    subprocess.run([sys.executable, "-m", "pacto_ng.cli", *argv, "--quiet", "--out", str(out)],
                   env=env, check=True)


def _read(out: Path) -> dict:
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "history.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    columns = {}
    for row in rows:
        for key, cell in row.items():
            if key == "time":  # wall time: never repeats
                continue
            try:
                columns.setdefault(key, []).append(float(cell))
            except ValueError:
                pass
    figures = {k: summary[k] for k in FIGURES if isinstance(summary.get(k), (int, float))}
    return {"figures": figures, "columns": columns}


def _difference(a: dict, b: dict) -> tuple[float, str]:
    """The largest difference between two runs, relative to the largest magnitude of its figure
    or history column, and where it is (0.0 and '' when identical)."""
    worst, where = 0.0, ""
    series = {f"summary {k}": ([v], [b["figures"].get(k)]) for k, v in a["figures"].items()}
    series.update({f"history {k}": (v, b["columns"].get(k)) for k, v in a["columns"].items()})
    for name, (x, y) in series.items():
        if y is None or None in y or len(x) != len(y):
            return float("inf"), name + " missing or of another length"
        x, y = np.asarray(x), np.asarray(y)
        scale = max(np.abs(x).max(), np.abs(y).max())
        if scale > 0 and not np.array_equal(x, y):
            d = float(np.abs(x - y).max() / scale)
            if d > worst:
                worst, where = d, name
    return worst, where


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="folder of the runs (default: a temporary folder)")
    ap.add_argument("--reuse", action="store_true", help="compare the runs already in --out")
    args = ap.parse_args(argv)
    root = Path(args.out or tempfile.mkdtemp(prefix="pacto-determinism-"))
    for name, cmd in COMMANDS.items():
        runs = {}
        for threads in (1, 2):
            for rep in (0, 1):
                folder = root / f"{name.replace(' ', '_')}-{threads}-{rep}"
                if not args.reuse:
                    _run(cmd, folder, threads)
                runs[threads, rep] = _read(folder)
        for label, a, b in (("1 thread twice", (1, 0), (1, 1)),
                            ("2 threads twice", (2, 0), (2, 1)),
                            ("1 against 2 threads", (1, 0), (2, 0))):
            diff, where = _difference(runs[a], runs[b])
            fa, fb = runs[a]["figures"]["objective"], runs[b]["figures"]["objective"]
            print(f"{name:30s} {label:20s} largest {diff:.2e} ({where or 'identical'}); "
                  f"final objective {abs(fa - fb) / abs(fa):.2e} relative", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
