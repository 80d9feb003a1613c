"""Determinism: the same command twice gives bit-identical results, with one thread and with two.

    python -m benchmarks.determinism [--out DIR]

Runs each command four times (PACTO_THREADS=1 twice, PACTO_THREADS=2 twice), each in its own
process and folder, and compares every run's summary.json objective figures and history.csv
bit for bit: within one thread count, and across the two counts.  Prints one line per command
and comparison with the largest relative difference (0 when identical).
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

COMMANDS = {
    "pa-inverter linear 60x40": ["run", "pa-inverter", "--nelx", "60", "--nely", "40",
                                 "--set", "iterations=30"],
    "pa-inverter neohookean 30x20": ["run", "pa-inverter", "--model", "neohookean", "--nelx",
                                     "30", "--nely", "20", "--set", "iterations=15"],
    "cantilever triangles": ["run", "cantilever", "--maxh", "0.04", "--set", "iterations=20"],
}
FIGURES = ("objective", "volume", "delta", "compliance", "strain_energy", "output_displacement")


def _run(argv: list[str], out: Path, threads: int) -> dict:
    env = {**os.environ, "PACTO_THREADS": str(threads)}
    subprocess.run([sys.executable, "-m", "pacto_ng.cli", *argv, "--quiet", "--out", str(out)],
                   env=env, check=True)
    summary = json.loads((out / "summary.json").read_text())
    with open(out / "history.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    figures = {k: summary[k] for k in FIGURES if isinstance(summary.get(k), (int, float))}
    numbers = []
    for row in rows[1:]:
        for cell in row:
            try:
                numbers.append(float(cell))
            except ValueError:
                pass
    return {"figures": figures, "history": numbers, "header": rows[0]}


def _difference(a: dict, b: dict) -> float:
    """The largest relative difference between two runs' figures and history (0: identical)."""
    worst = 0.0
    pairs = [(a["figures"][k], b["figures"].get(k)) for k in a["figures"]]
    if len(a["history"]) != len(b["history"]):
        return float("inf")
    pairs += list(zip(a["history"], b["history"]))
    for x, y in pairs:
        if y is None:
            return float("inf")
        if x != y:
            worst = max(worst, abs(x - y) / max(abs(x), abs(y)))
    return worst


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="folder of the runs (default: a temporary folder)")
    args = ap.parse_args(argv)
    root = Path(args.out or tempfile.mkdtemp(prefix="pacto-determinism-"))
    for name, cmd in COMMANDS.items():
        runs = {}
        for threads in (1, 2):
            for rep in (0, 1):
                runs[threads, rep] = _run(cmd, root / f"{name.replace(' ', '_')}-{threads}-{rep}",
                                          threads)
        one = _difference(runs[1, 0], runs[1, 1])
        two = _difference(runs[2, 0], runs[2, 1])
        across = _difference(runs[1, 0], runs[2, 0])
        print(f"{name:32s} 1 thread twice: {one:.3e}   2 threads twice: {two:.3e}   "
              f"1 against 2 threads: {across:.3e}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
