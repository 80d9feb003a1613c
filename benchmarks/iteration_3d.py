"""3D optimisation iterations: time and peak memory per iteration against displacement dofs.

    PACTO_THREADS=1 python3 -m benchmarks.iteration_3d [--budget 1400] [--out docs/studies.md]
    python3 -m benchmarks iteration_3d

Per case (cantilever-3d, pneunet-3d), model (linear, Neo-Hookean at the case's default load
and load ramp), linear-solver route (`--set solver=direct|iterative`, pacto_ng/physics/
solvers.py) and Netgen size (`--maxh`), a short optimisation in a fresh process:
`python3 -m pacto_ng.cli run CASE --maxh H --order 2 --model M --set solver=S --iterations 4
--out TMP --quiet`, under `/usr/bin/time -f %M` for the process's peak resident memory.  The
time per iteration is the median of the `time` column of the run's history.csv (analysis,
sensitivities and the MMA update of one iteration, pacto_ng/optimize/driver.py) over
iterations 2..4: the first builds the forms, the solver and the filter (the second builds the
linear direct path's element matrices, pacto_ng/physics/scatter.py: the median of three
leaves one slow iteration out).  The dofs are the run's
summary.json `mesh.displacement_dofs` (VectorH1 of order 2).  The log-log slope of time and of
memory against dofs is a least-squares fit over the sizes measured of each case, model and
route; a route stops growing after a run that takes more than `--run-limit` seconds, and the
study skips what would overrun `--budget` (both are recorded in the table, not hidden).
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

ORDER = 2
ITERATIONS = 4
FIRST_TIMED = 1  # 0-based: iterations 2..ITERATIONS (1-based) are timed
CASES = {  # Netgen sizes, coarse to fine (1.4-2x the dofs a step at order 2)
    "cantilever-3d": (0.062, 0.05, 0.04, 0.032, 0.025, 0.02),
    "pneunet-3d": (0.0075, 0.0065, 0.0056, 0.005, 0.0042, 0.0035),
}
MODELS = ("linear", "neohookean")
ROUTES = ("direct", "iterative")
RUN_TIMEOUT_S = 150.0  # a run longer than this is killed and recorded as failed (timeout)


def _key(r):
    return (r["case"], r["model"], r["route"], r["maxh"])


def one(case, maxh, model, route, timeout=RUN_TIMEOUT_S):
    """One short run in a fresh process; the row of the table (``status`` says how it went)."""
    row = {"case": case, "maxh": maxh, "model": model, "route": route}
    out = tempfile.mkdtemp(prefix="pacto_it3d_")
    memfile = os.path.join(out, "time.txt")
    run = os.path.join(out, "run")
    cmd = ["/usr/bin/time", "-o", memfile, "-f", "%M", sys.executable, "-m", "pacto_ng.cli",
           "run", case, "--maxh", f"{maxh:g}", "--order", str(ORDER), "--model", model,
           "--set", f"solver={route}", "--iterations", str(ITERATIONS), "--out", run, "--quiet"]
    row["command"] = " ".join(cmd[5:]).replace(sys.executable, "python3").replace(run, "TMP")
    t0 = time.perf_counter()
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        why = ("timeout" if timeout >= RUN_TIMEOUT_S else
               "the end of the study's time budget, not a failure of the run")
        row.update(status="failed" if timeout >= RUN_TIMEOUT_S else "skipped",
                   reason=f"killed after {timeout:.0f} s ({why})",
                   wall=time.perf_counter() - t0)
        shutil.rmtree(out, ignore_errors=True)
        return row
    row["wall"] = time.perf_counter() - t0
    try:
        row["rss_gib"] = int(open(memfile).read().strip().splitlines()[-1]) / 2 ** 20
    except (OSError, ValueError, IndexError):
        pass
    summ_path = os.path.join(run, "summary.json")
    hist_path = os.path.join(run, "history.csv")
    if done.returncode != 0 or not os.path.exists(hist_path):
        tail = (done.stderr or done.stdout).strip().splitlines()
        row.update(status="failed", reason=(tail[-1] if tail else f"exit {done.returncode}")[:200])
    else:
        summ = json.load(open(summ_path)) if os.path.exists(summ_path) else {}
        hist = np.genfromtxt(hist_path, delimiter=",", names=True)
        hist = np.atleast_1d(hist)
        times = [float(t) for t in hist["time"]]
        newton = [int(n) for n in hist["newton"]]
        loads = [float(x) for x in hist["load"]]
        row.update(ndof=int(summ.get("mesh", {}).get("displacement_dofs", 0)),
                   elements=int(summ.get("mesh", {}).get("elements", 0)),
                   times=times, newton=newton, loads=loads,
                   stopped=summ.get("stopped"), message=summ.get("message"),
                   run_wall=summ.get("wall_time_s"))
        timed = times[FIRST_TIMED:]
        if timed:
            row.update(status="ok", time=statistics.median(timed),
                       first=times[0], newton_median=statistics.median(newton[FIRST_TIMED:]))
        else:
            row.update(status="failed", reason=f"{len(times)} iterations only: "
                       f"{summ.get('message', '')}"[:200])
        if summ.get("stopped") == "newton":
            row.update(status="failed", reason=str(summ.get("message"))[:200])
    shutil.rmtree(out, ignore_errors=True)
    return row


def fit(rows, key):
    """Least-squares slope and intercept of log(key) against log(ndof); None below 2 sizes."""
    rows = [r for r in rows if r.get("status") == "ok" and r.get(key)]
    if len(rows) < 2:
        return None
    x = np.log([r["ndof"] for r in rows])
    y = np.log([r[key] for r in rows])
    return tuple(float(c) for c in np.polyfit(x, y, 1))


def study(budget, run_limit, results_path):
    """Every (size, case, model, route), smallest sizes first so that a partial study covers
    every combination; rows already in ``results_path`` are kept (the study resumes)."""
    rows = json.load(open(results_path)) if os.path.exists(results_path) else []
    have = {_key(r) for r in rows}
    t0 = time.perf_counter()
    stop = set()  # (case, model, route) that stopped growing
    for r in rows:
        if r.get("status") != "ok" or r.get("wall", 0) > run_limit:
            stop.add(_key(r)[:3])
    for i in range(max(len(v) for v in CASES.values())):
        for case, sizes in CASES.items():
            if i >= len(sizes):
                continue
            for model in MODELS:
                for route in ROUTES:
                    row = {"case": case, "maxh": sizes[i], "model": model, "route": route}
                    if _key(row) in have:
                        continue
                    if (case, model, route) in stop:
                        row.update(status="skipped", reason="a smaller size failed or took "
                                   f"more than {run_limit:.0f} s")
                    elif time.perf_counter() - t0 > budget:
                        row.update(status="skipped", reason=f"study budget of {budget:.0f} s "
                                   "spent")
                    else:
                        row = one(case, sizes[i], model, route,
                                  timeout=min(RUN_TIMEOUT_S,
                                              max(60.0, budget - (time.perf_counter() - t0))))
                        if row["status"] != "ok" or row["wall"] > run_limit:
                            stop.add((case, model, route))
                    rows.append(row)
                    print(f"  {case} {model} {route} maxh {sizes[i]:g}: "
                          + (f"{row['ndof']:,} dofs, {row['time']:.2f} s/iteration, "
                             f"{row.get('rss_gib', float('nan')):.2f} GiB, newton "
                             f"{row['newton']}, wall {row['wall']:.0f} s"
                             if row["status"] == "ok" else
                             f"{row['status']}: {row.get('reason')}"), flush=True)
                    with open(results_path, "w") as f:
                        json.dump(rows, f, indent=1)
    return rows


def _fmt_fit(f, what="time"):
    return "" if f is None else f"{f[0]:.2f}"


def markdown(rows, took, mach, partial=False):
    lines = ["## 3D optimisation iterations: time and memory against dofs", ""]
    if partial:
        lines += ["**Partial study**: not every size was measured (see the rows marked "
                  "skipped).", ""]
    lines += [__doc__.strip().split("\n\n", 2)[2], "",
              "| case | model | route | maxh m | dofs | s / iteration (median, it. 2-4) | "
              "first iteration s | Newton its (it. 1-4) | load factor (it. 2-4) | "
              "peak memory GiB | run wall s | status |",
              "|---|---|---|---:|---:|---:|---:|---|---|---:|---:|---|"]
    order = {c: i for i, c in enumerate(CASES)}
    for r in sorted(rows, key=lambda r: (order[r["case"]], MODELS.index(r["model"]),
                                         ROUTES.index(r["route"]), -r["maxh"])):
        if r["status"] == "ok":
            loads = sorted(set(f"{x:.2g}" for x in r["loads"][FIRST_TIMED:]), key=float)
            lines.append(
                f"| {r['case']} | {r['model']} | {r['route']} | {r['maxh']:g} | "
                f"{r['ndof']:,} | {r['time']:.2f} | {r['first']:.2f} | "
                f"{' '.join(str(n) for n in r['newton'])} | {', '.join(loads)} | "
                f"{r.get('rss_gib', float('nan')):.2f} | {r['wall']:.0f} | ok |")
        else:
            lines.append(f"| {r['case']} | {r['model']} | {r['route']} | {r['maxh']:g} | "
                         f"{r.get('ndof', '') or ''} |  |  |  |  | "
                         f"{r['rss_gib']:.2f} | " if "rss_gib" in r else
                         f"| {r['case']} | {r['model']} | {r['route']} | {r['maxh']:g} | "
                         f"|  |  |  |  |  | ")
            lines[-1] += (f"{r['wall']:.0f} | " if "wall" in r else " | ") + \
                f"{r['status']}: {r.get('reason', '')} |"
    lines += ["", "Fitted log-log slopes against dofs (time per iteration / peak memory; "
              "the number of sizes fitted), and the time per iteration at 1e6 dofs "
              "extrapolated from the time fit:", "",
              "| case | model | route | sizes | slope of time | slope of memory | "
              "s / iteration at 1e6 dofs (extrapolated) | largest measured dofs |",
              "|---|---|---|---:|---:|---:|---:|---:|"]
    fits = {}
    for case in CASES:
        for model in MODELS:
            for route in ROUTES:
                sel = [r for r in rows if (r["case"], r["model"], r["route"]) == (case, model,
                                                                                 route)
                       and r["status"] == "ok"]
                ft, fm = fit(sel, "time"), fit(sel, "rss_gib")
                fits[case, model, route] = ft
                ext = "" if ft is None else f"{np.exp(ft[1]) * 1e6 ** ft[0]:.3g}"
                top = max((r["ndof"] for r in sel), default=0)
                lines.append(f"| {case} | {model} | {route} | {len(sel)} | {_fmt_fit(ft)} | "
                             f"{_fmt_fit(fm)} | {ext} | {top:,} |")
    its = [(k, v) for k, v in fits.items() if k[2] == "iterative" and v is not None]
    lin = [(k, v) for k, v in fits.items() if k[1] == "linear" and k[2] == "iterative"
           and v is not None]
    lines += ["", "Aims of the 3D work (a time slope <= 1.2 for the iterative route; <= 60 s "
              "per linear iteration at 1e6 dofs): slope "
              + (", ".join(f"{k[0]} {k[1]} {v[0]:.2f} "
                           f"({'met' if v[0] <= 1.2 else 'not met'})" for k, v in its)
                 or "not measured")
              + "; linear iteration at 1e6 dofs (an extrapolation of the fit, not measured) "
              + (", ".join(f"{k[0]} {np.exp(v[1]) * 1e6 ** v[0]:.0f} s "
                           f"({'met' if np.exp(v[1]) * 1e6 ** v[0] <= 60 else 'not met'})"
                           for k, v in lin) or "not measured") + ".",
              "", f"*Measured {mach}; the runs took {sum(r.get('wall', 0) for r in rows):.0f} s"
              + ("" if took is None else f" (this call {took:.0f} s)")
              + ", one after the other, "
              "beside another heavy process on the same 2-core machine: absolute times are "
              "inflated and noisy, which is why the table gives medians.*", "",
              "Regenerate: `PACTO_THREADS=1 python3 -m benchmarks.iteration_3d` (or "
              "`python3 -m benchmarks iteration_3d`); one run: the row's command, e.g. "
              f"`{rows[0].get('command', '') if rows else ''}`."]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=float, default=1400.0,
                    help="seconds of runs before the study skips the rest")
    ap.add_argument("--run-limit", type=float, default=240.0,
                    help="a route stops growing after a run longer than this (s)")
    ap.add_argument("--results", default=os.path.join(tempfile.gettempdir(),
                                                      "pacto_iteration_3d.json"),
                    help="the measured rows (kept: a second call resumes)")
    ap.add_argument("--fresh", action="store_true", help="forget the rows of --results")
    ap.add_argument("--out", default=os.path.join("docs", "studies.md"))
    ap.add_argument("--no-write", action="store_true", help="print the section only")
    args = ap.parse_args(argv)
    os.environ.setdefault("PACTO_THREADS", "1")
    from benchmarks.__main__ import machine, replace_block

    if args.fresh and os.path.exists(args.results):
        os.remove(args.results)
    mach = machine()
    print(f"[iteration_3d] {mach}", flush=True)
    t0 = time.perf_counter()
    rows = study(args.budget, args.run_limit, args.results)
    partial = any(r["status"] == "skipped" and "budget" in r.get("reason", "") for r in rows)
    body = markdown(rows, time.perf_counter() - t0, mach, partial)
    if not args.no_write:
        replace_block(args.out, "benchmarks-iteration_3d", body)
    print(body)
    return 0


if __name__ == "__main__":
    sys.exit(main())
