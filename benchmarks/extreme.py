"""Extreme loads: the pressure-actuated cases past the thesis's pressures, and the nonlinear
force cases (cantilever, inverter) at and past their published limits.

    python -m benchmarks.extreme [--runs DIR] [--only NAME,...] [--report-only] [--cross]
                                 [--out FILE] [--doc docs/studies.md]

Every run is a plain ``pacto run`` (the command is in the table), written to ``DIR/NAME``
(default: $PACTO_BENCH_RUNS or ``output/extreme``); a run whose folder already holds a
``summary.json`` is not run again, so an interrupted study resumes.  Pressure-case designs are
then post-analysed with ``pacto analyse`` (density threshold 0.5, 0.4 for the inverter — lowered by `analyse` since 2026-12-02 where the part then misses the output; the analysis tables below were made before that; body-fitted remesh; Neo-Hookean
re-analysis under the Darcy pressure of the thresholded part, a fixed and a follower pressure on
its wetted boundary) over the same pressures for every design of a case, so that the linear and
the nonlinear designs are compared under the same Neo-Hookean analysis.

The optimisation settings of the nonlinear runs: the case defaults plus load continuation over
the first iterations (``load_ramp``), adaptive load continuation past a Newton failure
(``load_adapt``) and machine-code forms (``realcompile``); the command of each run, as read
back from its ``params.json``, is in the table (the Wang runs of the pa-inverter and the
cantilever pin ``--order 1``, the thesis's order; a run that starts from another's design names its folder in
``init_design``).  A cantilever or force-inverter run that reaches its iteration cap (150, 200) without meeting the
convergence test is continued from its checkpoint with ``pacto resume DIR --iterations N``
(N = 300, 400): its command in the table then shows ``--iterations N``.  "valid" means: the run finished at the full load (``load_factor_reached``
= 1, so every accepted state had det F > 0 where the model needs it), the volume constraint is
met (volume fraction <= volfrac + 0.002), the objective is better than at the first iteration
run at the full load (with a load ramp, iteration 0 ran at a fraction of it), and a mechanism's
output moves the working way (Δ > 0).  "grey": the fraction of design.vtu's points with 0.1 < ρ̄ < 0.9.
"leakage": the Darcy leakage figure of summary.json (pressure in solid beyond the wet skin of
the inlet-connected cavity; a solid island inside the cavity counts too).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

from benchmarks.extreme_cross import (CROSS, FOLLOWER_5E7, cross_force_markdown, cross_markdown,
                                      follower_markdown)
from benchmarks.extreme_tables import (analyses_markdown, design_difference,
                                       force_cases_markdown, inverter_designs_markdown,
                                       read_json, runs_markdown)


NL = ["--set", "load_adapt=1.2", "--set", "realcompile=1"]
PA = ["--set", "load_ramp=30"] + NL
FC = ["--set", "load_ramp=20"] + NL
#: the thesis meshes of the cases whose defaults are finer (the knee of their trade curves)
GRIP, PN = ["--maxh", "0.004"], ["--maxh", "0.003"]
#: order 1, the thesis's, for the Wang runs of the pa-inverter and the cantilever (whose Wang
#: default is order 2); harmless on the Neo-Hookean rows (their default is order 1)
O1 = ["--order", "1"]

#: name -> (case, arguments); the order is the order of the tables
RUNS = {
    # pa-inverter (thesis limit 1e7 Pa)
    "inv_lin": ("pa-inverter", ["--model", "linear", "--load", "1e6"]),
    "inv_w_1e6": ("pa-inverter", O1 + ["--model", "wang", "--load", "1e6"] + PA),
    "inv_w_1e7": ("pa-inverter", O1 + ["--model", "wang", "--load", "1e7"] + PA),
    "inv_w_5e7": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7"] + PA),
    "inv_w_5e7_b64": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--set", "beta_max=64"] + PA),
    "inv_wf_5e7": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--set", "load_type=follower"] + PA),
    "inv_wf_1e7": ("pa-inverter", O1 + ["--model", "wang", "--load", "1e7", "--set", "load_type=follower"] + PA),
    # 5e7 Pa on the coarse mesh, fixed and follower load (the thesis mesh's follower run was
    # too slow to finish)
    "inv_w_5e7_c": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--maxh", "0.008"] + PA),
    "inv_wf_5e7_c": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--maxh", "0.008",
                                     "--set", "load_type=follower"] + PA),
    # a slow load ramp (100 iterations): the layout forms at the lower pressures, as in the
    # 1e7 Pa run, before the full load acts
    "inv_w_5e7_r100": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--set", "load_ramp=100"] + NL),
    "inv_wf_5e7_r100": ("pa-inverter", O1 + ["--model", "wang", "--load", "5e7", "--set", "load_ramp=100",
                                        "--set", "load_type=follower"] + NL),
    # plain Neo-Hookean with a stiffer void (E0 = 1e-4 E1) and the slow ramp
    "inv_nh_5e7_e4_r100": ("pa-inverter", ["--model", "neohookean", "--load", "5e7", "--set", "E0=3e5",
                                           "--set", "load_ramp=100"] + NL),
    "inv_nhf_5e7_e4_r100": ("pa-inverter", ["--model", "neohookean", "--load", "5e7", "--set", "E0=3e5",
                                            "--set", "load_ramp=100", "--set", "load_type=follower"] + NL),
    "inv_nh_1e7": ("pa-inverter", ["--model", "neohookean", "--load", "1e7"] + PA),
    # pa-gripper (thesis limit 1e7 Pa)
    "grip_lin": ("pa-gripper", GRIP + ["--model", "linear", "--load", "1e6"]),
    "grip_w_1e6": ("pa-gripper", GRIP + ["--model", "wang", "--load", "1e6"] + PA),
    "grip_w_1e7": ("pa-gripper", GRIP + ["--model", "wang", "--load", "1e7"] + PA),
    "grip_w_5e7": ("pa-gripper", GRIP + ["--model", "wang", "--load", "5e7"] + PA),
    "grip_w_5e7_r100": ("pa-gripper", GRIP + ["--model", "wang", "--load", "5e7", "--set", "load_ramp=100"] + NL),
    "grip_nh_5e7_e4_r100": ("pa-gripper", GRIP + ["--model", "neohookean", "--load", "5e7", "--set",
                                                 "E0=3e5", "--set", "load_ramp=100"] + NL),
    # pneunet (thesis limit 1e5 Pa), mm-gripper (thesis limit 5e5 Pa)
    "pn_w_1e6": ("pneunet", PN + ["--model", "wang", "--load", "1e6"] + PA),
    "pn_nh_1e6": ("pneunet", PN + ["--model", "neohookean", "--load", "1e6"] + PA),
    # a sharper projection (β doubling to 64), and the objective "maximise Δ, SE <= se_max"
    "pn_w_1e6_b64": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "beta_max=64"] + PA),
    "pn_w_1e6_ose": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set",
                                 "objective=output_se"] + PA),
    # Wang et al.'s sharper schedule and interpolation settings on the PneuNet
    "pn_w2014_1e6": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "penal_step=0.05",
                                 "--set", "beta=4", "--set", "beta_max=64", "--set",
                                 "beta_every=10", "--set", "wang_beta=500", "--set",
                                 "wang_eta=0.01"] + PA),
    "pn_w_1e6_r100": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "load_ramp=100"] + NL),
    # the same with β stopping at 16: in pn_w_1e6_r100 the step of β to 32 at the full load
    # dropped the load factor to 0.001
    "pn_w_1e6_r100_b16": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "load_ramp=100",
                                           "--set", "beta_max=16"] + NL),
    # a stiffer void, E0 = 1e-3 E1 (the stability map: Neo-Hookean then carries 3e7-1e8 Pa)
    "pn_nh_1e6_e3": ("pneunet", PN + ["--model", "neohookean", "--load", "1e6", "--set", "load_ramp=100",
                                      "--set", "E0=1e5"] + NL),
    "pn_w_1e6_e3": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "load_ramp=100",
                                     "--set", "E0=1e5"] + NL),
    # a filter twice as wide (0.018 m): no wall thinner than the gaps the runs above open
    "pn_w_1e6_r100_f2": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "load_ramp=100",
                                          "--set", "beta_max=16", "--set", "filter_radius=0.018"] + NL),
    # the wide filter with the default β (to 32): β's steps at the full load (r100, 250
    # iterations to recover), or a load ramp slower than β's continuation (r150)
    "pn_w_1e6_r100_f2_b32": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--iterations", "250",
                                              "--set", "load_ramp=100", "--set", "filter_radius=0.018"] + NL),
    "pn_w_1e6_r150_f2_b32": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--iterations", "250",
                                              "--set", "load_ramp=150", "--set", "filter_radius=0.018"] + NL),
    # Neo-Hookean with a stiffer void, the wide filter and the slow ramp
    **{f"pn_nh_1e6_{tag}_f2_r150": ("pneunet", PN + ["--model", "neohookean", "--load", "1e6", "--iterations",
                                                    "250", "--set", "load_ramp=150", "--set",
                                                    "filter_radius=0.018", "--set", f"E0={E0}"] + NL)
       for tag, E0 in (("e3", "1e5"), ("e4", "1e4"))},
    # E0 = 1e-4 E1 with the case's filter, and from the linear design
    "pn_nh_1e6_e4_r150": ("pneunet", PN + ["--model", "neohookean", "--load", "1e6", "--iterations", "250",
                                           "--set", "load_ramp=150", "--set", "E0=1e4"] + NL),
    "pn_nh_1e6_e4_init_b8": ("pneunet", PN + ["--model", "neohookean", "--load", "1e6", "--set", "E0=1e4",
                                              "--set", "init_design={root}/pn_lin_1e6", "--set",
                                              "load_ramp=30", "--set", "penal_start=3", "--set",
                                              "beta=8"] + NL),
    # Wang from the linear design (a closed chamber) of the same pressure, the schedule
    # restarted (a) or continued at p = 3, β = 8 (b)
    "pn_lin_1e6": ("pneunet", PN + ["--model", "linear", "--load", "1e6"]),
    "pn_w_1e6_init": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set",
                                       "init_design={root}/pn_lin_1e6", "--set", "load_ramp=30"] + NL),
    "pn_w_1e6_init_b8": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set",
                                          "init_design={root}/pn_lin_1e6", "--set", "load_ramp=30",
                                          "--set", "penal_start=3", "--set", "beta=8"] + NL),
    # an output spring 10x stiffer (1e5 N/m): the spring-to-pressure ratio of the thesis's 1e5 Pa
    # runs (a variant of the case, not the case)
    "pn_w_1e6_r100_k1e5": ("pneunet", PN + ["--model", "wang", "--load", "1e6", "--set", "load_ramp=100",
                                            "--set", "beta_max=16", "--set", "k_out=1e5"] + NL),
    "mm_w_5e6": ("mm-gripper", GRIP + ["--model", "wang", "--load", "5e6"] + PA),
    "mm_w_5e6_r100": ("mm-gripper", GRIP + ["--model", "wang", "--load", "5e6", "--set", "load_ramp=100"] + NL),
    "mm_nh_5e6_e4_r100": ("mm-gripper", GRIP + ["--model", "neohookean", "--load", "5e6", "--set", "E0=3e4",
                                               "--set", "load_ramp=100"] + NL),
    # cantilever (thesis: NH 150 kN, Wang 250 kN; Wang et al. 2014: NH 240 kN, Wang 500 kN)
    **{f"cant_{m}_{F}": ("cantilever", O1 + ["--model", {"nh": "neohookean", "w": "wang"}[m],
                                             "--load", f"{F}e3"] + FC)
       for F in (80, 144, 240, 300, 500, 800) for m in ("nh", "w")},
    # cantilever on Wang et al.'s 120 x 30 quad mesh
    **{f"cant_q_{m}_{F}": ("cantilever", O1 + ["--model", {"nh": "neohookean", "w": "wang"}[m],
                                               "--load", f"{F}e3", "--nelx", "120", "--nely",
                                               "30"] + FC)
       for F in (80, 144, 240, 300) for m in ("nh", "w")},
    # Wang et al.'s own schedule, as data: p 1 -> 3 by 0.05, beta 4 -> 64 doubling every 10,
    # their interpolation settings beta1 = 500, eta1 = 0.01; quads and the thesis mesh
    **{f"cant{q}_w2014_w_{F}": ("cantilever", O1 + ["--model", "wang", "--load", f"{F}e3"] + mesh
                                + ["--set", "penal_start=1", "--set", "penal_step=0.05", "--set",
                                   "beta=4", "--set", "beta_max=64", "--set", "beta_every=10",
                                   "--set", "wang_beta=500", "--set", "wang_eta=0.01"] + FC)
       for F in (240, 300) for q, mesh in (("_q", ["--nelx", "120", "--nely", "30"]), ("", []))},
    # force inverter at the thesis mesh (thesis limit 0.4 N)
    "inv_f_lin_04": ("inverter", ["--model", "linear", "--load", "0.4", "--maxh", "3e-6"]),
    **{f"inv_f_{m}_{tag}": ("inverter", ["--model", {"nh": "neohookean", "w": "wang"}[m],
                                        "--load", F, "--maxh", "3e-6"] + FC)
       for tag, F in (("002", "0.02"), ("01", "0.1"), ("02", "0.2"), ("04", "0.4"), ("08", "0.8"))
       for m in ("nh", "w")},
}

#: pressure-case designs compared under one Neo-Hookean analysis sweep (pressures in Pa)
#: and the density threshold: 0.4 for the inverter, whose linear design's output bar hangs on a
#: grey joint that a 0.5 threshold cuts off (the part then floats and is dropped; measured)
ANALYSES = {
    "pa-inverter": (["inv_lin", "inv_w_1e6", "inv_w_1e7", "inv_wf_1e7", "inv_w_5e7", "inv_w_5e7_b64",
                     "inv_wf_5e7", "inv_w_5e7_c", "inv_wf_5e7_c", "inv_w_5e7_r100",
                     "inv_wf_5e7_r100", "inv_nh_5e7_e4_r100", "inv_nhf_5e7_e4_r100"],
                    "1e5,1e6,1e7,5e7", 0.4),
    "pa-gripper": (["grip_lin", "grip_w_1e6", "grip_w_1e7", "grip_w_5e7", "grip_w_5e7_r100",
                    "grip_nh_5e7_e4_r100"], "1e5,1e6,1e7,5e7", 0.5),
    "pneunet": (["pn_w_1e6", "pn_nh_1e6", "pn_w2014_1e6", "pn_w_1e6_b64", "pn_w_1e6_ose",
                 "pn_w_1e6_r100", "pn_w_1e6_r100_b16",
                 "pn_nh_1e6_e3", "pn_w_1e6_e3", "pn_w_1e6_r100_f2", "pn_w_1e6_r100_k1e5",
                 "pn_w_1e6_r100_f2_b32", "pn_w_1e6_r150_f2_b32",
                 "pn_nh_1e6_e3_f2_r150", "pn_nh_1e6_e4_f2_r150", "pn_lin_1e6", "pn_w_1e6_init",
                 "pn_w_1e6_init_b8", "pn_nh_1e6_e4_r150", "pn_nh_1e6_e4_init_b8"],
                "1e4,1e5,1e6", 0.5),
}


def command(name: str) -> str:
    case, args = RUNS[name]
    return " ".join(["pacto", "run", case] + args)


#: a force-case run that stops at its iteration cap without converging is continued to this
#: cap with ``pacto resume DIR --iterations N`` (the same run, from its checkpoint)
EXTEND = {"cantilever": 300, "inverter": 400}


def run(root: Path, name: str) -> None:
    out = root / name
    case, args = RUNS[name]
    args = [a.replace("{root}", str(root)) for a in args]  # a run that starts from another's design
    if not (out / "summary.json").exists():
        print(f"[extreme] {command(name)} --out {out}", flush=True)
        subprocess.run([sys.executable, "-m", "pacto_ng.cli", "run", case, *args, "--out",
                        str(out)], check=False)
    s = read_json(out / "summary.json")
    cap = EXTEND.get(case)
    if s is not None and cap and s["stopped"] == "iterations" and s["iterations"] < cap:
        print(f"[extreme] pacto resume {out} --iterations {cap}", flush=True)
        subprocess.run([sys.executable, "-m", "pacto_ng.cli", "resume", str(out),
                        "--iterations", str(cap)], check=False)


def analyse(root: Path, name: str, pressures: str, threshold: float) -> None:
    out = root / name
    done = read_json(out / "analysis" / "analysis.json")
    asked = None if done is None else done["settings"].get(
        "threshold_choice", {"requested": done["settings"]["threshold"]})["requested"]
    if not (out / "summary.json").exists() or asked == threshold:
        return
    print(f"[extreme] pacto analyse {out} --pressures {pressures} --threshold {threshold}",
          flush=True)
    subprocess.run([sys.executable, "-m", "pacto_ng.cli", "analyse", str(out), "--pressures",
                    pressures, "--threshold", str(threshold), "--quiet"], check=False)



def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default=os.environ.get("PACTO_BENCH_RUNS", "output/extreme"))
    ap.add_argument("--only", default="", help="comma-separated run names (default: all)")
    ap.add_argument("--report-only", action="store_true", help="no new runs, only the tables")
    ap.add_argument("--out", default=None, help="print the tables here (default: stdout)")
    ap.add_argument("--doc", default=None, help="rewrite the block benchmarks-extreme of this file")
    ap.add_argument("--cross", action="store_true",
                    help="also analyse every design at every pressure (cached in DIR/cross_CASE.json)")
    args = ap.parse_args(argv)
    root = Path(args.runs)
    names = [n for n in args.only.split(",") if n] or list(RUNS)
    for n in names:
        if n not in RUNS:
            ap.error(f"--only: unknown run '{n}' (choose from {', '.join(RUNS)})")
    if not args.report_only:
        for n in names:
            run(root, n)
        for case, (designs, pressures, threshold) in ANALYSES.items():
            for n in designs:
                if n in names:
                    analyse(root, n, pressures, threshold)
    text = ["### Runs", "", runs_markdown(root, names), "", "### Force cases", "",
            force_cases_markdown(root, RUNS), "", "#### Force inverter designs", "",
            inverter_designs_markdown(root, RUNS), "", "### Neo-Hookean analyses of the parts",
            "", analyses_markdown(root, names)]
    # two small cross studies always (cached in DIR): the force inverter's designs under one
    # Wang analysis, and the follower-load design against the fixed-load ones
    text += ["", "### Force inverter: each design analysed with the Wang model at 0.02 N "
             "and 0.4 N", "", cross_force_markdown(root, root / "cross_inverter.json")]
    text += ["", "### pa-inverter at 1e7 Pa: the follower-load design against the fixed-load "
             "designs (Wang mechanics on the density field, the follower load through I + γ∇u)",
             "", follower_markdown(root, root / "cross_follower_1e7.json")]
    text += ["", "### pa-inverter at 5e7 Pa: the follower-load designs against the fixed-load "
             "designs, optimised at 5e7 and at 1e7 Pa (as above, at 5e7 Pa)", "",
             follower_markdown(root, root / "cross_follower_5e7.json", FOLLOWER_5E7, 5e7)]
    if args.cross:
        for case in CROSS:
            text += ["", f"### {case}: each design analysed at each pressure (Wang mechanics on "
                     "the density field; −Δ/SE in m/J; the follower load through F)", "",
                     cross_markdown(root, case, root / f"cross_{case}.json")]
        pairs = [(a, b) for designs, _ in CROSS.values() for a in designs[1:] for b in designs[:1]]
        pairs += [("inv_wf_1e7", "inv_w_1e7")]
        rows = [(a, b, design_difference(root, a, b)) for a, b in pairs
                if (root / a / "design.vtu").exists() and (root / b / "design.vtu").exists()]
        text += ["", "| design | against | ‖ρ̄ − ρ̄_ref‖ / ‖ρ̄_ref‖ |", "|---|---|---|"]
        text += [f"| {a} | {b} | {d:.3f} |" for a, b, d in rows if d is not None]
    out = "\n".join(text)
    if args.out:
        Path(args.out).write_text(out + "\n")
    else:
        print(out)
    if args.doc:
        from benchmarks.__main__ import _describe, machine, replace_block

        body = ["## Extreme loads (thesis meshes)", "", _describe(sys.modules[__name__]), "", out,
                "", "Regenerate: `python -m benchmarks.extreme --runs DIR --doc "
                "docs/studies.md` (runs what is missing in DIR, then rewrites this block; "
                "`--cross` adds every PA design analysed at every pressure).",
                "", f"*Tables written {machine()}; the runs' wall times are of one run each, "
                "measured while other runs shared the 2 cores (2-4 processes at a time): "
                "indicative only (the timing comparisons, as medians and ratios, are the peer, "
                "trade, profile and MBB sections).*"]
        replace_block(args.doc, "benchmarks-extreme", "\n".join(body))
    return 0


if __name__ == "__main__":
    sys.exit(main())
