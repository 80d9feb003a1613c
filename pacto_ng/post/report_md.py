"""``report.md`` of ``pacto analyse`` (:func:`report_md`): the same sections for every part,
2D or 3D, a run's or as built, written from the content of ``analysis.json``
(:mod:`.report`).
"""
from __future__ import annotations

from .report import fmt_value


def report_md(d) -> str:
    """``report.md``: the same sections for every part (2D or 3D, a run's or as built): the
    part, the seal, the analyses, the gap, the warnings, the pictures."""
    L = _head(d) + _part_section(d) + _seal_section(d) + _analyses_section(d)
    L += _contact_section(d) + _gap_section(d) + _warnings_section(d) + _pictures_section(d)
    return "\n".join(L) + "\n"


def _head(d) -> list[str]:
    run = d["run"]
    unit = run["load_unit"]
    if run.get("as_built"):
        return [f"# Analysis of {run['case']} as built", "",
                f"The case's own geometry is the part: all its material (the design region "
                f"and the passive solids), its passive void regions removed; no optimisation.  "
                f"Reference load {run['load']:.4g} {unit}.", ""]
    L = [f"# Analysis of {run['case']} — {run['model']} design, optimised at "
         f"{run['load']:.4g} {unit}", "",
         f"Run folder `{run['dir']}`; design `{run['design']}` after {run['iterations']} "
         f"iterations (stopped: {run['stopped']}).  Rebuilt output displacement "
         f"Δ = {fmt_value(run['output_displacement_rebuilt'], '.6g')} m "
         f"(summary.json: {fmt_value(run['output_displacement_summary'], '.6g')} m)"
         + ("." if run.get("expected_order") is None or
            run["output_displacement_at_order"] == run["output_displacement_rebuilt"] else
            f"; at order {run['expected_order']}, the part's, on the same mesh: "
            f"{fmt_value(run['output_displacement_at_order'], '.6g')} m, the expected Δ "
            f"below."), ""]
    if run.get("order_note"):
        L += [f"**Note**: {run['order_note']}.", ""]
    if run.get("load_path_note"):
        L += [f"**Warning**: {run['load_path_note']}.", ""]
    # a 3D run's pictures: the ρ̄ = 0.5 iso-surface and the mid-depth cut (plots3d)
    L += ["| run design ρ̄ | run Darcy pressure |", "|---|---|",
          "| ![design](../design.png) | ![pressure](../pressure.png) |", ""]
    return L


def _part_section(d) -> list[str]:
    s, part, run = d["settings"], d["part"], d["run"]
    unit = part["measure_unit"]
    kind = "triangles" if run["dim"] == 2 else "tetrahedra"
    L = ["## The part", ""]
    if run.get("as_built"):
        L.append(f"The case's mesh without its void regions: {part['elements']} elements "
                 f"(maxh {fmt_value(s['maxh'])} m), measure {part['measure']:.6g} {unit}.")
    else:
        L.append(f"ρ̄ thresholded at {s['threshold']:.4g} and remeshed with Netgen {kind} of "
                 f"{s['maxh']:.4g} m ({part['elements']} elements, geometry "
                 f"{part['geometry']}).")
        ch = s.get("threshold_choice") or {}
        if ch.get("note"):
            L.append(f"The threshold: {ch['note']}.")
        m = part.get("measures", {})
        L += ["", f"| measure ({unit}) | value |", "|---|---|"]
        L += [f"| {k.replace('_', ' ')} | {fmt_value(v, '.6g')} |" for k, v in m.items()
              if isinstance(v, (int, float)) and not isinstance(v, bool)]
        L.append(f"| the design's material Σ a ρ̄ | {part['design_measure']:.6g} |")
    L += ["", f"Wetted (`pressure`) boundary: {fmt_value(part['wetted'])} "
              f"{'m' if run['dim'] == 2 else 'm²'}.  Rule: {d['definitions']['wetting']}."]
    for region, sh in (part.get("port_shifts") or {}).items():
        L.append(f"The named point `{region}` sits on the part's vertex {sh:.3g} m from its "
                 f"place on the design's mesh.")
    mats = d.get("materials")
    if mats:
        L += ["", f"**Two materials**: E2 on `stiff`, E1 on every other region "
                  f"({mats['mode']}).", "", f"| region | E (Pa) | measure ({unit}) |",
              "|---|---|---|"]
        L += [f"| {k} | {mats['E'].get(k, float('nan')):g} | {v:.6g} |"
              for k, v in mats["remeshed"].items()]
        if run["dim"] == 2:
            L += ["", "![materials](materials.png)"]
    ports = s["output_ports"]
    L += ["", f"Supports on the part: {s['supports']}.  Output Δ = Σ w·d·u over "
              f"{len(ports)} port(s): " + "; ".join(
                  f"`{q['region']}` d = {q['direction']}, w = {q['weight']:g}, spring "
                  f"{q['spring']:g} N/m" for q in ports) + ".", ""]
    return L


def _seal_section(d) -> list[str]:
    seal = d.get("seal")
    L = ["## The seal", ""]
    if seal is None:
        return L + ["No pressure chamber (no pressure load).", ""]
    what = ("the case's geometry: the void behind the inlet walls" if d["run"].get("as_built")
            else f"the thresholded design (threshold {seal['threshold']:g})")
    if not seal["chambers"]:
        L.append(f"Checked on {what}: no void lies behind the inlet (it is on the part's "
                 f"outer boundary, the fluid beyond it): no chamber to close.")
    for c in seal["chambers"]:
        state = "sealed: closed off from every zero-pressure boundary" if c["sealed"] else (
            f"**open** to `{c['boundary']}` near ("
            + ", ".join(f"{v:.4g}" for v in c["opening"]) + ") m")
        L.append(f"Checked on {what}: chamber `{c['name']}` is {state}.")
    return L + [""]


def _analyses_section(d) -> list[str]:
    s, kinds = d["settings"], d["settings"]["kinds"]
    E = s["E"]
    E_text = f"{E:g} Pa" if not isinstance(E, dict) else ", ".join(
        f"{v:g} Pa ({k})" for k, v in E.items())
    L = ["## The analyses", "",
         f"Model `{s['model']}`" + (f", material `{s['material']}`" if s["material"] else "")
         + f", E = {E_text}, ν = {s['nu']:g}"
         + (f", t = {s['thickness']:g} m ({s['plane']})" if s["thickness"] else "")
         + f"; displacement order {s['order']}, formulation {s['formulation']}.", "",
         f"* **output** — {d['definitions']['output']};"]
    if not d["run"].get("as_built"):
        L.append(f"* **expected** — {d['definitions']['expected']};")
    L += [f"* **{k}** — {d['definitions'][k]};" for k in kinds]
    ref = "follower" if "follower" in kinds else kinds[-1]
    L += ["", "![analysis](analysis.png)", "",
          "| P | expected Δ (m) | " + " | ".join(f"Δ {k} (m)" for k in kinds)
          + " | max \\|u\\| (m) | min J | Newton its |", "|" + "---|" * (5 + len(kinds))]
    for r in d["pressures"]:
        its = "/".join(str(r[k]["newton_iterations"]) for k in kinds)
        L.append(f"| {r['pressure']:.4g} | {fmt_value(r['expected'])} | "
                 + " | ".join(fmt_value(r[k]["delta"]) for k in kinds)
                 + f" | {fmt_value(r[ref]['max_u'])} | {fmt_value(r[ref]['min_J'])} | {its} |")
    L += ["", f"P in {d['run']['load_unit']}; max |u| and min J of the {ref} analysis; Newton "
              f"iterations {'/'.join(kinds)}; — : not converged.", ""]
    for k, peak in (d.get("pressure_maximum") or {}).items():
        if peak:
            past = [f"{r['pressure']:.4g}" for r in d["pressures"] if r[k].get("past_peak")]
            L += [f"**A pressure maximum** ({k}): {peak['pressure']:.5g} "
                  f"{d['run']['load_unit']} at Δ = {peak['delta']:.5g} m; "
                  + (f"reached past it: {', '.join(past)}." if past else
                     "no equilibrium at the larger pressures asked.")
                  + f"  {d['definitions']['pressure_maximum']}.", ""]
    regions = [q["region"] for q in s["output_ports"]]
    if len(regions) > 1:
        cols = [(k, r) for k in kinds for r in regions]
        L += ["Every port's own displacement d·u (m), Δ = Σ w·d·u:", "",
              "| P | " + " | ".join(f"{k} `{r}`" for k, r in cols) + " |",
              "|" + "---|" * (1 + len(cols))]
        L += [f"| {row['pressure']:.4g} | " + " | ".join(
            fmt_value(row[k]["ports"][r]) for k, r in cols) + " |" for row in d["pressures"]]
        L.append("")
    return L


def _contact_section(d) -> list[str]:
    """``--contact``: per pressure and kind where the walls touch, the force between them and
    the largest contact pressure; per kind the first swept pressure with contact."""
    if not d["settings"].get("contact"):
        return []
    kinds, unit = d["settings"]["kinds"], d["run"]["load_unit"]
    L = ["### Walls in contact", "", f"{d['definitions']['contact']}.", "",
         "| P | kind | contact area (m²) | force (N) | largest contact pressure (Pa) | "
         "force / area (Pa) |", "|---|---|---|---|---|---|"]
    for r in d["pressures"]:
        for k in kinds:
            c = r[k]["contact"] or {}
            area, force = c.get("area"), c.get("force")
            mean = force / area if area and force is not None else None
            L.append(f"| {r['pressure']:.4g} | {k} | {fmt_value(area)} | {fmt_value(force)} | "
                     f"{fmt_value(c.get('pressure'))} | {fmt_value(mean)} |")
    L.append("")
    for k, first in (d.get("first_contact") or {}).items():
        if first is None:
            continue
        if first["pressure"] is None:
            L.append(f"* {k}: the walls touch at no swept pressure"
                     + ("." if first["last_without"] is None else
                        f" (up to {first['last_without']:.4g} {unit})."))
            continue
        before = ("the sweep's first pressure: they may touch below it" if
                  first["last_without"] is None else
                  f"not at {first['last_without']:.4g} {unit}, the pressure before it: "
                  f"contact began between the two")
        L.append(f"* {k}: **first contact at {first['pressure']:.4g} {unit}**, the first "
                 f"swept pressure at which the walls touch (a swept pressure, not "
                 f"interpolated; {before}).")
    return L + [""]


def _gap_section(d) -> list[str]:
    L = ["## The gap", ""]
    if d["gap_at_largest_pressure"] is None:
        return L + ["No expected Δ: a part as built has no optimisation to compare with.", ""]

    def pct(gaps):
        return ", ".join(f"{k} {fmt_value(None if g is None else 100 * g, '+.1f')} %"
                         for k, g in gaps.items())

    P = [r["pressure"] for r in d["pressures"]]
    return L + [f"(analysed − expected)/|expected|: at {P[-1]:.4g} "
                f"{pct(d['gap_at_largest_pressure'])}; at {P[0]:.4g} "
                f"{pct(d['gap_at_smallest_pressure'])} (at a small pressure the gap is what "
                f"thresholding and remeshing change; its growth with the pressure is the "
                f"nonlinearity the optimisation's model missed).", ""] + _parts_table(d)


def _parts_table(d) -> list[str]:
    """Where the gap at the largest pressure comes from (analysis.json's ``gap_parts``)."""
    parts = d.get("gap_parts")
    if not parts:
        return []
    L = [f"Where it comes from, at {d['pressures'][-1]['pressure']:.4g} (in % of the expected "
         f"Δ; the steps add up to the gap):", "",
         "| kind | threshold (rounded on the design mesh) | remesh (body-fitted, same Darcy "
         "load) | wall pressure (instead of the Darcy body force) | total |", "|---|---|---|---|---|"]
    for k, g in parts.items():
        L.append(f"| {k} | " + " | ".join(f"{100 * g[s]:+.1f}" for s in
                                          ("threshold", "remesh", "wall_pressure", "total"))
                 + " |")
    return L + [""]


def _warnings_section(d) -> list[str]:
    L = ["## Warnings", ""]
    if not d["warnings"]:
        return L + ["None.", ""]
    return L + [f"* {w}" for w in d["warnings"]] + [""]


def _pictures_section(d) -> list[str]:
    ds = d["deformed_state"]
    L = ["## Pictures", ""]
    if ds["kind"] is not None:
        L += [f"The {ds['kind']} analysis at {ds['pressure']:.4g} {d['run']['load_unit']}, "
              f"true scale, over the undeformed part"
              + (" (red: the walls' vertices in contact)" if d["settings"].get("contact")
                 else "") + ":", "", "![deformed](deformed.png)", ""]
    L += ["Files: `analysis.json` (every number above), `analysis.csv`, `part.stl` (the part, "
          "closed and whole, in mm), `remeshed.vtu` / `deformed.vtu` (u, J, stress, von_mises"
          + (", p" if d["run"].get("as_built") is False else "") + "; reference / deformed "
          "configuration), `analysis.png`, `deformed.png`.", ""]
    return L
