"""What ``pacto analyse`` writes about a part, in one layout for 2D and 3D, for a run's part
and for a case as built: ``analysis.json`` (:func:`analysis_json`), ``analysis.csv``
(:func:`analysis_csv`) and ``report.md`` (:func:`report_md`).

``analysis.json``:

=============================  ==============================================================
``run``                        the run (case, model, load, design used, Δ from summary.json and
                               rebuilt, and at the part's order: ``expected_order``,
                               ``output_displacement_at_order``) or, ``as_built``, the case
                               and its parameters' source
``settings``                   the analysis: model, material preset, E (per region), ν, t,
                               plane, order, formulation, kinds, pressures, the threshold used
                               and its choice, threshold2, maxh, supports, output ports
``part``                       :meth:`~.part.Part.summary`, the part's measures (thresholded,
                               kept, remeshed), and every named point's source and new position
                               with its shift (``port_shifts``, ``output_port_shift``)
``seal``                       the chambers (:class:`~.seal.Seal`): of the thresholded design,
                               or of the case's geometry as built
``materials``                  a part with a ``stiff`` region: each region's modulus and measure
``pressures``                  per pressure: ``expected`` Δ (None as built), ``rounded`` Δ
                               (the part's solid rounded onto the design mesh) and per kind ``delta``,
                               every port's ``d·u`` (``ports``) and displacement vector
                               (``vectors``), ``max_u``, ``min_J``, ``newton_iterations``,
                               ``converged``, ``load_reached``
``gap_at_largest_pressure``,   per kind (analysed − expected)/|expected| (None as built)
``gap_at_smallest_pressure``
``gap_parts``                  per wall-pressure kind, at the largest pressure, the gap taken
                               apart (:func:`gap_parts`): ``threshold`` + ``remesh`` +
                               ``wall_pressure`` = ``total`` (None as built, for two
                               materials, or without the ``darcy`` kind)
``deformed_state``             the kind and pressure shown in the pictures and VTUs
``warnings``                   what a user must know beyond the figures
``definitions``, ``wall_time_s``
=============================  ==============================================================
"""
from __future__ import annotations

import csv
import io
import math

import numpy as np

from .materials import interface_length, material_areas
from .part3d import closed_checks
from .post3d import material_volumes

#: the definitions written into analysis.json and report.md
DEFINITIONS = {
    "output": "Delta = sum_k w_k d_k . u over the output ports (the value at a named point, "
              "the mean over a named edge or face), each port against its output spring, as "
              "the optimisation defines it; 'ports' holds every port's own d_k . u, 'vectors' "
              "its displacement vector",
    "expected": "the optimised density design (final x, last penalty and beta) re-analysed "
                "with the optimisation's own model, Darcy load and output spring at inlet "
                "pressure P (load factor P/load, warm-started along the sweep), on the run's "
                "mesh at the part's displacement order (run: expected_order); for a linear "
                "model its output displacement at the run's load scaled linearly with P",
    "darcy": "the Darcy pressure of the thresholded design (element rho = 1 where at least "
             "half of the element lies inside the thresholded solid, else 0; the run's Darcy "
             "parameters, P_in = the run's load) as the deformation-independent body force "
             "-grad p on the part, scaled with P/P_in",
    "fixed": "pressure P on the wetted boundary 'pressure', deformation independent",
    "follower": "pressure P on the wetted boundary 'pressure', following the deformation "
                "(cof(F) N0 = J F^-T N0)",
    "wetting": "a boundary of the part is wetted where it lies on the inlet, or inside the "
               "domain where the run's final Darcy pressure one source element size outside "
               "it is at least 0.5 P_in",
    "wetting_as_built": "the set-up's inlet boundaries (the chamber walls, or an outer edge "
                        "with the fluid beyond it) are the wetted boundary",
    "gap": "(analysed - expected) / |expected|, at the largest and at the smallest pressure "
           "(there: the effect of thresholding and remeshing alone)",
    "rounded": "the part's solid rounded onto the design mesh (element rho = 1 where at least "
               "half of the element lies inside the thresholded solid, else 0) analysed as "
               "'expected' is, with its own Darcy pressure",
    "gap_parts": "the gap of each wall-pressure kind taken apart, in units of |expected|: "
                 "threshold = (rounded - expected), the grey layer and the threshold level on "
                 "the design mesh; remesh = (darcy - rounded), the body-fitted smoothed "
                 "boundary and the part's mesh under the same Darcy load; wall_pressure = "
                 "(kind - darcy), the pressure on the wetted walls instead of the Darcy body "
                 "force; they add up to total = (kind - expected)",
}


def gap_parts(row, kinds) -> dict | None:
    """The gap of each wall-pressure kind at one pressure ``row`` taken apart (the
    ``gap_parts`` definition); None without the rounded design's or the darcy kind's Δ."""
    e, r = row.get("expected"), row.get("rounded")
    d = (row.get("darcy") or {}).get("delta")
    if e in (None, 0.0) or r is None or d is None:
        return None
    out = {}
    for k in kinds:
        a = row[k]["delta"] if k in ("fixed", "follower") else None
        if a is not None:
            out[k] = {"threshold": (r - e) / abs(e), "remesh": (d - r) / abs(e),
                      "wall_pressure": (a - d) / abs(e), "total": (a - e) / abs(e)}
    return out or None


def num(v):
    """A finite float, else None (JSON)."""
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def fmt_value(v, spec=".4g"):
    return "—" if v is None else format(v, spec)


def ports_json(ports) -> list[dict]:
    """The output ports as JSON: region, direction, spring (N/m) and weight of each."""
    return [{"region": p.region, "direction": list(map(float, p.direction)),
             "spring": float(p.spring), "weight": float(p.weight)} for p in ports]


def _point(pt, ports) -> dict:
    return {"delta": num(pt.delta),
            "ports": {q.region: num(v) for q, v in zip(ports, pt.ports)},
            "vectors": {q.region: [num(c) for c in vec] for q, vec in zip(ports, pt.vectors)},
            "max_u": num(pt.max_u), "min_J": num(pt.min_j),
            "newton_iterations": int(pt.iterations), "converged": bool(pt.converged),
            "load_reached": num(pt.load_reached)}


def _gaps(row, kinds) -> dict:
    e = row["expected"]
    return {k: None if e in (None, 0.0) or row[k]["delta"] is None else
            (row[k]["delta"] - e) / abs(e) for k in kinds}


def analysis_json(*, run: dict, settings: dict, part: dict, seal, materials, sweeps: dict,
                  ports, expected, deformed: dict, warnings: list, wall: float) -> dict:
    """The content of ``analysis.json`` (the module's table).  ``sweeps``: kind ->
    :class:`~.part_analysis.Sweep` over ``settings["pressures"]``; ``expected``: the rows of
    :func:`~.analyse.expected_sweep`, or None (a part as built)."""
    kinds = list(sweeps)
    rows = []
    for i, P in enumerate(settings["pressures"]):
        ex = expected[i] if expected else {}
        row = {"pressure": float(P), "expected": num(ex.get("delta")),
               "rounded": num(ex.get("rounded")),
               "expected_converged": ex.get("converged"),
               "expected_newton_iterations": ex.get("newton_iterations")}
        row.update({k: _point(sweeps[k].points[i], ports) for k in kinds})
        rows.append(row)
    built = bool(run.get("as_built"))
    definitions = {k: v for k, v in DEFINITIONS.items()
                   if k not in (("expected", "darcy", "gap", "wetting", "rounded", "gap_parts")
                                if built
                                else ("wetting_as_built",))}
    if built:
        definitions["wetting"] = definitions.pop("wetting_as_built")
    return {"run": run, "settings": dict(settings, kinds=kinds), "part": part, "seal": seal,
            "materials": materials, "definitions": definitions, "pressures": rows,
            "gap_at_largest_pressure": _gaps(rows[-1], kinds) if expected else None,
            "gap_at_smallest_pressure": _gaps(rows[0], kinds) if expected else None,
            "gap_parts": gap_parts(rows[-1], kinds) if expected else None,
            "deformed_state": deformed, "warnings": list(warnings), "wall_time_s": wall}


def analysis_csv(data: dict) -> str:
    """``analysis.csv``: one row per (kind, pressure): Δ, the expected Δ, every port's d·u
    (``port_REGION``) and displacement vector (``u_REGION_x`` ...), max |u|, min J, Newton
    iterations, converged."""
    rows = []
    for kind in data["settings"]["kinds"]:
        for r in data["pressures"]:
            pt = r[kind]
            row = {"kind": kind, "pressure": r["pressure"], "delta": pt["delta"],
                   "expected": r["expected"]}
            row.update({f"port_{k}": v for k, v in pt["ports"].items()})
            for k, vec in pt["vectors"].items():
                row.update({f"u_{k}_{a}": c for a, c in zip("xyz", vec)})
            row.update({k: pt[k] for k in ("max_u", "min_J", "newton_iterations", "converged",
                                           "load_reached")})
            rows.append(row)
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    return buf.getvalue()


def short_table(data) -> str:
    """The sweep as printed at the end of ``pacto analyse``."""
    kinds = data["settings"]["kinds"]
    lines = ["  P            expected    " + "".join(f"{k:12s}" for k in kinds)]
    for r in data["pressures"]:
        lines.append(f"  {r['pressure']:<11.4g} {fmt_value(r['expected']):11s} " + "".join(
            f"{fmt_value(r[k]['delta']):12s}" for k in kinds))
    return "\n".join(lines)


# -- report.md ----------------------------------------------------------------------------
def report_md(d) -> str:
    """``report.md``: the same sections for every part (2D or 3D, a run's or as built): the
    part, the seal, the analyses, the gap, the warnings, the pictures."""
    L = _head(d) + _part_section(d) + _seal_section(d) + _analyses_section(d)
    L += _gap_section(d) + _warnings_section(d) + _pictures_section(d)
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
    if run["dim"] == 2:
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
              f"true scale, over the undeformed part:", "", "![deformed](deformed.png)", ""]
    L += ["Files: `analysis.json` (every number above), `analysis.csv`, `part.stl` (the part, "
          "closed and whole, in mm), `remeshed.vtu` / `deformed.vtu` (u, J, stress, von_mises"
          + (", p" if d["run"].get("as_built") is False else "") + "; reference / deformed "
          "configuration), `analysis.png`, `deformed.png`.", ""]
    return L


def jsonable(value):
    """Tuples as lists, numpy numbers as Python numbers, recursively (for analysis.json)."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


# -- the part's entries ---------------------------------------------------------------------
def part_measures(part) -> dict:
    """The measures of a run's part (m² in 2D, m³ in 3D): thresholded, kept on the clamp,
    remeshed, and what was dropped on the way."""
    a, b = part.pieces
    if part.dim == 2:
        kept = a.polygon_area - b.dropped_area
        out = dict(thresholded=a.area, polygons=a.polygon_area, removed_specks=a.removed_area,
                   dropped_floating=b.dropped_area, kept=kept, remeshed=b.area)
    else:
        kept = a.volume_kept
        out = dict(thresholded=a.volume_thresholded, kept=kept, surface=a.volume,
                   remeshed=b.volume, pieces=a.pieces, dropped_pieces=a.dropped,
                   dropped_tetrahedra=b.dropped, **closed_checks(a.surface))
    out["remeshed_vs_kept"] = out["remeshed"] / kept - 1.0 if kept else None
    return out


def materials_entry(part, E, threshold2) -> dict | None:
    """analysis.json's ``materials`` for a part with a ``stiff`` region (else None): how the
    regions were made, threshold2, each region's modulus and measure (3D two-material runs:
    also in the clipped solid, ``part``; 2D: the interface's length)."""
    if not isinstance(E, dict):
        return None
    measures = {k: v for k, v in material_areas(part.mesh).items() if k in E}
    out = {"mode": part.materials or "as built", "threshold2": threshold2, "E": E,
           "remeshed": measures, "part": None, "interface_length": None}
    if part.dim == 3 and part.pieces[0] is not None and "material" in getattr(
            part.pieces[0].solid, "cell_data", {}):
        out["part"] = material_volumes(part.pieces[0].solid)
    if part.dim == 2:
        out["interface_length"] = interface_length(part.mesh)
    return out


def part_warnings(part, ports, sweeps, shown, h: float, unit: str) -> list[str]:
    """What a user must know of the part beyond its figures: an output point the part does
    not reach (its vertex more than two design elements ``h`` away), a sweep that stopped, a
    port that moves more across its direction than along it (in the ``shown`` kind's last
    converged state)."""
    out = []
    regions = {p.region for p in ports}
    for region, (src, new) in part.ports.items():
        shift = float(np.linalg.norm(np.subtract(new, src)))
        if region in regions and shift > 2.0 * h:
            out.append(f"the part does not reach the output point '{region}': its nearest "
                       f"vertex is {shift:.3g} m away (the output ends in void)")
    for kind, sw in sweeps.items():
        bad = [p for p in sw.points if not p.converged]
        if bad:
            above = "" if len(bad) == 1 else " nor above"
            out.append(f"the {kind} analysis did not converge at {bad[0].pressure:.4g} "
                       f"{unit} (equilibrium up to {100 * bad[0].load_reached:.3g} % of "
                       f"it){above}")
    if shown is not None:
        pt = sweeps[shown].points[int(np.flatnonzero(sweeps[shown].converged)[-1])]
        for port, vec in zip(ports, pt.vectors):
            d = np.asarray(port.direction, dtype=float) / np.linalg.norm(port.direction)
            v = np.asarray(vec, dtype=float)
            along = float(v @ d)
            across = float(np.linalg.norm(v - along * d))
            if across > abs(along):
                out.append(f"the output '{port.region}' moves more across its direction "
                           f"({across:.3g} m) than along it ({along:.3g} m) in the {shown} "
                           f"analysis at {pt.pressure:.4g} {unit}: the "
                           f"objective leaves that motion free")
    return out


def boundary_measures(mesh) -> dict:
    """The length (2D) or area (3D) of every named boundary of ``mesh``."""
    import ngsolve

    return {name: float(ngsolve.Integrate(1.0, mesh, ngsolve.BND,
                                          definedon=mesh.Boundaries(name)))
            for name in sorted(set(mesh.GetBoundaries()))}


def part_entry(part, ports, measures: dict) -> dict:
    """analysis.json's ``part``: :meth:`~.part.Part.summary`, its ``measures`` and its named
    points (source position, the part's vertex, the shift between them)."""
    entry = dict(part.summary(), measures=dict(measures), boundaries=boundary_measures(part.mesh))
    regions = {p.region for p in ports}
    entry["points"] = {k: {"source": list(map(float, a)), "new": list(map(float, b)),
                           "shift": float(np.linalg.norm(np.subtract(b, a)))}
                       for k, (a, b) in part.ports.items()}
    shifts = {k: v["shift"] for k, v in entry["points"].items() if k in regions}
    entry["port_shifts"] = shifts
    entry["output_port_shift"] = max(shifts.values()) if shifts else None
    return jsonable(entry)
