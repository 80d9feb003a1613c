"""One call for the whole post-analysis of a density field (docs/theory.md §7), writing its files.

:func:`post_analyse` chains :func:`~.threshold.threshold`, :func:`~.remesh.remesh`, the
sweeps of :mod:`.reanalysis` and the writers of :mod:`.export`, and writes into ``out_dir``:

=================  ====================================================================
``design.stl``     the thresholded, remeshed solid extruded by the thickness (watertight)
``remeshed.vtu``   the remeshed solid with ``u``, ``J``, ``stress``, ``von_mises``
``deformed.vtu``   the same in the deformed configuration
``deformed.png``   deformed solid over the undeformed outline, true scale (the whole part:
                   mirrored about a straight ``symmetry`` boundary of the source mesh)
``analysis.png``   Δ against pressure: expected, and every analysis kind
``analysis.csv``   one row per (kind, pressure): Δ, every port's d·u, max |u|, min J,
                   iterations, converged
``post.json``      threshold, areas, wetted length, ports, parameters and the sweeps
=================  ====================================================================

The deformed state is the last converged pressure of the ``follower`` sweep (else of the first
kind that converged somewhere).
"""
from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..files import atomic_write_text
from ..physics.loads import Port
from ..physics.mechanics import Supports
from ..physics.newton import DIRECT_RTOL, NewtonSettings
from .export import plot_deformed, plot_materials, plot_sweeps, write_stl, write_vtu
from .materials import interface_length, material_areas
from .plots import mirror_line
from .reanalysis import Reanalysis, output_ports, pressure_body_force
from .remesh import remesh
from .threshold import threshold


@dataclass
class PostResult:
    """What :func:`post_analyse` computed and wrote."""

    thresholded: object
    remeshed: object
    sweeps: dict
    files: dict = field(default_factory=dict)
    summary: dict = field(default_factory=dict)


def post_analyse(mesh, rho, out_dir, *, pressures, E: float, nu: float, thickness: float,
                 output: Port | tuple[Port, ...], clamp=("fixed",),
                 supports: Supports | None = None,
                 threshold_value: float = 0.5, thresholded=None,
                 maxh: float | None = None, pressure=None,
                 p_in: float | None = None, wet_fraction: float = 0.5,
                 wet_boundaries=("inlet",), kinds=("fixed", "follower"), darcy_pressure=None,
                 darcy_p_in: float | None = None, expected=None, order: int = 2,
                 newton: NewtonSettings = NewtonSettings(), domain=None, exclude=(),
                 mirror=True, stiff=None) -> PostResult:
    """Threshold, remesh, re-analyse and export a design.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The optimisation mesh.
    rho : array_like
        Element densities ρ̄ (NGSolve element order).
    out_dir : str or Path
        Created if missing.
    pressures : sequence of float
        The sweep, increasing (Pa).
    E : float or dict
        Young's modulus of the Neo-Hookean solid; ``{"soft": E1, "stiff": E2}`` with
        ``stiff``.
    nu, thickness : float
        Poisson's ratio and out-of-plane thickness.
    output : Port or tuple of Port
        The output port(s): Δ = Σ weight · direction · u at named points, each port with its
        spring (:class:`~.reanalysis.Reanalysis`).
    clamp : sequence of str
        Clamp boundaries (pieces not touching them are dropped).
    supports : Supports, optional
        Default ``Supports(clamp=clamp)``; add e.g. ``fix_y=("symmetry",)``.
    threshold_value : float
        Density threshold in (0, 1).
    thresholded : Thresholded, optional
        :func:`~.threshold.threshold` of ``mesh, rho`` at ``threshold_value``, if the caller has
        it already (else computed here).
    maxh : float, optional
        Element size of the new mesh, default the optimisation mesh's.
    pressure, p_in, wet_fraction, wet_boundaries
        The wetting rule of :func:`~.remesh.remesh`.
    kinds : sequence of {"fixed", "follower", "darcy"}
    darcy_pressure : GridFunction or CF on ``mesh``, optional
        The Darcy pressure for the ``darcy`` kind, at inlet pressure ``darcy_p_in``.
    expected : tuple ``(pressures, deltas)``, optional
        What the optimisation predicted, for the plot and the summary.
    order : int
        Displacement order of the re-analysis.
    newton : NewtonSettings
    domain : netgen.occ shape, optional
        The geometry ``mesh`` was made from: the part keeps its edges (see
        :func:`~.remesh.remesh`).
    exclude : iterable of str
        Passive void materials left out of the thresholding (see
        :func:`~.threshold.threshold`; with ``domain``, the case's void faces).
    mirror : bool
        ``deformed.png`` shows the whole part of a case solved on a symmetric half (mirrored
        about ``mesh``'s straight ``symmetry`` boundary).  The files are of the half.
    stiff : :class:`~.materials.StiffRegion`, optional
        Two materials: ρ̄2 thresholded on ``mesh``; the part is remeshed with regions ``soft``
        and ``stiff`` (:func:`~.remesh.remesh`), analysed with ``E[material]`` and drawn in
        ``materials.png``.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    th = thresholded
    if th is None or th.threshold != threshold_value:
        th = threshold(mesh, rho, threshold_value, exclude=exclude)
    rm = remesh(th, th.h if maxh is None else maxh, clamp=clamp, pressure=pressure, p_in=p_in,
                wet_fraction=wet_fraction, wet_boundaries=wet_boundaries, domain=domain,
                stiff=stiff)
    supports = Supports(clamp=tuple(clamp)) if supports is None else supports
    supports = _present(supports, rm.mesh)
    kw = dict(E=E, nu=nu, thickness=thickness, supports=supports, output=output, order=order,
              newton=newton)
    sweeps = {}
    for kind in kinds:
        extra = {}
        if kind == "darcy":
            if darcy_pressure is None or darcy_p_in is None:
                raise ValueError("the darcy kind needs darcy_pressure and darcy_p_in")
            extra = dict(body=pressure_body_force(darcy_pressure), body_pressure=darcy_p_in)
        sweeps[kind] = Reanalysis(rm.mesh, kind, **kw, **extra).sweep(pressures)

    files = {"stl": out / "design.stl", "remeshed": out / "remeshed.vtu",
             "deformed": out / "deformed.vtu", "deformed_png": out / "deformed.png",
             "analysis_png": out / "analysis.png", "csv": out / "analysis.csv",
             "json": out / "post.json"}
    write_stl(files["stl"], rm.mesh, thickness)
    order_ = [k for k in ("follower",) + tuple(kinds) if k in sweeps]
    shown = next((k for k in order_ if sweeps[k].converged.any()), None)
    if shown is not None:
        u = sweeps[shown].displacement()
        i = int(np.flatnonzero(sweeps[shown].converged)[-1])
        write_vtu(files["remeshed"], rm.mesh, u, E=E, nu=nu)
        write_vtu(files["deformed"], rm.mesh, u, E=E, nu=nu, deformed=True)
        plot_deformed(files["deformed_png"], rm.mesh, u,
                      title=f"{shown} pressure {sweeps[shown].pressures[i]:.3g} Pa (true scale)",
                      mirror=mirror_line(mesh, mirror) or False)
    else:
        write_vtu(files["remeshed"], rm.mesh)
        for k in ("deformed", "deformed_png"):
            files.pop(k)
    if stiff is not None:
        files["materials_png"] = out / "materials.png"
        plot_materials(files["materials_png"], rm.mesh, mirror=mirror_line(mesh, mirror) or False,
                       title=f"the part's materials (ρ̄2 thresholded at {stiff.threshold:g})")
    plot_sweeps(files["analysis_png"], sweeps, expected=expected)
    rows = [row for sw in sweeps.values() for row in sw.table()]
    buf = io.StringIO(newline="")
    writer = csv.DictWriter(buf, fieldnames=list(rows[0]))
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(files["csv"], buf.getvalue())
    summary = {
        "threshold": th.threshold, "thresholded_area": th.area,
        "polygon_area": th.polygon_area, "removed_speck_area": th.removed_area,
        "remeshed_area": rm.area, "dropped_floating_area": rm.dropped_area,
        "wetted_length": rm.wetted_length, "p_in": rm.p_in,
        "ports": {k: {"source": list(map(float, a)), "new": list(map(float, b))}
                  for k, (a, b) in rm.ports.items()},
        "materials": None if stiff is None else {
            "threshold2": stiff.threshold, "mode": rm.materials,
            "areas": material_areas(rm.mesh), "interface_length": interface_length(rm.mesh)},
        "elements": rm.mesh.ne, "geometry": rm.geometry, "order": order,
        "formulation": sorted({sw.analysis.formulation for sw in sweeps.values()}),
        "E": E, "nu": nu, "thickness": thickness,
        "supports": dataclasses.asdict(supports),
        "wet_boundaries": list(wet_boundaries),
        "output_ports": ports_json(output_ports(output)),
        "deformed_state": shown,
        "expected": None if expected is None else [list(map(float, a)) for a in expected],
        "sweeps": {k: [_jsonable(r) for r in sw.table()] for k, sw in sweeps.items()},
    }
    atomic_write_text(files["json"], json.dumps(summary, indent=2))
    return PostResult(th, rm, sweeps, files, summary)


def ports_json(ports) -> list[dict]:
    """The output ports as JSON: region, direction, spring (N/m) and weight of each."""
    return [{"region": p.region, "direction": list(map(float, p.direction)),
             "spring": float(p.spring), "weight": float(p.weight)} for p in ports]


def _present(supports: Supports, mesh) -> Supports:
    """The supports restricted to the boundaries and points the remeshed solid has: a thresholded
    design need not touch every support of its domain (e.g. a symmetry line); the clamp is
    guaranteed by :func:`~.remesh.remesh`."""
    names = set(mesh.GetBoundaries()) | set(mesh.GetBBoundaries())
    keep = lambda group: tuple(n for n in group if n in names)
    return Supports(**{k: keep(v) for k, v in dataclasses.asdict(supports).items()})


def _jsonable(row: dict) -> dict:
    out = {}
    for k, v in row.items():
        if isinstance(v, (np.floating, float)):
            v = float(v)
            out[k] = v if np.isfinite(v) else None
        elif isinstance(v, (np.integer, np.bool_)):
            out[k] = v.item()
        else:
            out[k] = v
    return out


# -- analysis.json and report.md of 'pacto analyse' ----------------------------
EXPECTED_DEFINITION = (
    "the optimised density design (final x, last penalty and beta) re-analysed with the "
    "optimisation's own model, Darcy load and output spring at inlet pressure P (load factor "
    "P/load, Newton with load stepping, warm-started along the sweep); for a linear model this "
    "equals the run's output displacement scaled linearly with P")


OUTPUT_DEFINITION = (
    "Delta = sum_k w_k d_k . u(x_k) over the output ports (x_k the port's vertex of the remeshed "
    "part, d_k its direction, w_k its weight), each port against its output spring k_k, as the "
    "optimisation defines it; 'ports' holds every port's own d_k . u(x_k)")


DARCY_DEFINITION = (
    "Darcy pressure of the thresholded design (element rho = 1 where at least half of the "
    "element lies inside the thresholded solid, else 0) as the deformation-independent body "
    "force -grad p, interpolated onto the remeshed solid")


MATERIALS_DEFINITION = (
    "two materials: the solid is where the nodal rho_bar1 >= threshold (the part); inside it, "
    "'stiff' (E2) where the nodal rho_bar2 >= threshold2, 'soft' (E1) elsewhere; the remeshed "
    "part has the regions 'soft' and 'stiff' ('body-fitted': glued along an 'interface' "
    "boundary; 'element-wise': each element by rho_bar2 at its centroid) and every analysis "
    "uses each region's own modulus")


def num_or_none(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def analysis_dict(run, problem, res, expected, pressures, delta_run, kinds, order, choice, maxh,
                  ports, supports, p_shown, rho_thr, wall, path_note=None) -> dict:
    """The content of ``analysis.json`` (see :mod:`~pacto_ng.post.cli_commands`); ``ports``: the
    output ports analysed."""
    rm, th = res.remeshed, res.thresholded
    p = run.params
    kept = th.polygon_area - rm.dropped_area
    mats = res.summary.get("materials")
    rows = []
    for i, P in enumerate(pressures):
        row = {"pressure": P, "expected": num_or_none(expected[i]["delta"]),
               "expected_converged": expected[i]["converged"],
               "expected_newton_iterations": expected[i]["newton_iterations"]}
        for k in kinds:
            pt = res.sweeps[k].points[i]
            row[k] = {"delta": num_or_none(pt.delta),
                      "ports": {q.region: num_or_none(v) for q, v in zip(ports, pt.ports)},
                      "max_u": num_or_none(pt.max_u), "min_J": num_or_none(pt.min_j),
                      "newton_iterations": int(pt.iterations), "converged": bool(pt.converged)}
        rows.append(row)
    def gap(row):
        out = {}
        for k in kinds:
            a, e = row[k]["delta"], row["expected"]
            out[k] = None if a is None or e in (None, 0.0) else (a - e) / abs(e)
        return out

    gaps, gaps0 = gap(rows[-1]), gap(rows[0])
    shifts = {p.region: float(np.hypot(*np.subtract(rm.ports[p.region][1],
                                                    rm.ports[p.region][0])))
              for p in ports if p.region in rm.ports}
    return {
        "run": {"dir": str(run.path), "case": run.case.name, "model": p.model, "load": run.load,
                "load_unit": run.case.load_unit, "iterations": run.k, "design": run.design,
                "stopped": run.summary.get("stopped"),
                "output_displacement_summary": run.summary.get("output_displacement"),
                "output_displacement_rebuilt": delta_run, "mesh_h": problem.h,
                "load_path_note": path_note},
        "settings": {"threshold": choice["used"],
                     "threshold_choice": dict(choice), "maxh": maxh,
                     "order": order, "kinds": list(kinds),
                     "E": p.E1 if mats is None else {"soft": p.E1, "stiff": p.E2},
                     "threshold2": None if mats is None else mats["threshold2"], "nu": p.nu,
                     "thickness": p.thickness, "material": "Neo-Hookean, plane strain",
                     "supports": dataclasses.asdict(supports),
                     "supports_used": res.summary.get("supports"),
                     "output_ports": ports_json(ports),
                     # the 2D re-analysis solves directly: the direct route's tolerance unless set
                     "newton_rtol": p.newton_rtol or DIRECT_RTOL},
        "definitions": {
            "output": OUTPUT_DEFINITION, "expected": EXPECTED_DEFINITION,
            "darcy": DARCY_DEFINITION,
            "fixed": "pressure P on the wetted boundary, deformation independent",
            "follower": "pressure P on the wetted boundary, following the deformation "
                        "(J F^-T N0)",
            "wetting": f"a boundary segment of the remeshed solid is wetted where it lies on the "
                       f"inlet boundary ({'|'.join(res.summary.get('wet_boundaries', []) or [])}) "
                       f"or where the run's final Darcy pressure one source element size "
                       f"outside it is at least 0.5 P_in",
            "gap": "(analysed - expected) / |expected|, at the largest and at the smallest "
                   "pressure (there: the effect of thresholding and remeshing alone)",
            "materials": None if mats is None else MATERIALS_DEFINITION},
        "areas": {"thresholded": th.area, "polygons": th.polygon_area,
                  "removed_specks": th.removed_area, "dropped_floating": rm.dropped_area,
                  "kept": kept, "remeshed": rm.area,
                  "remeshed_vs_kept": (rm.area - kept) / kept if kept else None,
                  "materials": None if mats is None else mats["areas"],
                  "darcy_elements_solid": float(np.sum(rho_thr * problem.field.areas)
                                                if hasattr(problem.field, "areas") else np.nan)},
        "remesh": {"elements": rm.mesh.ne, "geometry": rm.geometry,
                   "materials": None if mats is None else mats["mode"],
                   "interface_length": None if mats is None else mats["interface_length"],
                   "wetted_length": rm.wetted_length, "p_in": rm.p_in,
                   "ports": {k: {"source": list(map(float, a)), "new": list(map(float, b))}
                             for k, (a, b) in rm.ports.items()},
                   "port_shifts": shifts,
                   "output_port_shift": max(shifts.values()) if shifts else None},
        "deformed_state": {"kind": res.summary.get("deformed_state"), "pressure": p_shown},
        "pressures": rows,
        "gap_at_largest_pressure": gaps,
        "gap_at_smallest_pressure": gaps0,
        "wall_time_s": wall,
    }


def fmt_value(v, spec=".4g"):
    return "—" if v is None else format(v, spec)


def short_table(data) -> str:
    kinds = data["settings"]["kinds"]
    head = "  P (Pa)      expected    " + "".join(f"{k:12s}" for k in kinds)
    lines = [head]
    for r in data["pressures"]:
        lines.append(f"  {r['pressure']:<11.4g} {fmt_value(r['expected']):11s} " + "".join(
            f"{fmt_value(r[k]['delta']):12s}" for k in kinds))
    return "\n".join(lines)


def _ports_table(d, kinds, regions) -> list[str]:
    """report.md's table of every port's own displacement d·u per pressure and analysis."""
    cols = [(k, r) for k in kinds for r in regions]
    L = ["Every port's own displacement d·u (m), Δ = Σ w·d·u:", "",
         "| P (Pa) | " + " | ".join(f"{k} `{r}`" for k, r in cols) + " |",
         "|" + "---|" * (1 + len(cols))]
    for row in d["pressures"]:
        L.append(f"| {row['pressure']:.4g} | " +
                 " | ".join(fmt_value(row[k]["ports"][r]) for k, r in cols) + " |")
    L.append("")
    return L


def report_md(d) -> str:
    run, s, a, rm = d["run"], d["settings"], d["areas"], d["remesh"]
    kinds = s["kinds"]
    L = []
    L.append(f"# Post-analysis of {run['case']} — {run['model']} design, optimised at "
             f"{run['load']:.4g} {run['load_unit']}")
    L.append("")
    L.append(f"Run folder `{run['dir']}`; design `{run['design']}` after {run['iterations']} "
             f"iterations (stopped: {run['stopped']}).  Rebuilt output displacement "
             f"Δ = {fmt_value(run['output_displacement_rebuilt'], '.6g')} m "
             f"(summary.json: {fmt_value(run['output_displacement_summary'], '.6g')} m).")
    if run.get("load_path_note"):
        L.append("")
        L.append(f"**Warning**: {run['load_path_note']}.")
    L.append("")
    L.append("| run design ρ̄ | run Darcy pressure |")
    L.append("|---|---|")
    L.append("| ![design](../design.png) | ![pressure](../pressure.png) |")
    L.append("")
    L.append("## The part")
    L.append("")
    L.append(f"ρ̄ thresholded at {s['threshold']:g} (iso-line of the area-weighted nodal density) "
             f"and remeshed with Netgen triangles of {s['maxh']:.4g} m ({rm['elements']} "
             f"elements).")
    geo = rm.get("geometry", "traced")
    if geo == "domain":
        L.append("The part runs along the case's own geometry (its curved edges, holes and "
                 "chamber walls, with their names) wherever the solid reaches the domain's "
                 "boundary; inside, its boundary is the traced iso-line.")
    elif geo != "traced":
        L.append(f"The part's boundary is traced from the thresholded polygons: {geo[8:-1]}.")
    ch = s.get("threshold_choice")
    if ch:
        L.append(f"The threshold: {ch['note']}.  Material volume of the design "
                 f"{ch['design_volume']:.6g} m², area of the part at the threshold used "
                 f"{ch['part_area']:.6g} m².")
    L.append("")
    L.append("| area (m²) | value |")
    L.append("|---|---|")
    L.append(f"| thresholded (clipped mesh) | {a['thresholded']:.6g} |")
    L.append(f"| polygons (specks removed: {a['removed_specks']:.3g}) | {a['polygons']:.6g} |")
    L.append(f"| kept (floating pieces dropped: {a['dropped_floating']:.3g}) | {a['kept']:.6g} |")
    L.append(f"| remeshed | {a['remeshed']:.6g} ({100 * a['remeshed_vs_kept']:+.2f} % of kept) |")
    if a.get("materials"):
        L.append("")
        L.append(f"**Two materials**: {d['definitions']['materials']}.  ρ̄2 thresholded at "
                 f"{s['threshold2']:g}; the regions: {rm['materials']}, interface "
                 f"{rm['interface_length']:.4g} m long.")
        L.append("")
        L.append("| material | E (Pa) | area (m²) | share of the part |")
        L.append("|---|---|---|---|")
        total = sum(a["materials"].values())
        for name, area in a["materials"].items():
            L.append(f"| {name} | {s['E'].get(name, float('nan')):g} | {area:.6g} | "
                     f"{100 * area / total:.1f} % |")
        L.append("")
        L.append("![materials](materials.png)")
    L.append("")
    L.append(f"Wetted (`pressure`) boundary: {rm['wetted_length']:.4g} m.  Rule: "
             f"{d['definitions']['wetting']}.")
    for region, sh in rm["port_shifts"].items():
        warn = "" if sh <= 2 * run["mesh_h"] else \
            " **The output point moved more than two element sizes: the solid does not reach it.**"
        L.append(f"The output point `{region}` sits on the nearest vertex of the "
                 f"new mesh, {sh:.3g} m from its place in the run.{warn}")
    ports = s["output_ports"]
    if len(ports) == 1:
        L.append(f"Supports on the new mesh: {s['supports_used']}.  Output spring "
                 f"{ports[0]['spring']:g} N/m along {ports[0]['direction']}.")
    else:
        L.append(f"Supports on the new mesh: {s['supports_used']}.  Output Δ = Σ w·d·u over "
                 f"{len(ports)} ports: " + "; ".join(
                     f"`{q['region']}` d = {q['direction']}, w = {q['weight']:g}, spring "
                     f"{q['spring']:g} N/m" for q in ports) + ".")
    L.append("")
    L.append("## Re-analysis (Neo-Hookean, plane strain)")
    L.append("")
    E_text = (f"{s['E']:g} Pa" if not isinstance(s["E"], dict) else
              ", ".join(f"{v:g} Pa ({k})" for k, v in s["E"].items()))
    L.append(f"E = {E_text}, ν = {s['nu']:g}, t = {s['thickness']:g} m, displacement order "
             f"{s['order']}.")
    L.append("")
    L.append(f"* **expected** — {d['definitions']['expected']};")
    if "darcy" in kinds:
        L.append(f"* **darcy** (thesis §6.1.1, deformation-independent load) — "
                 f"{d['definitions']['darcy']};")
    if "fixed" in kinds:
        L.append(f"* **fixed** — {d['definitions']['fixed']};")
    if "follower" in kinds:
        L.append(f"* **follower** (thesis §6.1.2) — {d['definitions']['follower']}.")
    L.append("")
    L.append("![analysis](analysis.png)")
    L.append("")
    head = "| P (Pa) | expected Δ (m) | " + " | ".join(f"Δ {k} (m)" for k in kinds) + \
        " | max \\|u\\| (m) | min J | Newton its |"
    L.append(head)
    L.append("|" + "---|" * (4 + len(kinds)))
    ref = "follower" if "follower" in kinds else kinds[-1]
    for r in d["pressures"]:
        its = "/".join(str(r[k]["newton_iterations"]) for k in kinds)
        L.append(f"| {r['pressure']:.4g} | {fmt_value(r['expected'])} | " +
                 " | ".join(fmt_value(r[k]["delta"]) for k in kinds) +
                 f" | {fmt_value(r[ref]['max_u'])} | {fmt_value(r[ref]['min_J'])} | {its} |")
    L.append("")
    L.append(f"max |u| and min J of the {ref} analysis; Newton iterations "
             f"{'/'.join(kinds)}; — : not converged.")
    L.append("")
    if len(ports) > 1:
        L.extend(_ports_table(d, kinds, [q["region"] for q in ports]))
    pct = lambda gaps: ", ".join(f"{k} {fmt_value(None if g is None else 100 * g, '+.1f')} %"
                                 for k, g in gaps.items())
    P = [r["pressure"] for r in d["pressures"]]
    L.append(f"Gap to the expected Δ, (analysed − expected)/|expected|: at {P[-1]:.4g} Pa "
             f"{pct(d['gap_at_largest_pressure'])}; at {P[0]:.4g} Pa "
             f"{pct(d['gap_at_smallest_pressure'])} (at a small pressure the gap is what "
             f"thresholding and remeshing change; its growth with the pressure is the "
             f"nonlinearity the optimisation's model missed).")
    L.append("")
    ds = d["deformed_state"]
    if ds["kind"] is not None:
        L.append("## Deformed")
        L.append("")
        L.append(f"The {ds['kind']} analysis at {ds['pressure']:.4g} Pa, true scale, over the "
                 f"undeformed outline:")
        L.append("")
        L.append("![deformed](deformed.png)")
        L.append("")
    L.append("## Files")
    L.append("")
    L.append("`analysis.json` (every number above), `analysis.csv`, `post.json`, `design.stl` "
             "(the part, extruded by t), `remeshed.vtu` / `deformed.vtu` (u, p, J, stress, "
             "von_mises" + ("; material, E" if a.get("materials") else "") +
             "; reference / deformed configuration), `analysis.png`, `deformed.png`" +
             (", `materials.png`." if a.get("materials") else "."))
    L.append("")
    return "\n".join(L)
