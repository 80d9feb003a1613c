"""Stability map: the largest pressure an analysis completes, per model and parameter.

    python -m benchmarks.stability [--quick]

A fixed representative design (the pa-inverter design of :mod:`benchmarks.trade`: the physical
density after 20 optimisation iterations, a pixel image) is analysed with sensitivities
(``problem.evaluate``) at increasing inlet pressures ``LOADS`` (1e5 to 1e8 Pa), one parameter varied at a time from the base (Netgen mesh maxh 0.004, order 1,
E0/E1 = 1e-6, ν = 0.4, no filter and no projection except in the β rows, where the Helmholtz
filter and a projection of sharpness β act on the image), for Neo-Hookean and for Wang.
What fails in a whole optimisation (Newton, or the optimiser: objective not improved, volume
not met) is in the "Extreme loads" section, column "valid".  The sweep stops at the first failure;
reported: the largest load completed and why the next one failed (Newton's own reason: the
load increment fell below its minimum, too many iterations, or every step inverted an
element).  A completed analysis must also give a finite objective and gradient.  Newton's
budget is cut to ``MAX_ITER`` iterations per load step and ``MAX_TOTAL_ITER`` per analysis.

Each row is swept three times: on the design and on two copies of it whose densities are
multiplied by 1 + 1e-12 ξ (ξ standard normal, seeded), a perturbation at the level of
round-off.  Near the edge of the Newton budget the outcome depends on it (measured: the same
row completed 3e7 Pa on one copy and 1e8 Pa on another), so the table gives the largest load
that all three designs completed and the largest that any of them completed; where they
differ, the limit lies in that range and which side a run falls on is decided by round-off.
The failure column is that of the design that stopped first; the Newton counts are the
unperturbed design's.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np


LOADS = (1e5, 1e6, 3e6, 1e7, 3e7, 1e8)
BASE = {"maxh": "0.004", "order": "1", "filter": "none", "beta": "0", "beta_max": "0",
        "penal_start": "0", "E0": "3e3", "nu": "0.4"}


def _grid(model):
    """One parameter at a time away from the base, for one nonlinear model."""
    return [
        *[(f"E0/E1 ({model})", e, {"model": model, "E0": str(3e9 * float(e))})
          for e in ("1e-03", "1e-09")],
        *[(f"projection β ({model})", b, {"model": model, "filter": "helmholtz", "beta": b,
                                          "beta_max": b}) for b in ("8", "32", "128")],
        *[(f"ν ({model})", n, {"model": model, "nu": n}) for n in ("0.3", "0.45", "0.49")],
        (f"order ({model})", "2", {"model": model, "order": "2"}),
    ]


STUDIES = [  # (parameter label, value label, overrides); the base rows are the model rows
    *[("model", m, {"model": m}) for m in ("linear", "gnl", "neohookean", "wang")],
    *_grid("neohookean"), *_grid("wang"),
]
#: Newton budget of the sweep (the library defaults are 30 per load step, 1000 per analysis):
#: a failing analysis otherwise spends minutes halving its load increment
MAX_ITER, MAX_TOTAL_ITER = 30, 100
QUICK = [("model", m, {"model": m}) for m in ("linear", "neohookean")]
QUICK_LOADS = LOADS[:3]
#: relative size of the round-off perturbations of the design (one sweep each, and one on the
#: design itself)
PERTURBATIONS = (0.0, 1e-12, 1e-12)


def perturbed_design(design, eps, seed):
    """The design with its densities multiplied by ``1 + eps ξ`` (ξ standard normal)."""
    images, W, H = design
    if eps == 0.0:
        return design
    xi = np.random.default_rng(seed).standard_normal(np.shape(images))
    return np.clip(np.asarray(images) * (1.0 + eps * xi), 0.0, 1.0), W, H


def classify(reason: str) -> str:
    r = reason.lower()
    if "det f" in r or "invert" in r:
        return "inversion (det F <= 0 at every step length)"
    if "increment fell below" in r:
        return "Newton (load increment below minimum)"
    if "iterations" in r:
        return "Newton (iteration budget)"
    if "finite" in r or "nan" in r:
        return "non-finite values"
    return reason[:80]


def sweep(overrides, design, loads=LOADS):
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.physics.equilibrium import NewtonFailure
    from benchmarks.trade import sample

    case = get_case("pa-inverter")
    params = case.defaults.with_overrides({**BASE, **overrides, "load": str(loads[0])})
    images, W, H = design
    image = images[0]
    done, failure, newton, t_total = None, "", [], 0.0
    with compute():
        problem = build_problem(case, params)
        problem.mech.settings = replace(problem.mech.settings, max_iter=MAX_ITER,
                                        max_total_iter=MAX_TOTAL_ITER)
        x = sample(image, W, H, problem.field.centroids()[problem.field.design_index])
        beta = float(params.beta)
        for load in loads:
            problem.apply_schedule(float(params.penal), beta, load / loads[0])
            t0 = time.perf_counter()
            try:
                f0, f, df0, df = problem.evaluate(x)
            except NewtonFailure as err:
                failure = classify(err.result.reason)
                t_total += time.perf_counter() - t0
                break
            t_total += time.perf_counter() - t0
            if not (np.isfinite(f0) and np.all(np.isfinite(df0))):
                failure = "non-finite objective or gradient"
                break
            done = load
            newton.append(problem.mech.result.iterations)
    return dict(done=done, failure=failure or f"none up to {loads[-1]:.0e} Pa",
                newton=newton, time=t_total)


def study(quick=False, log=print):
    from benchmarks.trade import STUDIES as TRADE, fixed_design

    grid = TRADE["pa-inverter"][1]
    design = fixed_design("pa-inverter", grid, 8 if quick else 20)
    designs = [perturbed_design(design, eps, seed)
               for seed, eps in enumerate(PERTURBATIONS[:1] if quick else PERTURBATIONS)]
    loads = QUICK_LOADS if quick else LOADS
    rows = []
    for label, value, over in (QUICK if quick else STUDIES):
        runs = [sweep(over, d, loads) for d in designs]
        rank = [-1 if r["done"] is None else loads.index(r["done"]) for r in runs]
        worst = runs[int(np.argmin(rank))]
        r = dict(parameter=label, value=value, done=worst["done"],
                 done_any=runs[int(np.argmax(rank))]["done"], failure=worst["failure"],
                 newton=runs[0]["newton"], time=float(np.median([q["time"] for q in runs])),
                 runs=len(runs))
        rows.append(r)
        log(f"  stability {label}={value}: largest load {r['done']} (any copy: "
            f"{r['done_any']}), next: {r['failure']}")
    return rows


def markdown(rows):
    def fmt(v):
        return "none" if v is None else f"{v:.0e}"

    n = rows[0]["runs"] if rows else 1
    out = [f"| parameter | value | largest load completed by all {n} designs [Pa] | by any "
           "[Pa] | what failed at the next load (the design that stopped first) | Newton "
           "iterations per completed load (the unperturbed design) | time [s] (median) |",
           "|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['parameter']} | {r['value']} | {fmt(r['done'])} | "
                   f"{fmt(r['done_any'])} | {r['failure']} | "
                   f"{', '.join(map(str, r['newton'])) or '–'} | {r['time']:.1f} |")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    rows = study(args.quick)
    print(markdown(rows))
    return rows


if __name__ == "__main__":
    main()
