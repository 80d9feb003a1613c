"""3D iterations measured against the hardware: one iteration's time in stiffness
matrix-vector products at the same size, measured in the same process.

    PACTO_THREADS=1 python3 -m benchmarks.iteration_ratio [--sizes cantilever-3d:0.05,0.03]
        [--models linear,neohookean] [--routes direct,iterative] [--out docs/studies.md]
    python3 -m benchmarks iteration_ratio

Per case, Netgen size (``maxh``), model and linear-solver route (``solver=direct|iterative``,
pacto_ng/physics/routes.py), in one process: the case's problem at order 2
(``pacto_ng.case.build_problem``), optimised from its initial design as ``pacto run`` does
(its schedule, load ramp and optimiser) for ``1 + REPEATS`` iterations: the median time of
iterations 1 to ``REPEATS`` (history's ``time``: state, adjoints, sensitivities and the
optimiser's update; the first builds the forms, the solver and the filter).  The designs are
the run's own, so that what a solver keeps from one design to the next (a factorisation's
structure, a preconditioner kept across designs) is kept only as far as a run's first
iterations allow, where the designs change most.  The matrix-vector product: the
linear-elasticity stiffness matrix on the problem's own displacement space (the same sparsity
as every matrix of the iteration, stored in full, not its symmetric half), assembled by
NGSolve; the median of ``MV_REPEATS``
products ``y = A x``.  The ratio of the two medians is the iteration's cost in products: a
few dozen is what an optimal preconditioner allows (state, adjoint and sensitivities at a
handful of products each per Krylov iteration), several hundred is what the set-up of a
factorisation or of a preconditioner at every iteration costs.
"""
from __future__ import annotations

import argparse
import resource
import statistics
import time

import numpy as np
from ngsolve import BilinearForm, Grad, InnerProduct, SetNumThreads, Sym, TaskManager, dx

from benchmarks.__main__ import replace_block
from pacto_ng.auto import choose
from pacto_ng.case import build_problem, get_case
from pacto_ng.initial import initial_design
from pacto_ng.optimize.driver import LoopState, optimize
from pacto_ng.threads import thread_count

ORDER = 2
REPEATS = 5  # iterations timed after the first (which builds the forms, the solver, the filter)
MV_REPEATS = 20
SIZES = {"cantilever-3d": (0.05, 0.03), "pneunet-3d": (0.005, 0.0035)}
BLOCK = "iteration_ratio"


def matvec_time(space) -> float:
    """The median time of ``y = A x`` for the elasticity stiffness on ``space`` (full
    storage)."""
    u, v = space.TnT()
    a = BilinearForm(space, symmetric=False)
    a += InnerProduct(Sym(Grad(u)), Sym(Grad(v))) * dx
    a.Assemble()
    x, y = a.mat.CreateRowVector(), a.mat.CreateColVector()
    x.FV().NumPy()[:] = np.random.default_rng(0).random(len(x))
    times = []
    for _ in range(MV_REPEATS):
        t0 = time.perf_counter()
        a.mat.Mult(x, y)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def one(case: str, maxh: float, model: str, route: str) -> dict:
    """One size, model and route: ``{dofs, iteration, matvec, ratio}`` (seconds)."""
    c = get_case(case)
    params = c.defaults.replace(maxh=maxh, order=ORDER, model=model, solver=route)
    if params.load_ramp < 0:  # the load ramp a run chooses for the case's load
        params = choose(c, params)[0]
    params = c.resolve(params)
    problem = build_problem(c, params)
    problem.expect_many_designs()
    state = LoopState.start(initial_design(problem), problem.setup.objective_ref)
    optimize(problem, params.schedule.schedule(), iterations=1 + REPEATS, tol=0.0,
             method=params.optimizer, move=params.move, state=state, obj_tol=0.0,
             load_adapt=params.load_adapt)
    times = [row["time"] for row in state.history[1:]]
    space = problem.mech.fes
    mv = matvec_time(space)
    it = statistics.median(times)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # GiB, the process's so far
    return {"case": case, "maxh": maxh, "model": model, "route": route, "dofs": space.ndof,
            "load": state.history[-1]["load"], "iteration": it, "matvec": mv,
            "ratio": it / mv, "peak": peak}


def slopes(rows: list[dict]) -> str:
    """Per case, model and route measured at two sizes or more: the least-squares slope of
    log(time per iteration) against log(dofs)."""
    groups = {}
    for r in rows:
        groups.setdefault((r["case"], r["model"], r["route"]), []).append(r)
    lines = []
    for (case, model, route), rs in groups.items():
        if len(rs) > 1:
            fit = np.polyfit(np.log([r["dofs"] for r in rs]),
                             np.log([r["iteration"] for r in rs]), 1)[0]
            lines.append(f"- {case}, {model}, {route}: slope of time against dofs {fit:.2f} "
                         f"over {rs[0]['dofs']:,}-{rs[-1]['dofs']:,} dofs\n")
    return "".join(lines)


def table(rows: list[dict]) -> str:
    head = ("| case | maxh | model | load factor | route | displacement dofs | iteration (s) | "
            "matvec (ms) | iteration / matvec | peak RSS so far (GiB) |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    return head + "".join(
        f"| {r['case']} | {r['maxh']:g} | {r['model']} | {r['load']:g} | {r['route']} | "
        f"{r['dofs']:,} | "
        f"{r['iteration']:.3g} | {1e3 * r['matvec']:.3g} | **{r['ratio']:.0f}** | "
        f"{r['peak']:.2f} |\n" for r in rows) + "\n" + slopes(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default=",".join(f"{c}:{'/'.join(map(str, s))}"
                                                for c, s in SIZES.items()),
                    help="CASE:MAXH/MAXH,... (default %(default)s)")
    ap.add_argument("--models", default="linear,neohookean")
    ap.add_argument("--routes", default="direct,iterative")
    ap.add_argument("--out", default="", help="write the table into this report's block")
    a = ap.parse_args(argv)
    SetNumThreads(thread_count())
    rows = []
    with TaskManager():
        for item in a.sizes.split(","):
            case, sizes = item.split(":")
            for maxh in map(float, sizes.split("/")):
                for model in a.models.split(","):
                    for route in a.routes.split(","):
                        r = one(case, maxh, model, route)
                        print(f"{case} maxh {maxh:g} {model} {route}: {r['dofs']} dofs, "
                              f"iteration {r['iteration']:.3g} s, matvec "
                              f"{1e3 * r['matvec']:.3g} ms, ratio {r['ratio']:.0f}",
                              flush=True)
                        rows.append(r)
    text = table(rows)
    print(text)
    if a.out:
        replace_block(a.out, BLOCK, text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
