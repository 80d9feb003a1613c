"""Time per MBB optimisation iteration against one factorisation + solve at the same size.

    python -m benchmarks.mbb_iteration [--sizes 60x20,120x40,240x80,480x160] [--runs 3]

The structured half MBB beam (the 88-line set-up: unit elements, linear, SIMP p = 3, MMA), on
2 NGSolve threads in a TaskManager.  For each mesh and each of ``--runs`` runs: the median
wall time of an optimisation iteration (analysis, sensitivities, MMA update; over iterations
2..8 of an 8-iteration run) and the median time of one sparse Cholesky factorisation (symbolic
and numeric, a new ``Inverse``) plus one solve of the same stiffness matrix.  The table gives
the medians over the runs, their ratio, and the range of the runs' own ratios.  Aim: ratio <= 3
(an iteration costs at most three factorisations).
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def short_optimisation(case_name: str, nelx: int, nely: int, iterations: int):
    """Build ``case_name`` on a structured nelx x nely mesh and run ``iterations`` MMA
    iterations (no convergence stop).  Call inside a TaskManager.  Returns (problem, state)."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.optimize.driver import LoopState, optimize
    from pacto_ng.initial import initial_design

    case = get_case(case_name)
    params = case.defaults.with_overrides({"nelx": str(nelx), "nely": str(nely),
                                           "iterations": str(iterations)})
    problem = build_problem(case, params)
    state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
    optimize(problem, params.schedule.schedule(), iterations=iterations, tol=0.0, method="mma",
             move=params.move, state=state)
    return problem, state


def measure(nelx: int, nely: int, iterations: int = 8, repeat: int = 3):
    from pacto_ng.threads import compute

    with compute(threads=2):
        problem, state = short_optimisation("mbb", nelx, nely, iterations)
        per_it = statistics.median(h["time"] for h in state.history[1:])
        # one factorisation + solve of the same matrix
        mech = problem.mech
        mech.assemble_tangent(mech.gfu.vec, 1.0)
        times = []
        rhs = mech.gfu.vec.CreateVector()
        rhs.SetRandom()
        out = rhs.CreateVector()
        for _ in range(repeat):
            t0 = time.perf_counter()
            inv = mech.matrix.Inverse(mech.fes.FreeDofs(), inverse="sparsecholesky")
            out.data = inv * rhs
            times.append(time.perf_counter() - t0)
        fs = statistics.median(times)
    return dict(mesh=f"{nelx} x {nely}", dofs=mech.fes.ndof, per_iteration=per_it,
                factor_solve=fs, ratio=per_it / fs)


SIZES = ((60, 20), (120, 40), (240, 80), (480, 160))


def study(sizes=SIZES, runs=3, iterations=8):
    """One row per mesh: medians over ``runs`` runs of :func:`measure`."""
    rows = []
    for nx, ny in sizes:
        rs = [measure(nx, ny, iterations) for _ in range(runs)]
        per = statistics.median(r["per_iteration"] for r in rs)
        fs = statistics.median(r["factor_solve"] for r in rs)
        ratios = [r["ratio"] for r in rs]
        rows.append(dict(mesh=rs[0]["mesh"], dofs=rs[0]["dofs"], per_iteration=per,
                         factor_solve=fs, ratio=per / fs, ratio_min=min(ratios),
                         ratio_max=max(ratios), runs=runs))
        print(f"  mbb {nx}x{ny}: ratio {per / fs:.2f} ({min(ratios):.2f}-{max(ratios):.2f})",
              flush=True)
    return rows


def markdown(rows):
    out = ["| mesh | dofs | time per iteration [s] | factorisation + solve [s] | ratio | "
           "runs' ratios |", "|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['mesh']} | {r['dofs']} | {r['per_iteration']:.4f} | "
                   f"{r['factor_solve']:.4f} | {r['ratio']:.2f} | {r['ratio_min']:.2f}-"
                   f"{r['ratio_max']:.2f} |")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default=",".join(f"{x}x{y}" for x, y in SIZES))
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--iterations", type=int, default=8)
    args = ap.parse_args(argv)
    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    rows = study(sizes, args.runs, args.iterations)
    print(markdown(rows))
    return rows


if __name__ == "__main__":
    main()
