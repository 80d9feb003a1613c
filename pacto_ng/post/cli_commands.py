"""``pacto export``: from a finished run to a part to fabricate from (``pacto analyse`` is
:mod:`pacto_ng.post.analyse`, ``pacto compare`` :mod:`pacto_ng.post.compare`; reading a run
folder back, :mod:`pacto_ng.post.runs`).

``export DIR --format stl|vtk|vtu|msh`` thresholds and remeshes the run's final design (the
settings of ``DIR/analysis/analysis.json`` when it exists, so that the exported part is the
analysed one) and writes the whole mechanism (mirrored about a symmetry line), in mm for STL
and m otherwise (docs/postprocessing.md, "pacto export").  A 3D run's export is
:func:`~pacto_ng.post.post3d.export_run_3d`.
"""
from __future__ import annotations

import json
import math

import numpy as np

from ..errors import InputError
from ..files import atomic_path
from .domain import symmetry_line
from .export import UNITS
from .materials import material_areas
from .part2d import PartMesh, part_fields, part_mesh, write_part_stl, write_part_vtu
from .post3d import export_run_3d, is_3d
from .runs import export_destination, load_run, part_of_run
from .seal import design_seal, warn_if_open


# ------------------------------------------------------------------------------------------
def check_threshold(value, *, allow_volume: bool = False, name: str = "--threshold"):
    """A threshold in (0, 1), or (with ``allow_volume``) the word ``volume``: the
    volume-preserving threshold of :func:`~pacto_ng.post.threshold_choice.volume_threshold`."""
    if isinstance(value, str):
        if value.strip().lower() == "volume":
            if not allow_volume:
                raise InputError(f"{name}: 'volume' is an option of 'pacto analyse' "
                                 f"--threshold only; give a number in (0, 1)")
            return "volume"
        try:
            value = float(value)
        except ValueError:
            raise InputError(f"{name}: expected a number in (0, 1)"
                             f"{' or volume' if allow_volume else ''}, got '{value}'") from None
    if not (0.0 < float(value) < 1.0) or not math.isfinite(float(value)):
        raise InputError(f"{name}: must lie in (0, 1), got {value:g}")
    return float(value)


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)


# ------------------------------------------------------------------------------------------
# pacto export
EXPORT_FORMATS = ("stl", "vtk", "vtu", "msh")
#: ``pacto export``'s length unit when ``--units`` is not given: the STL (for slicers and CAD,
#: which read it in mm) in mm; the analysis files (vtk, vtu, msh) in the solver's SI metres
DEFAULT_UNITS = {"stl": "mm", "vtk": "m", "vtu": "m", "msh": "m"}


def check_units(units, fmt: str) -> str:
    """``--units``: mm or m (None: :data:`DEFAULT_UNITS` of the format)."""
    if units is None:
        return DEFAULT_UNITS[fmt]
    if units not in UNITS:
        raise InputError(f"--units: choose from {', '.join(UNITS)} (got '{units}')")
    return units


def write_msh(path, mesh, *, units: str = "m"):
    """Gmsh 2.2 file of a 2D part through meshio: the triangles, whose physical group
    is their material (``solid``; ``soft`` and ``stiff`` for a two-material part), and every
    boundary edge as a line whose physical group is its boundary name (the materials are
    groups 1, 2, ..., the boundaries follow).  ``mesh`` is a 2D NGSolve mesh or a
    :class:`~pacto_ng.post.part2d.PartMesh` (e.g. the whole, mirrored part); coordinates in
    ``units``."""
    import meshio

    part = mesh if isinstance(mesh, PartMesh) else part_mesh(mesh)
    mat_groups = part.material_groups
    names = sorted(set(part.edge_names))
    tag = {n: i + 1 + len(mat_groups) for i, n in enumerate(names)}
    cells, phys = [], []
    if len(part.edges):
        cells.append(("line", part.edges))
        phys.append(np.array([tag[n] for n in part.edge_names], dtype=np.int64))
    for (kind, block), idx in zip(part.blocks(), part.block_order()):
        cells.append((kind, block))
        phys.append(part.material[idx].astype(np.int64))
    field_data = dict(mat_groups)
    field_data.update({n: np.array([t, 1]) for n, t in tag.items()})
    pts = part.points / UNITS[units]
    m = meshio.Mesh(np.c_[pts, np.zeros(len(pts))], cells,
                    cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                    field_data=field_data)
    with atomic_path(path) as tmp:
        meshio.write(str(tmp), m, file_format="gmsh22", binary=False)
    return m


def _analysed_settings(run, threshold_value, maxh, threshold2):
    """The threshold, maxh and threshold2 not given: those of ``DIR/analysis/analysis.json``
    when it exists (the exported part is then the analysed one), else None."""
    prev = run.path / "analysis" / "analysis.json"
    if prev.exists() and (threshold_value is None or maxh is None or threshold2 is None):
        try:
            s = json.loads(prev.read_text())["settings"]
            threshold_value = s["threshold"] if threshold_value is None else threshold_value
            maxh = s["maxh"] if maxh is None else maxh
            threshold2 = s.get("threshold2") if threshold2 is None else threshold2
        except (ValueError, KeyError, TypeError):
            pass
    return threshold_value, maxh, threshold2


def export_run(folder, fmt: str, *, out=None, threshold_value=None, maxh=None,
               quiet: bool = False, threshold2=None, units=None, mirror: bool = True) -> int:
    """``pacto export``: the thresholded, remeshed part of a run as stl | vtk | vtu | msh.

    Without ``--threshold``/``--maxh`` the settings of ``DIR/analysis/analysis.json`` are used
    when it exists (the exported part is then the analysed one), else 0.5 and half the run's
    element size.

    * ``mirror`` (default): a case solved on a symmetric half (a straight ``symmetry``
      boundary) is written whole: the part and its mirror image merged along the line
      (:func:`~pacto_ng.post.part2d.part_mesh`); False: the half as solved.
    * ``units``: ``mm`` or ``m``, default :data:`DEFAULT_UNITS` (mm for STL, m otherwise).
    * STL: the part extruded by the case's thickness (``params.json``), closed, binary, the
      unit in its header.  VTK / VTU: the 2D cells with the run's final state on them
      (:func:`~pacto_ng.post.part2d.part_fields`: ρ̄, u, p, the model's strain and stress; the
      coordinates and u in ``units``, p and stress in Pa).  MSH: Gmsh 2.2 with the boundary
      names as physical groups.
    * A two-material part (``threshold2``: ρ̄2's, default the analysis's, else 0.5) has the
      regions ``soft`` and ``stiff``: the STL is the whole part; the VTK/VTU has cell data
      ``material`` (named in its field data) and ``E``; the MSH the materials as physical
      groups of the triangles.
    """
    units, threshold2 = _checked_options(fmt, units, threshold_value, maxh, threshold2)
    run = load_run(folder, "export")
    if is_3d(run):
        return export_run_3d(run, fmt, out=out, threshold_value=threshold_value, quiet=quiet,
                             units=units, mirror=mirror, threshold2=threshold2)
    threshold_value, maxh, threshold2 = _analysed_settings(run, threshold_value, maxh,
                                                           threshold2)
    threshold_value = 0.5 if threshold_value is None else threshold_value
    threshold2 = 0.5 if threshold2 is None else threshold2
    th, rm, problem = part_of_run(run, threshold_value, maxh, threshold2)
    warn_if_open(design_seal(problem, run.case.make_setup(run.params), th.threshold,
                             exclude=th.excluded))
    # the whole mechanism: the symmetry line of the run's own mesh (the part may not reach it)
    line = symmetry_line(problem.mesh) if mirror else None
    part = part_mesh(rm.mesh, line)
    dst = export_destination(run, out, fmt)
    notes = []
    if mirror and line is None and run.summary.get("symmetric_half_domain"):
        notes.append("not mirrored: the run's symmetry boundary is not a straight line")
    notes += _write_part(dst, fmt, part, run, problem, units, rm.materials is not None)
    _say(quiet, f"{dst}: {run.case.name} part"
                + (" (whole: the half and its mirror image)" if line is not None else "")
                + _part_description(part, th, rm, run, fmt, units, threshold2)
                + "".join(f"; {n}" for n in notes))
    return 0


def _checked_options(fmt: str, units, threshold_value, maxh, threshold2) -> tuple:
    """``(units, threshold2)``: the options checked (InputError), the unit defaulted
    (:func:`check_units`) and ``threshold2`` as a number."""
    if fmt not in EXPORT_FORMATS:
        raise InputError(f"--format: choose from {', '.join(EXPORT_FORMATS)} (got '{fmt}')")
    units = check_units(units, fmt)
    if threshold_value is not None:
        check_threshold(threshold_value)
    if threshold2 is not None:
        threshold2 = check_threshold(threshold2, name="--threshold2")
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    return units, threshold2


def _write_part(dst, fmt: str, part: PartMesh, run, problem, units: str, two: bool) -> list:
    """Write ``part`` to ``dst`` as ``fmt`` (VTK/VTU with the run's final state on it);
    returns the notes for the line that says what was written."""
    t = float(run.params.thickness)
    scale = 1.0 / UNITS[units]
    notes = []
    if fmt == "stl":
        write_part_stl(dst, part, t, units=units,
                       header=f"pacto_ng {run.case.name} part, thickness {t * scale:g} {units}"
                              + (", whole (mirrored)" if part.line is not None else ""))
    elif fmt == "msh":
        write_msh(dst, part, units=units)
    else:
        E = {"soft": run.params.E1, "stiff": run.params.E2} if two else None
        try:
            point, cell, field_notes = part_fields(problem, part)
        except ValueError as err:
            raise InputError(f"export: {err}") from None
        notes += field_notes
        write_part_vtu(dst, part, point_data=point, cell_data=cell, units=units, fmt=fmt, E=E)
        notes.append("fields " + ", ".join([*point, *cell]) + " of the run's final state")
    return notes


def _part_description(part: PartMesh, th, rm, run, fmt: str, units: str,
                      threshold2: float) -> str:
    """The exported part for the line that says what was written: threshold, elements, area,
    boundaries, unit, materials and geometry."""
    t = float(run.params.thickness)
    scale = 1.0 / UNITS[units]
    two = rm.materials is not None
    return (f", threshold {th.threshold:g}, {len(part.elements)} "
            f"{'triangles' if all(len(e) == 3 for e in part.elements) else 'elements'}, "
            f"area {part.area() * scale ** 2:.6g} {units}² ("
            + ("the half: " if part.line is not None else "")
            + f"remeshed {rm.area:.6g} m², thresholded {th.area:.6g} m²), boundaries "
            f"{', '.join(sorted(set(part.edge_names)))}"
            + (f", extruded by the thickness {t * scale:g} {units}" if fmt == "stl" else "")
            + f"; units {units}"
            + ("; materials " + ", ".join(f"{k} {v:.6g} m²" for k, v in
                                          material_areas(rm.mesh).items())
               + f" (ρ̄2 at {threshold2:g}, {rm.materials})" if two else "")
            + {"domain": ", on the case's own geometry", "traced": ""}.get(
                rm.geometry, f"; {rm.geometry}"))
