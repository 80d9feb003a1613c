"""The cross analyses of the extreme-load study (:mod:`benchmarks.extreme`): the final design of
a run analysed again with another model, load or load type (its density field, the run's last
penalty and β), as markdown tables whose results are cached in a JSON file of the runs folder.
"""
from __future__ import annotations

import json
from pathlib import Path

from benchmarks.extreme_tables import number, strain_concentration


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
        lambda r: f"{1e6 * r['delta']:.2f} ({number(r['concentration'], '{:.1f}')})")
