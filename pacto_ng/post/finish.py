"""Steps 3 and 5 of ``pacto analyse``, for every part (a run's, :mod:`.analyse`, or a case
as built, :mod:`.as_built`): what is analysed (:class:`Subject`), the part analysed for every
kind over the pressures, and the files written into its folder (:func:`finish`).
"""
from __future__ import annotations

import dataclasses
import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import atomic_write_text
from ..params import Parameters
from ..physics.walls import pressure_body_force, solid_boundaries
from .domain import symmetry_line
from .export import material_names, write_vtu
from .materials import STIFF
from .part import Part, part_ports, present_supports
from .part_analysis import PartAnalysis
from .part_entries import materials_entry, part_entry, part_warnings
from .part_resources import TIME_LIMIT, contact_check
from .part_stage import write_part_stl
from .pictures import plot_deformed, plot_materials, plot_sweeps
from .plots3d import deformed_picture
from .report import analysis_csv, analysis_json, jsonable, ports_json, short_table
from .report_md import report_md


@dataclass
class Subject:
    """What ``pacto analyse`` analyses: a run's part or a case as built (:mod:`.as_built`).

    ``mesh`` is the design's (the case's) mesh, whose symmetry lines or planes make the whole
    part; ``params`` the analysis's parameters (model, order, material); ``run`` the ``run``
    entry of analysis.json; ``expected`` the rows of :func:`~.expected.expected_sweep` (None
    as built); ``darcy`` ``(p, P_in)``: the thresholded design's Darcy field on ``mesh``
    (None as built); ``h`` the design's element size; ``contact``: every boundary of the part
    that bounds its solid in frictionless self-contact."""

    case: object
    params: Parameters
    setup: object
    mesh: object
    part: Part
    out: Path
    run: dict
    h: float
    expected: list | None = None
    darcy: tuple | None = None
    measures: dict = dataclasses.field(default_factory=dict)
    warnings: list = dataclasses.field(default_factory=list)
    contact: bool = False  # the part's boundaries in self-contact (--contact)
    time_limit: float = TIME_LIMIT  # --time-limit: a sweep with contact estimated longer is refused


def say(quiet, msg):
    """Print ``msg`` (flushed) unless ``quiet``."""
    if not quiet:
        print(msg, flush=True)


def finish(subject: Subject, kinds, pressures, settings: dict, *, quiet: bool, t0: float) -> int:
    """Analyse the part of ``subject`` for every kind over ``pressures`` and write the files
    of the module docstring into ``subject.out``; ``settings`` holds what the flow chose (the
    threshold and its choice, threshold2, maxh).  Returns 0."""
    part, params = subject.part, subject.params
    settings = dict(settings, contact=subject.contact)
    ports = part_ports(subject.setup)
    supports = present_supports(subject.setup.supports, part.mesh)
    sweeps = {kind: _sweep(subject, kind, pressures, ports, supports, quiet) for kind in kinds}
    shown = next((k for k in ("follower",) + tuple(kinds) if k in sweeps
                  and sweeps[k].converged.any()), None)
    E = region_moduli(part.mesh, params)
    ana = next(iter(sweeps.values())).analysis
    settings = dict(settings, model=params.model, material=params.material, E=E, nu=params.nu,
                    thickness=params.thickness if part.dim == 2 else None,
                    plane=params.plane if part.dim == 2 else None, order=ana.order,
                    formulation=ana.formulation, pressures=[float(P) for P in pressures],
                    supports=dataclasses.asdict(supports), output_ports=ports_json(ports))
    deformed = {"kind": shown, "pressure": None if shown is None else float(
        sweeps[shown].pressures[np.flatnonzero(sweeps[shown].converged)[-1]])}
    warnings = subject.warnings + part_warnings(part, ports, sweeps, shown, subject.h,
                                                subject.run["load_unit"])
    data = analysis_json(
        run=subject.run, settings=jsonable(settings),
        part=part_entry(part, ports, subject.measures),
        seal=None if part.seal is None else part.seal.to_json(),
        materials=materials_entry(part, E, settings.get("threshold2")), sweeps=sweeps,
        ports=ports, expected=subject.expected, deformed=deformed, warnings=warnings,
        wall=time.perf_counter() - t0)
    mats = data["materials"]
    if mats:
        unit = "m²" if part.dim == 2 else "m³"
        cut = mats["part"] or {}
        say(quiet, f"  materials (remeshed, {mats['mode']}"
                    + ("; the part cut at the iso-surface" if cut else "") + "): " + ", ".join(
                        f"{k} {v:.4g} {unit}" + (f" ({cut[k]:.4g})" if k in cut else "")
                        for k, v in mats["remeshed"].items()))
    out = subject.out
    out.mkdir(parents=True, exist_ok=True)
    _write_files(subject, data, sweeps, shown, t0)
    for w in warnings:
        print(f"pacto: warning: {w}", file=sys.stderr, flush=True)
    say(quiet, short_table(data))
    say(quiet, f"  written to {out} ({time.perf_counter() - t0:.1f} s)")
    return 0


def _sweep(subject: Subject, kind, pressures, ports, supports, quiet):
    """One kind's :class:`~.part_analysis.Sweep`, a progress line per pressure."""
    extra = {}
    if kind == "darcy":
        p, p_in = subject.darcy
        extra = dict(body=pressure_body_force(p), body_pressure=p_in)
    if subject.contact:
        extra["contact"] = solid_boundaries(subject.part.mesh)  # not the domains' interfaces
    try:
        ana = PartAnalysis(subject.part.mesh, kind, params=subject.params, supports=supports,
                           ports=ports, chamber=subject.part.sealed is True, **extra)
    except ValueError as err:
        raise InputError(f"analyse: the part cannot be analysed: {err}") from None
    if subject.contact:
        say(quiet, f"  {kind}: " + contact_check(ana.iteration_seconds(), len(pressures),
                                                 subject.time_limit))
    return ana.sweep(pressures, say=None if quiet else (lambda line: print(line, flush=True)))


def region_moduli(mesh, params):
    """Young's modulus of the part: E1, or per region ``{name: E2 on stiff, else E1}``."""
    names = material_names(mesh)
    if STIFF not in names:
        return float(params.E1)
    return {n: float(params.E2 if n == STIFF else params.E1) for n in names}


def _write_files(subject: Subject, data: dict, sweeps: dict, shown, t0: float) -> None:
    """The files: the table, the pictures, the STL, the VTUs, the report and, last (with the
    wall time since ``t0``), analysis.json."""
    out, part, run = subject.out, subject.part, subject.run
    unit = run["load_unit"]
    exp = [r for r in (subject.expected or []) if r["converged"]]
    plot_sweeps(out / "analysis.png", sweeps, log=True,
                expected=([r["pressure"] for r in exp], [r["delta"] for r in exp]) if exp
                else None,
                title=f"{run['case']} — " + ("as built" if run["as_built"] else
                                             f"{run['model']} design, {part.dim}D part")
                + f", {subject.params.model} analysis")
    atomic_write_text(out / "analysis.csv", analysis_csv(data))
    write_part_stl(out / "part.stl", part, subject)
    line = symmetry_line(subject.mesh) if part.dim == 2 else None
    if part.dim == 2 and isinstance(data["settings"]["E"], dict):
        plot_materials(out / "materials.png", part.mesh, mirror=line or False,
                       title="the part's regions: E2 on 'stiff', E1 elsewhere")
    u, extra = None, {}
    if shown is not None:
        sw = sweeps[shown]
        u = sw.displacement()
        P = data["deformed_state"]["pressure"]
        title = (f"{run['case']} part, {shown} {P:.3g} {unit}, {subject.params.model} "
                 f"(true scale)")
        touch = sw.contact_points()  # --contact: the walls' vertices in contact, marked
        if part.dim == 2:
            plot_deformed(out / "deformed.png", part.mesh, u, title=title, mirror=line or False,
                          contact=touch)
        else:
            deformed_picture(out / "deformed.png", part.mesh, u, title=title, contact=touch)
        if subject.darcy is not None:
            p, p_in = subject.darcy
            extra["p"] = _vertex_values(p, subject.mesh, part.mesh) * (P / p_in)
    phi = sweeps[shown].analysis.energy_density if shown is not None else None
    kw = dict(phi=phi, plane=subject.params.plane, E=data["settings"]["E"], point_data=extra)
    write_vtu(out / "remeshed.vtu", part.mesh, u, **kw)
    if u is not None:
        write_vtu(out / "deformed.vtu", part.mesh, u, deformed=True, **kw)
    data["wall_time_s"] = time.perf_counter() - t0
    atomic_write_text(out / "report.md", report_md(data))
    atomic_write_text(out / "analysis.json", json.dumps(data, indent=1))


def _vertex_values(field, source, mesh) -> np.ndarray:
    """``field`` (a CF on ``source``) at the vertices of ``mesh``; 0 outside ``source``."""
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    mips = source(*(pts[:, i].copy() for i in range(mesh.dim)))
    vals = np.zeros(len(pts))
    inside = np.asarray(mips["nr"]) >= 0
    if inside.any():
        vals[inside] = np.asarray(field(mips[inside])).ravel()
    return vals
