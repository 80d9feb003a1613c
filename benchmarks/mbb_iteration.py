"""Time per MBB optimisation iteration against one factorisation + solve at the same size.

    python -m benchmarks.mbb_iteration [--sizes 60x20,120x40,240x80,480x160] [--repeat 3]

For each structured mesh: the median wall time of an optimisation iteration (analysis,
sensitivities, MMA update; measured over iterations 2..N of a run) and the median time of one
sparse Cholesky factorisation plus one solve of the same stiffness matrix (NGSolve, the same
inverse type).  The ratio is what the issue asks for (aim <= 3).  Prints a markdown table.
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
    from pacto_ng.run import initial_design, schedule_of

    case = get_case(case_name)
    params = case.defaults.with_overrides({"nelx": str(nelx), "nely": str(nely),
                                           "iterations": str(iterations)})
    problem = build_problem(case, params)
    state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
    optimize(problem, schedule_of(params), iterations=iterations, tol=0.0, method="mma",
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


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="60x20,120x40,240x80,480x160")
    ap.add_argument("--iterations", type=int, default=8)
    args = ap.parse_args(argv)
    rows = []
    for s in args.sizes.split(","):
        nx, ny = (int(v) for v in s.split("x"))
        rows.append(measure(nx, ny, args.iterations))
    print("| mesh | dofs | time per iteration (median) [s] | factorisation + solve [s] | ratio |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mesh']} | {r['dofs']} | {r['per_iteration']:.4f} | {r['factor_solve']:.4f} "
              f"| {r['ratio']:.2f} |")
    return rows


if __name__ == "__main__":
    main()
