"""Trade curves: wall time against accuracy over mesh size x element order, per case and model.

    python -m benchmarks.trade [--quick] [--repeat 3] [--cases a,b] [--plot docs/trade_curves.png]

A fixed design per case: the physical density after ``DESIGN_ITERATIONS`` optimisation
iterations of the case's defaults on a coarse structured mesh (computed once, cached in
``$PACTO_BENCH_CACHE`` or the system temp folder), interpolated bilinearly between its element
centres, so that every mesh samples one continuous function (at its element centroids) and
refinement converges to one problem; the runs use no filter and no projection (the function
already is the physical density).  A spread force load keeps its width of the default mesh
(``load_width``) at every mesh size.  Per (Netgen triangle size maxh, order 1/2/3): median
wall time of one analysis with sensitivities (``problem.evaluate``: Darcy, Newton or the linear
solve, adjoints, sensitivity forms; each timed evaluation is on the other of the design and a
1 % perturbation of it than the one before, so that every solve starts from another design's
equilibrium, as in an optimisation), dofs, objective, output displacement, and the relative
error of the objective against the finest run of that case and model (the reference).
Cases without a trade curve: ``mbb`` (unit elements by definition, so a finer mesh is a larger
beam; and its point load's compliance has no mesh limit in 2D) and ``c-beam`` (an analysis
whose result, the load factor at which the void inverts, depends on the mesh and the load
path rather than converging: 0.44-1.52 measured, see ``pacto_ng.studies.c_beam_limit``).
"""
from __future__ import annotations

import argparse
from dataclasses import replace
import os
import statistics
import tempfile
import time

import numpy as np

from benchmarks import perturbed

DESIGN_ITERATIONS = 20

#: case -> (models, structured mesh of the design run, maxh levels, overrides); the default
#: marked is the case's own (its maxh and order)
STUDIES = {
    "pa-inverter": (("linear", "wang"), (50, 25), (0.008, 0.004, 0.002, 0.001), {}),
    "pa-gripper": (("linear",), (50, 25), (0.008, 0.004, 0.002, 0.001), {}),
    "mm-gripper": (("linear",), (50, 25), (0.008, 0.004, 0.002, 0.001), {}),
    "pneunet": (("linear",), (60, 30), (0.006, 0.003, 0.0015, 0.00075), {}),
    "cantilever": (("linear", "wang"), (80, 20), (0.04, 0.02, 0.01, 0.005),
                   {"load_width": "0.04"}),
    "inverter": (("linear",), (60, 30), (6e-6, 3e-6, 1.5e-6, 0.75e-6),
                 {"load_width": "3e-6"}),
}
#: the nonlinear rows (``--models``): Neo-Hookean/Wang at this load of the pressure cases
#: (the force cases at their default loads)
NL_LOAD = 1e6
QUICK = {"pa-inverter": (("linear",), (50, 25), (0.008, 0.004), {})}
MAX_DOFS = 400_000
MAX_DOFS_NONLINEAR = 160_000  # a Newton solve costs 4-8 linear ones


def _cache_dir():
    d = os.environ.get("PACTO_BENCH_CACHE") or os.path.join(tempfile.gettempdir(),
                                                            "pacto_bench_cache")
    os.makedirs(d, exist_ok=True)
    return d


def fixed_design(case_name, grid, iterations=DESIGN_ITERATIONS):
    """(images (k, nely, nelx), width, height): the physical densities (k = 1, or 2 for two
    materials) after a short optimisation on a structured mesh (cached)."""
    from pacto_ng.threads import compute

    from benchmarks.mbb_iteration import short_optimisation

    nelx, nely = grid
    path = os.path.join(_cache_dir(), f"{case_name}_{nelx}x{nely}_{iterations}_v2.npz")
    if os.path.exists(path):
        d = np.load(path)
        return d["image"], float(d["W"]), float(d["H"])
    with compute():
        problem, _ = short_optimisation(case_name, nelx, nely, iterations)
        names = ["rho_bar"] if "rho_bar" in problem.values else ["rho_bar1", "rho_bar2"]
        image = np.stack([np.asarray(problem.values[n]).reshape(nely, nelx) for n in names])
        pts = np.array([v.point for v in problem.mesh.vertices])
    W, H = pts[:, 0].max(), pts[:, 1].max()
    np.savez(path, image=image, W=W, H=H)
    return image, W, H


def sample(image, W, H, cen):
    """The pixel value of each point (piecewise constant; image (nely, nelx))."""
    nely, nelx = image.shape
    i = np.clip((cen[:, 0] / W * nelx).astype(int), 0, nelx - 1)
    j = np.clip((cen[:, 1] / H * nely).astype(int), 0, nely - 1)
    return np.clip(image[j, i], 0.0, 1.0)


def sample_smooth(image, W, H, cen):
    """Bilinear interpolation of the pixel values between the pixel centres (constant beyond
    the outer centres): a continuous density function."""
    from scipy.interpolate import RegularGridInterpolator

    nely, nelx = image.shape
    xs = (np.arange(nelx) + 0.5) * W / nelx
    ys = (np.arange(nely) + 0.5) * H / nely
    f = RegularGridInterpolator((ys, xs), image, method="linear")
    q = np.column_stack([np.clip(cen[:, 1], ys[0], ys[-1]), np.clip(cen[:, 0], xs[0], xs[-1])])
    return np.clip(f(q), 0.0, 1.0)


def run_point(case_name, model, maxh, order, design, repeat=3, extra=None):
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case

    case = get_case(case_name)
    over = {"model": model, "maxh": str(maxh), "order": str(order), "filter": "none",
            "beta": "0", "beta_max": "0", "penal_start": "0", **(extra or {})}
    if model != "linear" and case.load_unit == "Pa":
        over["load"] = str(NL_LOAD)
    params = case.defaults.with_overrides(over)
    images, W, H = design
    with compute():
        t0 = time.perf_counter()
        problem = build_problem(case, params)
        problem.mech.settings = replace(problem.mech.settings, max_total_iter=150)
        setup = time.perf_counter() - t0
        cen = problem.field.centroids()[problem.field.design_index]
        x = np.concatenate([sample_smooth(im, W, H, cen) for im in images])
        t0 = time.perf_counter()
        f0 = problem.evaluate(x)[0]
        first = time.perf_counter() - t0
        # the timed evaluations alternate between x and a 1 % perturbation of it, as in an
        # optimisation: every one is a new design, so the warm-started Newton solve (or the
        # linear solve) cannot find the state already in equilibrium
        x2 = perturbed(x)
        problem.evaluate(x2)  # (untimed) a second design: the linear path's element matrices
        problem.evaluate(x)
        ts = []
        for k in range(repeat):
            t0 = time.perf_counter()
            problem.evaluate(x2 if k % 2 == 0 else x)
            ts.append(time.perf_counter() - t0)
        if repeat % 2 == 1:
            f0 = problem.evaluate(x)[0]  # (untimed) the state and values of the design itself
        vals = problem.values
        dofs = problem.mech.fes.ndof + (problem.pressure_block.fes.ndof
                                        if problem.pressure_block is not None else 0)
        newton = problem.mech.result.iterations if problem.mech.result else 0
    return dict(case=case_name, model=model, maxh=maxh, order=order, dofs=dofs,
                elements=problem.mesh.ne, f=float(f0), time=statistics.median(ts),
                first=first, setup=setup, newton=newton,
                delta=float(vals["delta"]) if "delta" in vals else float("nan"))


def study(quick=False, repeat=3, log=print, cases=None, models=None):
    from pacto_ng.case import get_case
    from pacto_ng.physics.equilibrium import NewtonFailure

    plan = QUICK if quick else STUDIES
    if cases:
        unknown = [c for c in cases if c not in STUDIES]
        if unknown:
            raise SystemExit(f"trade: unknown case(s) {', '.join(unknown)} "
                             f"(choose from {', '.join(STUDIES)})")
        plan = {c: STUDIES[c] for c in cases}
    results, failed = [], []
    for case_name, (case_models, grid, levels, extra) in plan.items():
        case = get_case(case_name)
        design = fixed_design(case_name, grid, 8 if quick else DESIGN_ITERATIONS)
        for model in models or case_models:
            rows = []
            for order in (1, 2) if quick else (1, 2, 3):
                for maxh in levels:
                    # rough dof estimate of a triangle mesh: 2 * (order/maxh)^2 * area
                    W, H = design[1], design[2]
                    est = 2 * 2.3 * W * H * (order / maxh) ** 2
                    if est > (MAX_DOFS if model == "linear" else MAX_DOFS_NONLINEAR):
                        continue
                    try:
                        r = run_point(case_name, model, maxh, order, design, repeat, extra)
                    except NewtonFailure as err:
                        log(f"  trade {case_name} {model} maxh={maxh} order={order}: {err}")
                        failed.append((model, maxh, order, str(err)))
                        continue
                    r["default"] = maxh == case.defaults.maxh and order == case.order_for(model)
                    rows.append(r)
                    log(f"  trade {case_name} {model} maxh={maxh} order={order}: "
                        f"{r['dofs']} dofs, {r['time']:.3f} s, f={r['f']:.8g}")
            if not rows:
                continue
            ref = max(rows, key=lambda r: r["dofs"])
            for r in rows:
                r["err"] = abs(r["f"] - ref["f"]) / abs(ref["f"])
                r["ref"] = r is ref
            results.append(dict(case=case_name, model=model, rows=rows, ref=ref,
                                failed=[f for f in failed if f[0] == model]))
            failed = []
    return results


def _pct(e):
    return f"{100 * e:.2f} %"


def summary_line(res):
    """The default against the finest run, against order 3 on its own mesh, the next finer
    order-1 mesh (whether the default's error is converged or a crossing), the knee."""
    ref = res["ref"]
    d = next((r for r in res["rows"] if r["default"]), None)
    if d is None:
        return ""
    rows = res["rows"]
    within = d["err"] <= 0.01
    s = (f"**{res['case']} / {res['model']}**: the case default (maxh {d['maxh']}, order {d['order']}) is "
         f"{_pct(d['err'])} from the finest objective (maxh {ref['maxh']}, order {ref['order']}, "
         f"{ref['dofs']} dofs) at {100 * d['time'] / ref['time']:.2g} % of its time: "
         f"{'within' if within else '**not** within'} 1 %.")
    same = [r for r in rows if r["maxh"] == d["maxh"] and r["order"] == 3]
    if same:
        e = abs(d["f"] - same[0]["f"]) / abs(same[0]["f"])
        s += (f" On its own mesh (the design's resolution) order {d['order']} is {_pct(e)} from "
              "order 3.")
    finer = sorted((r for r in rows if r["order"] == d["order"] and r["maxh"] < d["maxh"]
                    and not r["ref"]), key=lambda r: -r["maxh"])
    if finer:
        s += (f" Order {d['order']} on the next finer mesh (maxh {finer[0]['maxh']}): "
              f"{_pct(finer[0]['err'])}.")
    ok = [r for r in rows if not r["ref"] and r["err"] <= 0.01]
    if ok:
        k = min(ok, key=lambda r: r["time"])
        s += (f" Cheapest run within 1 %: maxh {k['maxh']}, order {k['order']} "
              f"({k['dofs']} dofs, {k['time']:.3f} s, {_pct(k['err'])}, "
              f"{k['time'] / d['time']:.2g}x the default's time).")
    else:
        s += " No run other than the reference is within 1 %."
    return s


def markdown(results):
    out = []
    for res in results:
        from pacto_ng.case import get_case

        load = (f" at {NL_LOAD:g} Pa" if res["model"] != "linear"
                and get_case(res["case"]).load_unit == "Pa" else "")
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

    ncol = min(3, len(results))
    nrow = -(-len(results) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.5 * ncol, 4 * nrow), squeeze=False)
    markers = {1: "o", 2: "s", 3: "^"}
    for ax in axes.flat[len(results):]:
        ax.set_visible(False)
    for ax, res in zip(axes.flat, results):
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
    ap.add_argument("--cases", default="", help="comma-separated cases (default: all)")
    ap.add_argument("--models", default="", help="comma-separated models (default: each case's models in STUDIES)")
    args = ap.parse_args(argv)
    res = study(args.quick, args.repeat, cases=[c for c in args.cases.split(",") if c],
                models=[m for m in args.models.split(",") if m])
    print(markdown(res))
    if args.plot:
        plot(res, args.plot)
    return res


if __name__ == "__main__":
    main()
