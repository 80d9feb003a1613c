"""Trade curves: wall time against accuracy over mesh size x element order, per case and model.

    python -m benchmarks.trade [--quick] [--repeat 3] [--plot docs/trade_curves.png]

A fixed design per case: the physical density after ``DESIGN_ITERATIONS`` optimisation
iterations of the case's defaults on a coarse structured mesh (computed once, cached in
``$PACTO_BENCH_CACHE`` or the system temp folder).  It is a pixel image, so every mesh samples
the same function at its element centroids; the runs use no filter and no projection (the
image already is the physical density).  Per (Netgen triangle size maxh, order 1/2/3):
median wall time of one analysis with sensitivities (``problem.evaluate``: Darcy, Newton or
the linear solve, adjoints, sensitivity forms), dofs, objective, output displacement, and the
relative error of the objective against the finest run of that case and model.
The cantilever's tip load is spread over ±2 h (the case's definition), so across mesh sizes
its objective changes by definition as well as by discretisation; at fixed maxh only the
order changes.
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import os
import statistics
import tempfile
import time

import numpy as np

DESIGN_ITERATIONS = 20

STUDIES = {  # case -> (models, structured mesh of the design run, maxh levels, default maxh)
    "pa-inverter": (("linear",), (50, 25), (0.008, 0.004, 0.002), 0.004),
    "cantilever": (("linear",), (80, 20), (0.04, 0.02, 0.01), 0.01),
    # neohookean (at NH_LOAD, orders 1-2) is left out of the default run: on this fixed design
    # its Newton failed at maxh 0.004 and 0.002 (load factor 0.44 / 0.41 after 150 iterations),
    # and each failure costs minutes; add ("linear", "neohookean") to run it
}
QUICK = {"pa-inverter": (("linear",), (50, 25), (0.008, 0.004), 0.004)}
MAX_DOFS = 250_000
NH_LOAD = 3e5  # Pa: the fixed design's Neo-Hookean analysis fails at maxh 0.008 at 1e6 Pa


def _cache_dir():
    d = os.environ.get("PACTO_BENCH_CACHE") or os.path.join(tempfile.gettempdir(),
                                                            "pacto_bench_cache")
    os.makedirs(d, exist_ok=True)
    return d


def fixed_design(case_name, grid, iterations=DESIGN_ITERATIONS):
    """(image (nely, nelx), width, height): rho_bar after a short optimisation (cached)."""
    from ngsolve import SetNumThreads, TaskManager

    from benchmarks.mbb_iteration import short_optimisation

    nelx, nely = grid
    path = os.path.join(_cache_dir(), f"{case_name}_{nelx}x{nely}_{iterations}.npz")
    if os.path.exists(path):
        d = np.load(path)
        return d["image"], float(d["W"]), float(d["H"])
    SetNumThreads(2)
    with TaskManager():
        problem, _ = short_optimisation(case_name, nelx, nely, iterations)
        image = np.asarray(problem.values["rho_bar"]).reshape(nely, nelx)
        pts = np.array([v.point for v in problem.mesh.vertices])
    W, H = pts[:, 0].max(), pts[:, 1].max()
    np.savez(path, image=image, W=W, H=H)
    return image, W, H


def sample(image, W, H, cen):
    nely, nelx = image.shape
    i = np.clip((cen[:, 0] / W * nelx).astype(int), 0, nelx - 1)
    j = np.clip((cen[:, 1] / H * nely).astype(int), 0, nely - 1)
    return np.clip(image[j, i], 0.0, 1.0)


def run_point(case_name, model, maxh, order, design, repeat=3):
    from ngsolve import SetNumThreads, TaskManager

    from pacto_ng.case import build_problem, get_case

    SetNumThreads(2)
    case = get_case(case_name)
    over = {"model": model, "maxh": str(maxh), "order": str(order), "filter": "none",
            "beta": "0", "beta_max": "0", "penal_start": "0"}
    if model != "linear" and case.load_unit == "Pa":
        over["load"] = str(NH_LOAD)
    params = case.defaults.with_overrides(over)
    image, W, H = design
    with TaskManager():
        t0 = time.perf_counter()
        problem = build_problem(case, params)
        problem.mech.settings = replace(problem.mech.settings, max_total_iter=150)
        setup = time.perf_counter() - t0
        x = sample(image, W, H, problem.field.centroids()[problem.field.design_index])
        t0 = time.perf_counter()
        f0 = problem.evaluate(x)[0]
        first = time.perf_counter() - t0
        ts = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            f0 = problem.evaluate(x)[0]
            ts.append(time.perf_counter() - t0)
        vals = problem.values
        dofs = problem.mech.fes.ndof + (problem.pressure_block.fes.ndof
                                        if problem.pressure_block is not None else 0)
        newton = problem.mech.result.iterations if problem.mech.result else 0
    return dict(case=case_name, model=model, maxh=maxh, order=order, dofs=dofs,
                elements=problem.mesh.ne, f=float(f0), time=statistics.median(ts),
                first=first, setup=setup, newton=newton,
                delta=float(vals["delta"]) if "delta" in vals else float("nan"))


def study(quick=False, repeat=3, log=print):
    from pacto_ng.physics.mechanics import NewtonFailure

    plan = QUICK if quick else STUDIES
    results, failed = [], []
    for case_name, (models, grid, levels, default) in plan.items():
        design = fixed_design(case_name, grid, 8 if quick else DESIGN_ITERATIONS)
        for model in models:
            rows = []
            for order in (1, 2) if quick or model != "linear" else (1, 2, 3):
                for maxh in levels:
                    # rough dof estimate of a triangle mesh: 2 * (order/maxh)^2 * area
                    W, H = design[1], design[2]
                    est = 2 * 2.3 * W * H * (order / maxh) ** 2
                    if est > MAX_DOFS:
                        continue
                    try:
                        r = run_point(case_name, model, maxh, order, design, repeat)
                    except NewtonFailure as err:
                        log(f"  trade {case_name} {model} maxh={maxh} order={order}: {err}")
                        failed.append((model, maxh, order, str(err)))
                        continue
                    r["default"] = (maxh == default and order == 1)
                    rows.append(r)
                    log(f"  trade {case_name} {model} maxh={maxh} order={order}: "
                        f"{r['dofs']} dofs, {r['time']:.3f} s, f={r['f']:.8g}")
            ref = max(rows, key=lambda r: r["dofs"])
            for r in rows:
                r["err"] = abs(r["f"] - ref["f"]) / abs(ref["f"])
                r["ref"] = r is ref
            results.append(dict(case=case_name, model=model, rows=rows, ref=ref,
                                failed=[f for f in failed if f[0] == model]))
            failed = []
    return results


def summary_line(res):
    ref = res["ref"]
    d = next((r for r in res["rows"] if r["default"]), None)
    if d is None:
        return ""
    others = [r for r in res["rows"] if not r["ref"]]
    knee = None
    ok = [r for r in others if r["err"] <= 0.01]
    if ok:
        knee = min(ok, key=lambda r: r["time"])
    s = (f"**{res['case']} / {res['model']}**: the case default (maxh {d['maxh']}, order 1) is "
         f"within {100 * d['err']:.2g} % of the finest objective (maxh {ref['maxh']}, order "
         f"{ref['order']}, {ref['dofs']} dofs) at {100 * d['time'] / ref['time']:.2g} % of its "
         f"time.")
    if knee is not None:
        s += (f" Cheapest run within 1 %: maxh {knee['maxh']}, order {knee['order']} "
              f"({knee['dofs']} dofs, {knee['time']:.3f} s, error {100 * knee['err']:.2g} %).")
    else:
        s += " No run other than the reference is within 1 %."
    return s


def markdown(results):
    out = []
    for res in results:
        load = f" at {NH_LOAD:g} Pa" if res["model"] != "linear" and res["case"] != "cantilever" else ""
        out.append(f"#### {res['case']}, {res['model']}{load}")
        out.append("")
        out.append("| maxh | order | elements | dofs | time [s] | objective | output Δ | "
                   "error vs finest |")
        out.append("|---|---|---|---|---|---|---|---|")
        for r in sorted(res["rows"], key=lambda r: (r["order"], -r["maxh"])):
            tag = " (default)" if r["default"] else (" (reference)" if r["ref"] else "")
            delta = "–" if not np.isfinite(r["delta"]) else f"{r['delta']:.4g}"
            out.append(f"| {r['maxh']}{tag} | {r['order']} | {r['elements']} | {r['dofs']} | "
                       f"{r['time']:.3f} | {r['f']:.8g} | {delta} | "
                       f"{'–' if r['ref'] else format(r['err'], '.2e')} |")
        out.append("")
        for _m, maxh, order, why in res.get("failed", []):
            out.append(f"- maxh {maxh}, order {order}: not in the table, {why}")
        line = summary_line(res)
        if line:
            out.append(line)
            out.append("")
    return "\n".join(out)


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(4.5 * len(results), 4), squeeze=False)
    markers = {1: "o", 2: "s", 3: "^"}
    for ax, res in zip(axes[0], results):
        rows = [r for r in res["rows"] if not r["ref"]]
        for k in (1, 2, 3):
            rr = sorted((r for r in rows if r["order"] == k), key=lambda r: r["time"])
            if rr:
                ax.loglog([r["time"] for r in rr], [max(r["err"], 1e-12) for r in rr],
                          marker=markers[k], label=f"order {k}")
        # Pareto front
        front, best = [], np.inf
        for r in sorted(rows, key=lambda r: r["time"]):
            if r["err"] < best:
                best = r["err"]
                front.append(r)
        ax.loglog([r["time"] for r in front], [max(r["err"], 1e-12) for r in front], "k--",
                  lw=0.8, label="Pareto front")
        for r in rows:
            if r["default"]:
                ax.loglog([r["time"]], [max(r["err"], 1e-12)], "r*", ms=14, label="case default")
        ax.axhline(0.01, color="grey", lw=0.5)
        ax.set_xlabel("time of one analysis + sensitivities [s]")
        ax.set_ylabel("relative error of the objective")
        ax.set_title(f"{res['case']}, {res['model']}")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--plot", default="")
    args = ap.parse_args(argv)
    res = study(args.quick, args.repeat)
    print(markdown(res))
    if args.plot:
        plot(res, args.plot)
    return res


if __name__ == "__main__":
    main()
