"""The silicone cases at their defaults, and the pressure where each first fails.

    python3 -m benchmarks silicone [--out docs/studies.md] [--runs DIR] [--cases A,B]

For ``pneunet-silicone`` and ``gripper-silicone``: ``pacto run CASE`` at its defaults (into
``DIR/CASE``, reused if it holds a finished run), then ``pacto evaluate`` of its final design
(the checkpoint's design variables, filtered and projected as the run left them) at inlet
pressures doubling from the case's load, with the mixed formulation (the case's default) and
with the displacement formulation (each into its own folder of DIR, reused likewise), until
Newton no longer reaches the full pressure.  The
pressure where it first fails is the first of that series whose equilibrium Newton did not
reach (``load_factor_reached`` < 1 in the evaluation's summary.json); the table gives the load
factor it reached there and the output displacement at the last pressure reached.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

CASES = ("pneunet-silicone", "gripper-silicone")
DOUBLINGS = 8


def pacto(*args) -> int:
    return subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args]).returncode


def run_case(case: str, runs: str) -> dict:
    out = os.path.join(runs, case)
    summary = os.path.join(out, "summary.json")
    if not os.path.exists(summary):
        pacto("run", case, "--out", out, "--quiet", "--overwrite")
    return json.load(open(summary))


def first_failure(case: str, runs: str, formulation: str, load: float) -> list[dict]:
    rows = []
    ckpt = os.path.join(runs, case, "checkpoint.npz")
    for k in range(DOUBLINGS):
        p = load * 2 ** k
        out = os.path.join(runs, f"{case}-{formulation}-{p:g}")
        if not os.path.exists(os.path.join(out, "summary.json")):  # else reused
            pacto("evaluate", case, "--density", ckpt, "--load", f"{p:g}", "--set",
                  f"formulation={formulation}", "--out", out, "--quiet", "--overwrite")
        s = json.load(open(os.path.join(out, "summary.json")))
        rows.append({"pressure": p, "reached": float(s["load_factor_reached"]),
                     "delta": s.get("output_displacement"),
                     "newton": s.get("newton_iterations_total")})
        print(case, formulation, rows[-1], flush=True)
        if rows[-1]["reached"] < 1.0:
            break
    return rows


def report(results: dict) -> str:
    lines = ["| case | run at defaults | formulation | largest pressure reached | first "
             "failure (load factor reached) | Δ at the largest pressure |", "|---|---|---|---|---|---|"]
    for case, (s, sweeps) in results.items():
        run = (f"{s['iterations']} iterations, {'converged' if s['converged'] else 'not converged'}"
               f", Δ = {s['output_displacement']:.3e} m at {s['load']:g} Pa "
               f"({s['formulation']})")
        for form, rows in sweeps.items():
            ok = [r for r in rows if r["reached"] >= 1.0]
            bad = [r for r in rows if r["reached"] < 1.0]
            last = ok[-1] if ok else None
            lines.append(
                f"| {case} | {run} | {form} | {last['pressure']:g} Pa |" if last else
                f"| {case} | {run} | {form} | none |")
            lines[-1] += (f" {bad[0]['pressure']:g} Pa ({bad[0]['reached']:.3f}) |" if bad
                          else f" none up to {rows[-1]['pressure']:g} Pa |")
            lines[-1] += f" {last['delta']:.3e} m |" if last and last["delta"] is not None \
                else " |"
    lines += ["", "Each evaluation: Δ (m) and the Newton iterations of its adaptive load steps "
              "(`failed at f`: the load factor Newton reached).", "",
              "| case | pressure (Pa) | mixed | displacement |", "|---|---|---|---|"]
    for case, (_, sweeps) in results.items():
        by_p = {}
        for form, rows in sweeps.items():
            for r in rows:
                by_p.setdefault(r["pressure"], {})[form] = r
        for P, cols in sorted(by_p.items()):
            cells = []
            for form in ("mixed", "displacement"):
                r = cols.get(form)
                cells.append("" if r is None else
                             f"failed at {r['reached']:.3f} ({r['newton']} iterations)"
                             if r["reached"] < 1.0 else
                             f"{r['delta']:.3e} ({r['newton']} iterations)")
            lines.append(f"| {case} | {P:g} | {cells[0]} | {cells[1]} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join("docs", "studies.md"))
    ap.add_argument("--runs", default=os.path.join("output", "benchmarks-silicone"))
    ap.add_argument("--cases", default=",".join(CASES))
    args = ap.parse_args(argv)
    from benchmarks.__main__ import machine, replace_block

    mach = machine()
    print(f"[silicone] {mach}", flush=True)
    results = {}
    for case in args.cases.split(","):
        s = run_case(case, args.runs)
        sweeps = {form: first_failure(case, args.runs, form, s["load"])
                  for form in ("mixed", "displacement")}
        results[case] = (s, sweeps)
    body = ("## Silicone cases: defaults and the pressure where each first fails\n\n"
            "`python3 -m benchmarks silicone` (" + mach + ").  "
            + __doc__.split("\n\n")[2].replace("\n", " ") + "\n\n" + report(results))
    replace_block(args.out, "benchmarks-silicone", body)
    print(body)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
