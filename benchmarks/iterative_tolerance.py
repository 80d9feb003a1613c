"""The iterative route's tolerance: what Newton's residual tolerance costs and what it changes.

    python3 -m benchmarks iterative_tolerance [--iterations 25] [--out docs/studies.md]
    python3 -m benchmarks.iterative_tolerance --no-write

The two 3D linear cases at order 2 on their default meshes, every system on the iterative route
(`--set solver=iterative`: CG with BDDC).  First a run of `--iterations` optimisation
iterations with Newton's tolerance at 1e-10 of the load (the direct route's default); its last
design is then analysed once per tolerance `newton_rtol` (the adjoint's Krylov tolerance is a
tenth of it, pacto_ng/physics/solvers.py `adjoint_rtol`; the Darcy and filter solves keep
1e-12), against the analysis at 1e-12: the objective's relative error, the gradient's largest
error relative to its largest entry, and the CG iterations of the displacement (equilibrium
and adjoint).  Then a second run of the same length with no tolerance set (the route's default,
pacto_ng/physics/newton.py `ITERATIVE_RTOL`), against the first: the largest relative
difference of the objective histories and the largest difference of the final design
variables.  The optimiser stops on a design change below `tol` (0.01) or an objective change
below `obj_tol` (1e-4, relative) over five iterations.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

CASES = ("cantilever-3d", "pneunet-3d")
TOLERANCES = (1e-10, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4)
REFERENCE = 1e-12


def _analyse(case, x, k, rtol):
    """Objective, gradient, displacement CG iterations and seconds of one analysis of ``x``
    at the schedule of iteration ``k`` with Newton's tolerance ``rtol``."""
    from pacto_ng.api import case_parameters
    from pacto_ng.case import build_problem

    params = case_parameters(case, {"order": 2, "solver": "iterative", "newton_rtol": rtol})
    problem = build_problem(case, params)
    problem.mech.expect_many_designs()
    problem.apply_schedule(*params.schedule.schedule().values(k, []))
    start = time.perf_counter()
    f0, _, df0, _ = problem.evaluate(x)
    seconds = time.perf_counter() - start
    return f0, df0, problem.mech.solver_info["total_iterations"], seconds


def study(iterations: int, folder: str) -> list[dict]:
    from pacto_ng.api import run
    from pacto_ng.case import get_case
    from pacto_ng.threads import compute

    rows = []
    for name in CASES:
        case = get_case(name)
        tight = run(case, os.path.join(folder, f"{name}-tight"), order=2, solver="iterative",
                    newton_rtol=1e-10, iterations=iterations, overwrite=True)
        default = run(case, os.path.join(folder, f"{name}-default"), order=2,
                      solver="iterative", iterations=iterations, overwrite=True)
        h_t = np.array([r["objective"] for r in tight.history])
        h_d = np.array([r["objective"] for r in default.history])
        row = {"case": name, "dofs": tight.summary["mesh"]["displacement_dofs"],
               "history": float(np.max(np.abs(h_d - h_t) / np.abs(h_t))),
               "design": float(np.max(np.abs(default.x - tight.x))),
               "wall_tight": tight.summary["wall_time_s"],
               "wall_default": default.summary["wall_time_s"],
               "default_rtol": default.summary["solvers"]["displacement"]["newton_rtol"],
               "analyses": []}
        with compute():
            f_ref, g_ref, its_ref, _ = _analyse(case, tight.x, iterations, REFERENCE)
            for rtol in TOLERANCES:
                f, g, its, sec = _analyse(case, tight.x, iterations, rtol)
                row["analyses"].append({
                    "rtol": rtol, "objective": abs(f - f_ref) / abs(f_ref),
                    "gradient": float(np.max(np.abs(g - g_ref)) / np.max(np.abs(g_ref))),
                    "cg": its, "seconds": sec})
        row["cg_reference"] = its_ref
        print(row, flush=True)
        rows.append(row)
    return rows


def markdown(rows, iterations: int, mach: str) -> str:
    out = ["## The iterative route's tolerance", "",
           "\n\n".join(p.strip() for p in __doc__.strip().split("\n\n")[2:]), "",
           "| case | dofs | newton_rtol | objective error | gradient error | displacement CG "
           "iterations | analysis s |", "|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r['case']} | {r['dofs']:,} | {REFERENCE:.0e} (reference) | | | "
                   f"{r['cg_reference']} | |")
        for a in r["analyses"]:
            out.append(f"| {r['case']} | {r['dofs']:,} | {a['rtol']:.0e} | "
                       f"{a['objective']:.1e} | {a['gradient']:.1e} | {a['cg']} | "
                       f"{a['seconds']:.2f} |")
    out += ["", f"Whole runs of {iterations} iterations, the route's default tolerance against "
            "1e-10:", "",
            "| case | default newton_rtol | objective histories, largest relative difference | "
            "final design, largest difference | wall s (1e-10, default) |",
            "|---|---:|---:|---:|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {r['default_rtol']:.0e} | {r['history']:.1e} | "
                   f"{r['design']:.1e} | {r['wall_tight']:.1f}, {r['wall_default']:.1f} |")
    out += ["", f"*Measured {mach}.*", "",
            "Regenerate: `python3 -m benchmarks iterative_tolerance`."]
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--iterations", type=int, default=25)
    ap.add_argument("--out", default=os.path.join("docs", "studies.md"))
    ap.add_argument("--no-write", action="store_true", help="print the section only")
    args = ap.parse_args(argv)
    from benchmarks.__main__ import machine, replace_block

    mach = machine()
    print(f"[iterative_tolerance] {mach}", flush=True)
    with tempfile.TemporaryDirectory() as folder:
        rows = study(args.iterations, folder)
    body = markdown(rows, args.iterations, mach)
    if not args.no_write:
        replace_block(args.out, "benchmarks-iterative_tolerance", body)
    print(body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
