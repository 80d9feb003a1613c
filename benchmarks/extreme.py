"""Extreme loads: the pressure-actuated cases past the thesis's pressures, and the nonlinear
force cases (cantilever, inverter) at and past their published limits.

    python -m benchmarks.extreme [--runs DIR] [--only NAME,...] [--report-only] [--cross]
                                 [--out FILE] [--doc docs/benchmarks.md]

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
import json
import os
import subprocess
import sys
from pathlib import Path

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
    s = _load(out / "summary.json")
    cap = EXTEND.get(case)
    if s is not None and cap and s["stopped"] == "iterations" and s["iterations"] < cap:
        print(f"[extreme] pacto resume {out} --iterations {cap}", flush=True)
        subprocess.run([sys.executable, "-m", "pacto_ng.cli", "resume", str(out),
                        "--iterations", str(cap)], check=False)


def analyse(root: Path, name: str, pressures: str, threshold: float) -> None:
    out = root / name
    done = _load(out / "analysis" / "analysis.json")
    asked = None if done is None else done["settings"].get(
        "threshold_choice", {"requested": done["settings"]["threshold"]})["requested"]
    if not (out / "summary.json").exists() or asked == threshold:
        return
    print(f"[extreme] pacto analyse {out} --pressures {pressures} --threshold {threshold}",
          flush=True)
    subprocess.run([sys.executable, "-m", "pacto_ng.cli", "analyse", str(out), "--pressures",
                    pressures, "--threshold", str(threshold), "--quiet"], check=False)


#: cross analyses: every design of a case analysed with the Wang model (Neo-Hookean wherever
#: material is) on its density field, at each pressure, with the fixed and the follower load
CROSS = {
    "pa-inverter": (["inv_lin", "inv_w_1e6", "inv_w_1e7", "inv_w_5e7", "inv_w_5e7_r100"],
                    [(1e6, "fixed"), (1e7, "fixed"), (5e7, "fixed"), (1e7, "follower"),
                     (5e7, "follower")]),
    "pa-gripper": (["grip_lin", "grip_w_1e6", "grip_w_1e7", "grip_w_5e7", "grip_w_5e7_r100"],
                   [(1e6, "fixed"), (1e7, "fixed"), (5e7, "fixed"), (5e7, "follower")]),
}


def rebuilt(folder: Path, **changes):
    """(run, problem): the final design of a run folder analysed again with ``changes`` to its
    parameters (no load ramp, no machine-code forms: one analysis)."""
    import dataclasses

    from pacto_ng.post.runs import load_run, rebuild
    from pacto_ng.threads import compute

    run = load_run(folder, "extreme")
    run.params = run.params.replace(load_ramp=0, realcompile=False, **changes)
    with compute():
        return run, rebuild(run)


def cross_evaluate(folder: Path, model: str, load: float, load_type: str,
                   follower_wang: bool = True) -> dict:
    """The final design of a run (its density field, the run's last penalty and β) analysed
    with ``model`` at inlet pressure ``load`` under a ``load_type`` Darcy load: −Δ/SE, Δ, SE,
    or the load factor Newton reached.  ``follower_wang``: the Wang follower load follows
    I + γ∇u (False: F everywhere)."""
    _, problem = rebuilt(folder, model=model, load=load, load_type=load_type,
                         newton_increment=0.25, follower_wang=follower_wang)
    if problem.failure:
        reached = problem.mech.result.load_reached if problem.mech.result else 0.0
        return dict(ok=False, reached=reached)
    v = problem.values
    return dict(ok=True, objective=float(v[problem.objective]), delta=float(v["delta"]),
                se=float(v["se"]) if "se" in v else None)


def cached_table(root: Path, cache: Path, designs, points, head, evaluate, cell) -> str:
    """A markdown table, one row per existing run of ``designs`` and one column per point:
    ``evaluate(name, point)`` (a dict with ``ok``, or ``reached`` on failure) is cached in the
    JSON file ``cache`` under ``"name|key(point)"``; ``cell(result)`` formats a success."""
    done = json.loads(cache.read_text()) if cache.exists() else {}
    lines = [head, "|---|" + "---|" * len(points)]
    for n in designs:
        if not (root / n / "summary.json").exists():
            continue
        cells = []
        for key, point in points:
            if f"{n}|{key}" not in done:
                done[f"{n}|{key}"] = evaluate(n, point)
                cache.write_text(json.dumps(done, indent=1))
            r = done[f"{n}|{key}"]
            cells.append(cell(r) if r["ok"] else f"fails (load factor {r['reached']:.2g})")
        lines.append(f"| {n} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def cross_markdown(root: Path, case: str, cache: Path) -> str:
    designs, points = CROSS[case]
    head = "| design (optimised at) | " + " | ".join(f"{P:.0e} Pa {t}" for P, t in points) + " |"
    # computed before follower_wang existed: the follower load through F
    return cached_table(
        root, cache, designs, [(f"{P:g}|{t}", (P, t)) for P, t in points], head,
        lambda n, pt: cross_evaluate(root / n, "wang", pt[0], pt[1], follower_wang=False),
        lambda r: f"{r['objective']:.4g} (Δ {1e3 * r['delta']:.3g} mm)")


#: follower design against fixed-load designs at 1e7 Pa, Wang mechanics, follower_wang on
FOLLOWER_1E7 = ["inv_wf_1e7", "inv_w_1e7", "inv_lin"]
#: at 5e7 Pa: the follower and the fixed-load designs optimised there with the 100-iteration
#: load ramp, and the 1e7 Pa designs of each load type
FOLLOWER_5E7 = ["inv_wf_5e7_r100", "inv_w_5e7_r100", "inv_wf_1e7", "inv_w_1e7"]


def follower_markdown(root: Path, cache: Path, designs=FOLLOWER_1E7, load=1e7) -> str:
    head = "| design | under the follower load: −Δ/SE (Δ [mm], SE [J]) | under the fixed load |"
    return cached_table(
        root, cache, designs, [(t, t) for t in ("follower", "fixed")], head,
        lambda n, t: cross_evaluate(root / n, "wang", load, t),
        lambda r: f"{r['objective']:.4g} ({1e3 * r['delta']:.3g}, {r['se']:.3g})")


def design_difference(root: Path, a: str, b: str):
    """‖ρ̄_a − ρ̄_b‖ / ‖ρ̄_b‖ over the elements (same case and mesh), from design.vtu."""
    import meshio
    import numpy as np

    ra, rb = (np.asarray(meshio.read(root / n / "design.vtu").point_data["rho_bar"])
              for n in (a, b))
    if ra.shape != rb.shape:
        return None
    return float(np.linalg.norm(ra - rb) / np.linalg.norm(rb))


def _load(path: Path):
    return json.loads(path.read_text()) if path.exists() else None


def _g(x, fmt="{:.4g}"):
    return "–" if x is None else fmt.format(x)


def first_full_load_objective(folder: Path):
    """The objective of the first iteration run at the full load (history.csv), or None."""
    import csv

    path = folder / "history.csv"
    if not path.exists():
        return None
    with open(path) as fh:
        for row in csv.DictReader(fh):
            if float(row["load"]) >= 1.0:
                return float(row["objective"])
    return None


def grey_fraction(folder: Path):
    """Fraction of the design.vtu points (ρ̄ as written there) with 0.1 < ρ̄ < 0.9."""
    import meshio
    import numpy as np

    path = folder / "design.vtu"
    if not path.exists():
        return None
    m = meshio.read(path)
    r = np.asarray(m.point_data["rho_bar" if "rho_bar" in m.point_data else "rho_bar1"])
    return float(np.mean((r > 0.1) & (r < 0.9)))


def valid(s: dict, folder: Path) -> bool:
    """Finished at the full load, volume met, objective better than at the first full-load
    iteration, and a mechanism's output moving the right way (Δ > 0)."""
    p = s["parameters"]
    first = first_full_load_objective(folder)
    delta = s.get("output_displacement")
    return bool(s.get("load_factor_reached") == 1.0 and s.get("stopped") != "newton"
                and s["volume_fraction"] <= p["volfrac"] + 0.002
                and s["objective"] is not None and first is not None and s["objective"] <= first
                and (delta is None or s.get("objective_name") != "objective" or delta > 0))


def command_of(folder: Path) -> str:
    """The ``pacto run`` arguments of a run folder: its case and every parameter that differs
    from the case's defaults (read from params.json)."""
    from pacto_ng.case import get_case

    info = json.loads((folder / "params.json").read_text())
    case = get_case(info["case"])
    ref = case.defaults.to_dict()
    args = [case.name]
    for key, val in info["params"].items():
        if ref.get(key) == val:
            continue
        if key == "order" and val == case.order_for(info["params"]["model"]):
            continue  # the case's order for the run's model
        if key in ("model", "load", "maxh", "order", "nelx", "nely", "iterations"):
            args += [f"--{key}", f"{val:g}" if isinstance(val, float) else str(val)]
        else:
            args += ["--set", f"{key}={int(val) if isinstance(val, bool) else val}"]
    return " ".join(args)


def runs_markdown(root: Path, names) -> str:
    head = ("| run | command (`pacto run ...`) | stopped | its | load factor reached | objective: it 0 "
            "→ first at full load → final | Δ [mm] | volume | grey | leakage | Newton its | wall [s] | valid |")
    lines = [head, "|" + "---|" * 13]
    for n in names:
        s = _load(root / n / "summary.json")
        if s is None:
            continue
        hist = s.get("objective_history") or [None]
        d = s.get("output_displacement")
        lines.append(
            f"| {n} | `{command_of(root / n)}` | {s['stopped']} | {s['iterations']} "
            f"| {_g(s.get('load_factor_reached'))} | {_g(hist[0])} → "
            f"{_g(first_full_load_objective(root / n))} → {_g(s['objective'])} "
            f"| {_g(None if d is None else 1e3 * d)} | {s['volume_fraction']:.4f} "
            f"| {_g(grey_fraction(root / n), '{:.1%}')} "
            f"| {_g(s.get('leakage'), '{:.2%}')} | {s['newton_iterations_total']} "
            f"| {s['wall_time_s']:.0f} | {'yes' if valid(s, root / n) else '**no**'} |")
    return "\n".join(lines)


def analyses_markdown(root: Path, names) -> str:
    lines = ["| design | threshold | P [Pa] | expected Δ [mm] | Darcy Δ [mm] | fixed Δ [mm] "
             "| follower Δ [mm] | min J (follower) | remeshed vs thresholded area | output port moved [m] |",
             "|" + "---|" * 10]
    for n in names:
        a = _load(root / n / "analysis" / "analysis.json")
        if a is None:
            continue
        for r in a["pressures"]:
            cells = []
            for k in ("darcy", "fixed", "follower"):
                v = r.get(k)
                cells.append("–" if not v or v["delta"] is None or not v["converged"]
                             else f"{1e3 * v['delta']:.4g}")
            fj = (r.get("follower") or {}).get("min_J")
            e = r["expected"] if r.get("expected_converged") else None
            lines.append(f"| {n} | {a['settings']['threshold']:g} | {r['pressure']:.0e} | "
                         f"{_g(None if e is None else 1e3 * e)} | " + " | ".join(cells)
                         + f" | {_g(fj, '{:.3f}')} | "
                         f"{_g(a['areas']['remeshed_vs_kept'], '{:+.2%}')} | "
                         f"{_g(a['remesh']['output_port_shift'], '{:.2g}')} |")
    return "\n".join(lines)


def strain_concentration(folder: Path):
    """How lumped a mechanism's hinges are: the 99th percentile of the Green–Lagrange strain
    norm ‖E‖ over the solid (ρ̄ > 0.5) P1 triangles of design.vtu divided by its median (E from
    the written u, element by element).  Lumped hinges: a few elements take the strain (high
    ratio); distributed compliance: a low ratio.  None if not P1 triangles."""
    import meshio
    import numpy as np

    path = folder / "design.vtu"
    if not path.exists():
        return None
    m = meshio.read(path)
    if len(m.cells) != 1 or m.cells[0].type != "triangle":
        return None
    tri = m.cells[0].data
    X, U = m.points[tri][:, :, :2], np.asarray(m.point_data["u"])[tri][:, :, :2]
    dX = np.stack([X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]], axis=2)
    dU = np.stack([U[:, 1] - U[:, 0], U[:, 2] - U[:, 0]], axis=2)
    F = np.eye(2) + dU @ np.linalg.inv(dX)
    E = 0.5 * (np.einsum("eki,ekj->eij", F, F) - np.eye(2))
    norm = np.linalg.norm(E.reshape(len(E), -1), axis=1)
    rho = np.asarray(m.point_data["rho_bar"]).reshape(-1)[tri[:, 0]]
    solid = norm[rho > 0.5]
    return float(np.percentile(solid, 99) / np.median(solid)) if solid.size else None


def inverter_designs_markdown(root: Path) -> str:
    """Force inverter designs: output displacement of each run, its design's difference from
    the linear design and its strain concentration (lumped vs distributed hinges)."""
    lines = ["| run | load [N] | model | Δ [µm] | ‖ρ̄ − ρ̄_linear‖ / ‖ρ̄_linear‖ | strain "
             "concentration (99th pct / median ‖E‖ in solid) | grey |", "|---|---|---|---|---|---|---|"]
    for n in RUNS:
        if RUNS[n][0] != "inverter":
            continue
        s = _load(root / n / "summary.json")
        if s is None:
            continue
        d = design_difference(root, n, "inv_f_lin_04") if (
            root / "inv_f_lin_04" / "design.vtu").exists() else None
        lines.append(f"| {n} | {s['parameters']['load']:g} | {s['model']} "
                     f"| {1e6 * s['output_displacement']:.2f} | {_g(d, '{:.3f}')} "
                     f"| {_g(strain_concentration(root / n), '{:.1f}')} "
                     f"| {_g(grey_fraction(root / n), '{:.0%}')} |")
    return "\n".join(lines)


#: force-inverter designs analysed with the Wang model at these loads [N]
CROSS_INVERTER = (["inv_f_lin_04", "inv_f_w_002", "inv_f_w_01", "inv_f_w_02", "inv_f_w_04",
                   "inv_f_w_08", "inv_f_nh_002"], (0.02, 0.4))


def cross_force(root: Path, name: str, model: str, load: float) -> dict:
    """The final design of a force-case run analysed with ``model`` at ``load``: Δ and the
    strain concentration of that state (its design.vtu is written to DIR/cross_force/...)."""
    from pacto_ng.outputs import write_vtu
    from pacto_ng.threads import compute

    run, problem = rebuilt(root / name, model=model, load=load)
    with compute():
        if problem.failure:
            return dict(ok=False, reached=problem.mech.result.load_reached)
        out = root / "cross_force" / f"{name}_{model}_{load:g}"
        out.mkdir(parents=True, exist_ok=True)
        write_vtu(out / "design", problem, run.x)
    return dict(ok=True, delta=float(problem.values["delta"]),
                concentration=strain_concentration(out))


def cross_force_markdown(root: Path, cache: Path) -> str:
    designs, loads = CROSS_INVERTER
    head = ("| design (optimised at) | " + " | ".join(
        f"Wang at {F:g} N: Δ [µm] (strain concentration)" for F in loads) + " |")
    return cached_table(
        root, cache, designs, [(f"wang|{F:g}", F) for F in loads], head,
        lambda n, F: cross_force(root, n, "wang", F),
        lambda r: f"{1e6 * r['delta']:.2f} ({_g(r['concentration'], '{:.1f}')})")


def force_cases_markdown(root: Path) -> str:
    """Cantilever: end compliance [kJ] per load, model and mesh; force inverter: output
    displacement [µm] per load and model (the runs of RUNS that exist in ``root``)."""
    def cell(name, scale, unit_fmt):
        s = _load(root / name / "summary.json")
        if s is None:
            return "not run"
        ok = valid(s, root / name)
        state = {"converged": "converged", "iterations": "iteration cap",
                 "newton": "Newton failure"}.get(s["stopped"], s["stopped"])
        val = (s["output_displacement"] if s.get("objective_name") == "output" or
               s["case"] == "inverter" else s["objective"])
        txt = "–" if val is None else unit_fmt.format(scale * val)
        return (f"{txt} ({state}, {s['iterations']} its, load {s['load_factor_reached']:.3g}, "
                f"grey {_g(grey_fraction(root / name), '{:.0%}')}, {s['wall_time_s']:.0f} s"
                f"{'' if ok else ', **not valid**'})")

    out = ["#### Cantilever: end compliance [kJ] (state, iterations, load factor reached, grey "
           "fraction, wall time)", "",
           "Wang et al.'s schedule: p 1 → 3 by 0.05 per iteration, β 4 → 64 doubling every 10 "
           "iterations, β1 = 500, η1 = 0.01 (commands in the runs table).", "",
           "| load [kN] | NH, thesis mesh | Wang, thesis mesh | NH, 120 × 30 quads | Wang, 120 × 30 "
           "quads | Wang, Wang et al.'s schedule, thesis mesh | Wang, Wang et al.'s schedule, quads |",
           "|---|---|---|---|---|---|---|"]
    for F in (80, 144, 240, 300, 500, 800):
        names = [f"cant_nh_{F}", f"cant_w_{F}", f"cant_q_nh_{F}", f"cant_q_w_{F}",
                 f"cant_w2014_w_{F}", f"cant_q_w2014_w_{F}"]
        if not any((root / n / "summary.json").exists() for n in names):
            continue
        out.append(f"| {F} | " + " | ".join(cell(n, 1e-3, "{:.2f}") if n in RUNS else "–"
                                          for n in names) + " |")
    out += ["", "#### Force inverter (thesis mesh, maxh 3e-6 m): output displacement −u_x [µm]", "",
            "| load [N] | linear | Neo-Hookean | Wang |", "|---|---|---|---|"]
    for tag, F in (("002", "0.02"), ("01", "0.1"), ("02", "0.2"), ("04", "0.4"), ("08", "0.8")):
        names = [f"inv_f_lin_{tag}", f"inv_f_nh_{tag}", f"inv_f_w_{tag}"]
        if not any((root / n / "summary.json").exists() for n in names):
            continue
        out.append(f"| {F} | " + " | ".join(cell(n, 1e6, "{:.2f}") if n in RUNS else "–"
                                          for n in names) + " |")
    return "\n".join(out)


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
            force_cases_markdown(root), "", "#### Force inverter designs", "",
            inverter_designs_markdown(root), "", "### Neo-Hookean analyses of the parts",
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
                "docs/benchmarks.md` (runs what is missing in DIR, then rewrites this block; "
                "`--cross` adds every PA design analysed at every pressure).",
                "", f"*Tables written {machine()}; the runs' wall times are of one run each, "
                "measured while other runs shared the 2 cores (2-4 processes at a time): "
                "indicative only (the timing comparisons, as medians and ratios, are the peer, "
                "trade, profile and MBB sections).*"]
        replace_block(args.doc, "benchmarks-extreme", "\n".join(body))
    return 0


if __name__ == "__main__":
    sys.exit(main())
