"""What ``pacto analyse`` writes about a part, in one layout for 2D and 3D, for a run's part
and for a case as built: ``analysis.json`` (:func:`analysis_json`; the part's entries in it:
:mod:`.part_entries`), ``analysis.csv`` (:func:`analysis_csv`) and the table printed at the
end (:func:`short_table`); ``report.md`` is :mod:`.report_md`.

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
                               ``converged``, ``load_reached``, ``past_peak``,
                               ``volume_change`` (the chamber's), ``contact``
                               (``--contact``: ``area``, ``force``, ``pressure``; else None)
``pressure_maximum``,          per kind the pressure maximum passed, and the path's
``path``                       equilibria (``pressure``, ``delta``, ``volume_change``)
``first_contact``              ``--contact``: per kind the first swept pressure with the walls
                               touching and the one before it (:func:`first_contact`); else None
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
    "contact": "--contact, per pressure and kind: area, where the walls overlap (m², of one "
               "wall; in 2D its length times the thickness); force, the normal force between "
               "them (N); pressure, the largest contact pressure (Pa), the largest over the "
               "walls' vertices of the contact pressure averaged around the vertex with its "
               "hat function as the weight (it tends to the peak as the elements shrink; "
               "over a zone narrower than a few elements it is averaged with the walls "
               "beside it and can fall below force / area: refine the mesh)",
    "first_contact": "--contact, per kind: pressure, the first pressure of the sweep at which "
                     "the walls touch (the smallest swept pressure with a contact area > 0; a "
                     "swept pressure, not interpolated), and last_without, the swept pressure "
                     "before it, at which they did not touch: contact began between the two "
                     "(None: no swept pressure with contact, or none without)",
    "volume_change": "per pressure and kind, the change of the volume the wetted walls "
                     "enclose (the chamber; m³, in 2D its area times the thickness), from "
                     "the walls' motion (Nanson's formula), the symmetry planes through its "
                     "origin; None for the darcy kind",
    "path": "per kind, the equilibria of the path followed where Newton lost the "
            "equilibrium (pressure, delta, volume_change), in order: the pressure against "
            "the chamber's volume through a pressure maximum",
    "pressure_maximum": "per kind, the largest pressure on the equilibrium path where Newton "
                        "lost the equilibrium at a pressure of the sweep and the path, "
                        "followed on with Delta prescribed, showed the pressure falling "
                        "(a chamber that balloons), with Delta there; a point marked "
                        "past_peak was reached along that path",
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
    """``v`` formatted with ``spec``; "—" for None (not converged, not computed)."""
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
            "load_reached": num(pt.load_reached), "past_peak": bool(pt.past_peak),
            "volume_change": None if pt.volume_change is None else num(pt.volume_change),
            # --contact: where the walls touch (m²), the force between them (N) and the
            # largest contact pressure (Pa)
            "contact": None if pt.contact_area is None else
            {"area": num(pt.contact_area), "force": num(pt.contact_force),
             "pressure": num(pt.contact_pressure)}}


def first_contact(sweep) -> dict | None:
    """``{"pressure", "last_without"}`` of a sweep with contact (None without): the smallest
    swept pressure at which the walls touch (a contact area > 0; None if they touch at none)
    and the largest converged swept pressure below it at which they do not (None if there is
    none): the walls first touch between the two."""
    if all(p.contact_area is None for p in sweep.points):
        return None
    out = {"pressure": None, "last_without": None}
    for p in sweep.points:
        if p.contact_area:
            out["pressure"] = float(p.pressure)
            break
        if p.converged:
            out["last_without"] = float(p.pressure)
    return out


def _gaps(row, kinds) -> dict:
    e = row["expected"]
    return {k: None if e in (None, 0.0) or row[k]["delta"] is None else
            (row[k]["delta"] - e) / abs(e) for k in kinds}


def analysis_json(*, run: dict, settings: dict, part: dict, seal, materials, sweeps: dict,
                  ports, expected, deformed: dict, warnings: list, wall: float) -> dict:
    """The content of ``analysis.json`` (the module's table).  ``sweeps``: kind ->
    :class:`~.part_analysis.Sweep` over ``settings["pressures"]``; ``expected``: the rows of
    :func:`~.expected.expected_sweep`, or None (a part as built)."""
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
                                else ("wetting_as_built",))
                   + (() if settings.get("contact") else ("contact", "first_contact"))}
    if built:
        definitions["wetting"] = definitions.pop("wetting_as_built")
    return {"run": run, "settings": dict(settings, kinds=kinds), "part": part, "seal": seal,
            "materials": materials, "definitions": definitions, "pressures": rows,
            "gap_at_largest_pressure": _gaps(rows[-1], kinds) if expected else None,
            "gap_at_smallest_pressure": _gaps(rows[0], kinds) if expected else None,
            "gap_parts": gap_parts(rows[-1], kinds) if expected else None,
            "pressure_maximum": {k: sweeps[k].peak for k in kinds},
            "path": {k: sweeps[k].path for k in kinds},
            "first_contact": ({k: first_contact(sweeps[k]) for k in kinds}
                              if settings.get("contact") else None),
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


def jsonable(value):
    """Tuples as lists, numpy numbers as Python numbers, recursively (for analysis.json)."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value
