"""One design on several MPI ranks: per-dof time and memory, strong and weak scaling.

    python3 -m benchmarks scaling [--out docs/scaling.md] [--runs DIR] [--iterations N]

``pacto run cantilever-3d`` (linear; CG with BDDC, the route a distributed mesh takes) for
``--iterations`` iterations at several tetrahedron sizes and element orders 1 and 2 (BDDC's
coarse space is the vertices: every dof at order 1), serially and under ``mpirun -n 3``
(rank 0 holds no element: 2 parts, one per core of this machine).  Time per iteration: the
median of the history's iteration times after the first (which assembles and sets up once).
Memory: the peak resident size of the largest process (``ru_maxrss`` of the children), and
its ratio to the dofs.  Strong scaling: the same mesh on 1 and on 2 parts; weak scaling: twice
the dofs on 2 parts.  Writes the block ``scaling`` of ``--out``.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import time

CASE = "cantilever-3d"
# (element order, tetrahedron size in m), each on 1 and 2 parts
STRONG = ((1, 0.02), (1, 0.014), (2, 0.03), (2, 0.02))
# (order, serial size, 2-part size with about twice the dofs)
WEAK = ((1, 0.02, 0.02 / 2 ** (1 / 3)), (2, 0.03, 0.03 / 2 ** (1 / 3)))


def run(ranks: int, order: int, maxh: float, out: str, iterations: int) -> dict:
    """One run (reused when its summary exists); its figures."""
    summary = os.path.join(out, "summary.json")
    if not os.path.exists(summary):
        args = ["run", CASE, "--maxh", f"{maxh:g}", "--order", str(order),
                "--iterations", str(iterations),
                "--set", "solver=iterative", "--out", out, "--quiet", "--overwrite"]
        cmd = [sys.executable, "-m", "pacto_ng.cli", *args]
        if ranks > 1:
            mpirun = [shutil.which("mpirun"), "-n", str(ranks + 1), "--oversubscribe"]
            if os.geteuid() == 0:
                mpirun.append("--allow-run-as-root")
            cmd = mpirun + [sys.executable, "-m", "mpi4py", "-m", "pacto_ng.cli", *args]
        # a fresh parent per run: its children's peak is this run's largest process
        probe = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True); "
                 "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
        t0 = time.perf_counter()
        env = dict(os.environ, PACTO_THREADS="1", OMPI_MCA_mpi_yield_when_idle="1")
        done = subprocess.run([sys.executable, "-c", probe, *cmd], check=True, env=env,
                              capture_output=True, text=True)
        with open(os.path.join(out, "measured.json"), "w") as fh:
            json.dump({"wall": time.perf_counter() - t0,
                       "peak_kb": int(done.stdout.split()[-1])}, fh)
    s = json.load(open(summary))
    measured = json.load(open(os.path.join(out, "measured.json")))
    with open(os.path.join(out, "history.csv")) as fh:
        times = sorted(float(r["time"]) for r in list(csv.DictReader(fh))[1:])
    return {"ranks": ranks, "order": order, "maxh": maxh, "elements": s["mesh"]["elements"],
            "dofs": s["mesh"]["displacement_dofs"], "iteration_s": times[len(times) // 2],
            "peak_mb": measured["peak_kb"] / 1024,
            "objective": s["objective"]}


def report(strong: list, weak: list, iterations: int) -> str:
    from benchmarks.__main__ import machine

    lines = [f"`python3 -m benchmarks scaling --iterations {iterations}` ({machine()}).", "",
             "### Strong scaling: one mesh on 1 and 2 parts", "",
             "| order | elements | displacement dofs | parts | s / iteration | speed-up | "
             "parallel efficiency | peak MB (largest process) | µs / iteration / dof | "
             "objective |", "|---|---|---|---|---|---|---|---|---|---|"]
    for one, two in strong:
        for r in (one, two):
            speed = one["iteration_s"] / r["iteration_s"]
            lines.append(f"| {r['order']} | {r['elements']:,} | {r['dofs']:,} | "
                         f"{max(r['ranks'], 1)} | "
                         f"{r['iteration_s']:.3f} | {speed:.2f} | "
                         f"{speed / max(r['ranks'], 1):.2f} | {r['peak_mb']:.0f} | "
                         f"{1e6 * r['iteration_s'] / r['dofs']:.1f} | {r['objective']:.6g} |")
    lines += ["", "### Weak scaling: twice the dofs on twice the parts", "",
              "| order | parts | elements | displacement dofs | dofs / part | s / iteration | "
              "efficiency (1-part time / this time) |", "|---|---|---|---|---|---|---|"]
    for one, two in weak:
        for r in (one, two):
            parts = max(r["ranks"], 1)
            lines.append(f"| {r['order']} | {parts} | {r['elements']:,} | {r['dofs']:,} | "
                         f"{r['dofs'] // parts:,} | {r['iteration_s']:.3f} | "
                         f"{one['iteration_s'] / r['iteration_s']:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python3 -m benchmarks scaling")
    ap.add_argument("--out", default="docs/scaling.md")
    ap.add_argument("--runs", default="output/bench-scaling")
    ap.add_argument("--iterations", type=int, default=5)
    a = ap.parse_args(argv)
    os.environ["PACTO_THREADS"] = "1"  # every run and the report's machine line: one thread
    it = a.iterations
    folder = lambda ranks, k, h: os.path.join(a.runs, f"r{ranks}-p{k}-h{h:g}")
    strong = [(run(1, k, h, folder(1, k, h), it), run(2, k, h, folder(2, k, h), it))
              for k, h in STRONG]
    weak = [(run(1, k, h1, folder(1, k, h1), it), run(2, k, h2, folder(2, k, h2), it))
            for k, h1, h2 in WEAK]
    from benchmarks.__main__ import replace_block

    replace_block(a.out, "scaling", report(strong, weak, it))
    print(f"wrote the block 'scaling' of {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
