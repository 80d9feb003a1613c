"""The tables of the extreme-load study (:mod:`benchmarks.extreme`), read from its run folders:
every run's outcome (its command, stopping reason, objective, validity, grey fraction,
leakage), the force cases by load and model, the force inverter's designs and the Neo-Hookean
analyses of the pressure cases' parts.
"""
from __future__ import annotations

import json
from pathlib import Path


def read_json(path: Path):
    """The JSON file ``path`` read, or None if it does not exist."""
    return json.loads(path.read_text()) if path.exists() else None


def number(x, fmt="{:.4g}"):
    """``x`` formatted with ``fmt`` for a table cell; "–" for None."""
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
        s = read_json(root / n / "summary.json")
        if s is None:
            continue
        hist = s.get("objective_history") or [None]
        d = s.get("output_displacement")
        lines.append(
            f"| {n} | `{command_of(root / n)}` | {s['stopped']} | {s['iterations']} "
            f"| {number(s.get('load_factor_reached'))} | {number(hist[0])} → "
            f"{number(first_full_load_objective(root / n))} → {number(s['objective'])} "
            f"| {number(None if d is None else 1e3 * d)} | {s['volume_fraction']:.4f} "
            f"| {number(grey_fraction(root / n), '{:.1%}')} "
            f"| {number(s.get('leakage'), '{:.2%}')} | {s['newton_iterations_total']} "
            f"| {s['wall_time_s']:.0f} | {'yes' if valid(s, root / n) else '**no**'} |")
    return "\n".join(lines)


def analyses_markdown(root: Path, names) -> str:
    lines = ["| design | threshold | P [Pa] | expected Δ [mm] | Darcy Δ [mm] | fixed Δ [mm] "
             "| follower Δ [mm] | min J (follower) | remeshed vs thresholded area | output port moved [m] |",
             "|" + "---|" * 10]
    for n in names:
        a = read_json(root / n / "analysis" / "analysis.json")
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
                         f"{number(None if e is None else 1e3 * e)} | " + " | ".join(cells)
                         + f" | {number(fj, '{:.3f}')} | "
                         f"{number(a['areas']['remeshed_vs_kept'], '{:+.2%}')} | "
                         f"{number(a['remesh']['output_port_shift'], '{:.2g}')} |")
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



def design_difference(root: Path, a: str, b: str):
    """‖ρ̄_a − ρ̄_b‖ / ‖ρ̄_b‖ over the elements (same case and mesh), from design.vtu."""
    import meshio
    import numpy as np

    ra, rb = (np.asarray(meshio.read(root / n / "design.vtu").point_data["rho_bar"])
              for n in (a, b))
    if ra.shape != rb.shape:
        return None
    return float(np.linalg.norm(ra - rb) / np.linalg.norm(rb))


def inverter_designs_markdown(root: Path, runs: dict) -> str:
    """Force inverter designs: output displacement of each run of ``runs`` (name -> (case,
    arguments)), its design's difference from the linear design and its strain concentration
    (lumped vs distributed hinges)."""
    lines = ["| run | load [N] | model | Δ [µm] | ‖ρ̄ − ρ̄_linear‖ / ‖ρ̄_linear‖ | strain "
             "concentration (99th pct / median ‖E‖ in solid) | grey |", "|---|---|---|---|---|---|---|"]
    for n in runs:
        if runs[n][0] != "inverter":
            continue
        s = read_json(root / n / "summary.json")
        if s is None:
            continue
        d = design_difference(root, n, "inv_f_lin_04") if (
            root / "inv_f_lin_04" / "design.vtu").exists() else None
        lines.append(f"| {n} | {s['parameters']['load']:g} | {s['model']} "
                     f"| {1e6 * s['output_displacement']:.2f} | {number(d, '{:.3f}')} "
                     f"| {number(strain_concentration(root / n), '{:.1f}')} "
                     f"| {number(grey_fraction(root / n), '{:.0%}')} |")
    return "\n".join(lines)



def force_cases_markdown(root: Path, runs: dict) -> str:
    """Cantilever: end compliance [kJ] per load, model and mesh; force inverter: output
    displacement [µm] per load and model (the runs of ``runs`` that exist in ``root``)."""
    def cell(name, scale, unit_fmt):
        s = read_json(root / name / "summary.json")
        if s is None:
            return "not run"
        ok = valid(s, root / name)
        state = {"converged": "converged", "iterations": "iteration cap",
                 "newton": "Newton failure"}.get(s["stopped"], s["stopped"])
        val = (s["output_displacement"] if s.get("objective_name") == "output" or
               s["case"] == "inverter" else s["objective"])
        txt = "–" if val is None else unit_fmt.format(scale * val)
        return (f"{txt} ({state}, {s['iterations']} its, load {s['load_factor_reached']:.3g}, "
                f"grey {number(grey_fraction(root / name), '{:.0%}')}, {s['wall_time_s']:.0f} s"
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
        out.append(f"| {F} | " + " | ".join(cell(n, 1e-3, "{:.2f}") if n in runs else "–"
                                          for n in names) + " |")
    out += ["", "#### Force inverter (thesis mesh, maxh 3e-6 m): output displacement −u_x [µm]", "",
            "| load [N] | linear | Neo-Hookean | Wang |", "|---|---|---|---|"]
    for tag, F in (("002", "0.02"), ("01", "0.1"), ("02", "0.2"), ("04", "0.4"), ("08", "0.8")):
        names = [f"inv_f_lin_{tag}", f"inv_f_nh_{tag}", f"inv_f_w_{tag}"]
        if not any((root / n / "summary.json").exists() for n in names):
            continue
        out.append(f"| {F} | " + " | ".join(cell(n, 1e6, "{:.2f}") if n in runs else "–"
                                          for n in names) + " |")
    return "\n".join(out)
