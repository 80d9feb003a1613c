"""Time and Newton iterations per optimisation iteration of the cantilever, per mechanics model.

    python -m benchmarks.nonlinear_iteration [--models linear,gnl,neohookean,wang]
        [--maxh 0.02,0.01] [--orders 1,2] [--load 144e3] [--iterations 5] [--threads 2]
        [--realcompile]

For each model, Netgen mesh size and displacement order: one cantilever optimisation (the case's
defaults: Helmholtz filter + projection, MMA, load 144 kN unless told) of ``--iterations``
iterations.  Reported: the median wall time of an optimisation iteration (analysis with Newton,
adjoint sensitivities, MMA update) and the median number of Newton iterations per optimisation
iteration, both over iterations 2..N (the first iteration starts Newton from u = 0 and is shown
separately).  Prints a markdown table.
"""
from __future__ import annotations

import argparse
import statistics
import time


def measure(model: str, maxh: float, order: int, load: float = 144e3, iterations: int = 5,
            threads: int = 2, realcompile: bool = False) -> dict:
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.optimize.driver import LoopState, optimize
    from pacto_ng.initial import initial_design

    if iterations < 4:
        raise ValueError("need >= 4 iterations (medians over >= 3 iterations after the first)")
    case = get_case("cantilever")
    params = case.defaults.with_overrides({"model": model, "maxh": str(maxh), "nelx": "0",
                                           "nely": "0", "order": str(order),
                                           "load": str(load), "iterations": str(iterations),
                                           "realcompile": str(int(realcompile))})
    t0 = time.perf_counter()
    with compute(threads=threads):
        problem = build_problem(case, params)
        setup = time.perf_counter() - t0
        state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
        res = optimize(problem, params.schedule.schedule(), iterations=iterations, tol=0.0,
                       method="mma", move=params.move, state=state)
    hist = state.history
    if res.stopped == "newton" or len(hist) < 4:
        # a Newton failure is a result (e.g. St Venant-Kirchhoff under compression), not a crash
        return dict(model=model, maxh=maxh, order=order, dofs=problem.mech.fes.ndof,
                    failed=res.message)
    later = hist[1:]
    return dict(model=model, maxh=maxh, order=order, dofs=problem.mech.fes.ndof,
                elements=problem.mech.fes.mesh.ne,
                setup=setup, first_time=hist[0]["time"], first_newton=hist[0]["newton"],
                per_iteration=statistics.median(h["time"] for h in later),
                newton=statistics.median(h["newton"] for h in later), n=len(later))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="linear,gnl,neohookean,wang")
    ap.add_argument("--maxh", default="0.02,0.01")
    ap.add_argument("--orders", default="1,2")
    ap.add_argument("--load", type=float, default=144e3)
    ap.add_argument("--iterations", type=int, default=5)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--realcompile", action="store_true",
                    help="machine-code Newton forms (the compile time is in the set-up, not shown)")
    args = ap.parse_args(argv)
    rows = []
    print(f"| model | maxh [m] | order | dofs | time per iteration (median of {args.iterations - 1}) [s] "
          "| Newton per iteration (median) | first iteration [s] / Newton |")
    print("|---|---|---|---|---|---|---|")
    for h in (float(v) for v in args.maxh.split(",")):
        for order in (int(v) for v in args.orders.split(",")):
            for model in args.models.split(","):
                r = measure(model, h, order, args.load, args.iterations, args.threads,
                            args.realcompile)
                rows.append(r)
                if "failed" in r:
                    print(f"| {r['model']} | {r['maxh']:g} | {r['order']} | {r['dofs']} "
                          f"| Newton failure: {r['failed'].split(';')[0]} | | |", flush=True)
                    continue
                print(f"| {r['model']} | {r['maxh']:g} | {r['order']} | {r['dofs']} "
                      f"| {r['per_iteration']:.3f} | {r['newton']:g} "
                      f"| {r['first_time']:.2f} / {r['first_newton']} |", flush=True)
    return rows


if __name__ == "__main__":
    main()
