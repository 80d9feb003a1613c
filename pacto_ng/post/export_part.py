"""The two steps of ``pacto export`` that differ by dimension, :data:`STEPS`; the one flow
around them is :func:`~pacto_ng.post.cli_commands.export_run`.  **Make the part's solid**: 2D
the design thresholded and remeshed (:func:`make_2d`), 3D the smoothed iso-surface and the
clipped solid (:func:`make_3d`).  **Mirror, write and describe it**: 2D about the symmetry line
(:func:`write_2d`: STL extruded, VTK/VTU with the run's state, MSH), 3D about the symmetry
planes (:func:`write_3d`: STL the surface, VTK/VTU the clipped solid with the run's state).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..files import atomic_path
from ..threads import compute
from .domain import symmetry_line
from .export import UNITS
from .materials import SOFT, STIFF, material_areas
from .mirror3d import mirror_solid, mirror_surface, symmetry_planes
from .part2d import PartMesh, part_fields, part_mesh, write_part_stl, write_part_vtu
from .part3d import closed_checks, part3d, void_regions, write_part_stl as write_surface_stl
from .post3d import RHO2, material_volumes, part_solid, split_materials, write_part_solid
from .runs import design_density, part_of_run, rebuild

#: the formats ``pacto export`` writes, per dimension
FORMATS = {2: ("stl", "vtk", "vtu", "msh"), 3: ("stl", "vtk", "vtu")}


@dataclass
class ExportPart:
    """A run's part as ``pacto export`` makes it (:func:`make_2d`, :func:`make_3d`)."""

    problem: object  # the run rebuilt, its final design analysed
    threshold: float  # the density threshold the part is cut at
    exclude: tuple  # the passive void regions left out of it (and of the seal check)
    solid: object  # 2D: (Thresholded, Remeshed); 3D: the Part3D
    threshold2: float | None  # two materials: ρ̄2's threshold; one material: None


@dataclass
class Written:
    """What :func:`write_2d` / :func:`write_3d` wrote, for the line that says so."""

    about: str | None  # what the part was mirrored about; None: written as solved
    measures: str  # the part's elements, size and boundaries
    notes: list  # materials, geometry, the fields written


# -- make the part's solid ------------------------------------------------------------------
def make_2d(run, setup, threshold: float, maxh, threshold2: float) -> ExportPart:
    """The thresholded, remeshed part (:func:`~.runs.part_of_run`; ``maxh`` None: half the
    run's element size; ``setup`` unused: part_of_run makes its own)."""
    th, rm, problem = part_of_run(run, threshold, maxh, threshold2)
    return ExportPart(problem, th.threshold, tuple(th.excluded), (th, rm),
                      None if rm.materials is None else threshold2)


def make_3d(run, setup, threshold: float, maxh, threshold2: float) -> ExportPart:
    """The :class:`~.part3d.Part3D` of the run's final design (``maxh`` unused: the 3D part
    is the smoothed iso-surface, not a remesh); a two-material design's solid cut into the
    materials at ρ̄2 = ``threshold2`` (:func:`~.post3d.split_materials`).  InputError when
    there is no part."""
    with compute():
        problem = rebuild(run)
    exclude = void_regions(problem.mesh, setup)
    two = setup.materials == 2
    try:
        part = part3d(problem.mesh, design_density(problem), threshold,
                      clamp=setup.supports.clamp, exclude=exclude,
                      fields={RHO2: problem.values["rho_bar2"]} if two else None)
        if two:
            part.solid = split_materials(part.solid, threshold2)
    except ValueError as err:
        raise InputError(str(err)) from None
    return ExportPart(problem, part.threshold, exclude, part, threshold2 if two else None)


# -- mirror, write and describe it ----------------------------------------------------------
def write_2d(dst, fmt: str, part: ExportPart, run, units: str, mirror: bool) -> Written:
    """The remeshed part, with ``mirror`` merged with its image about the symmetry line of the
    run's own mesh (the part may not reach it), written to ``dst`` as ``fmt`` in ``units``."""
    th, rm = part.solid
    line = symmetry_line(part.problem.mesh) if mirror else None
    whole = part_mesh(rm.mesh, line)
    t, scale = float(run.params.thickness), 1.0 / UNITS[units]
    state = []
    if fmt == "stl":
        write_part_stl(dst, whole, t, units=units,
                       header=f"pacto_ng {run.case.name} part, thickness {t * scale:g} {units}"
                              + (", whole (mirrored)" if line is not None else ""))
    elif fmt == "msh":
        write_msh(dst, whole, units=units)
    else:
        point, cell, state = _sampled(part_fields, part.problem, whole)
        E = None if part.threshold2 is None else {SOFT: run.params.E1, STIFF: run.params.E2}
        write_part_vtu(dst, whole, point_data=point, cell_data=cell, units=units, fmt=fmt, E=E)
        state.append(fields_note([*point, *cell]))
    notes = [] if part.threshold2 is None else [
        materials_note(material_areas(rm.mesh), "m²", part.threshold2, rm.materials)]
    if rm.geometry != "traced":  # "domain", or "traced (... failed: why)"
        notes.append("on the case's own geometry" if rm.geometry == "domain" else rm.geometry)
    kind = "triangles" if all(len(e) == 3 for e in whole.elements) else "elements"
    measures = (f"{len(whole.elements)} {kind}, area {whole.area() * scale ** 2:.6g} {units}² ("
                + ("the half: " if line is not None else "")
                + f"remeshed {rm.area:.6g} m², thresholded {th.area:.6g} m²), boundaries "
                f"{', '.join(sorted(set(whole.edge_names)))}"
                + (f", extruded by the thickness {t * scale:g} {units}" if fmt == "stl" else ""))
    return Written(None if line is None else f"1 line ({_line_text(line)})", measures,
                   notes + state)


def write_3d(dst, fmt: str, part: ExportPart, run, units: str, mirror: bool) -> Written:
    """The 3D part, with ``mirror`` reflected about the symmetry planes of the run's mesh
    (:func:`~.mirror3d.symmetry_planes`), written to ``dst`` as ``fmt`` in ``units``: STL the
    closed, smoothed surface; VTK/VTU the clipped solid with the run's final state."""
    p3 = part.solid
    planes = symmetry_planes(part.problem.mesh) if mirror else []
    surface = mirror_surface(p3.surface, planes) if planes else p3.surface
    about = f"{len(planes)} plane{'' if len(planes) == 1 else 's'}"
    state = []
    if fmt == "stl":
        write_surface_stl(dst, surface, units, header=f"pacto_ng {run.case.name} part (3D)"
                          + (f", whole (mirrored about {about})" if planes else ""))
    else:
        solid, state = _sampled(part_solid, p3, part.problem)
        write_part_solid(dst, mirror_solid(solid, planes), 1.0 / UNITS[units])
        state.append(fields_note([*solid.point_data, *solid.cell_data]))
    notes = [] if part.threshold2 is None else [
        materials_note(material_volumes(p3.solid), "m³", part.threshold2)]
    chk = closed_checks(surface)
    measures = (f"volume {p3.volume:.6g} m³ as solved (thresholded, kept pieces "
                f"{p3.volume_kept:.6g}: {100 * p3.volume_error:+.2f} %; {p3.dropped} of "
                f"{p3.pieces} pieces off the clamp dropped), {surface.n_cells} triangles, "
                f"{chk['n_open_edges']} open edges, manifold {chk['manifold']}")
    return Written(f"{about} ({', '.join(map(str, planes))}), volume {surface.volume:.6g} m³"
                   if planes else None, measures, notes + state)


#: per dimension: make the part's solid, and mirror, write and describe it
STEPS = {2: (make_2d, write_2d), 3: (make_3d, write_3d)}


def _sampled(sample, *args):
    """``sample(*args)`` (the run's final state on the part); its ValueError one InputError."""
    try:
        return sample(*args)
    except ValueError as err:
        raise InputError(f"export: {err}") from None


def fields_note(names) -> str:
    return "fields " + ", ".join(names) + " of the run's final state"


def materials_note(measures: dict, unit: str, threshold2: float, mode: str = "") -> str:
    """Each material's area or volume (``unit``) as solved, and ρ̄2's threshold."""
    return ("materials " + ", ".join(f"{k} {v:.6g} {unit}" for k, v in measures.items())
            + f" as solved (ρ̄2 at {threshold2:g}" + (f", {mode})" if mode else ")"))


def _line_text(line) -> str:
    """A 2D symmetry line as the 3D planes are printed: ``symmetry: y = 0 m``."""
    (px, py), (dx, dy) = line.point, line.direction
    where = (f"y = {py:g} m" if abs(dy) < 1e-12 else f"x = {px:g} m" if abs(dx) < 1e-12 else
             f"through ({px:g}, {py:g}) m along ({dx:.6g}, {dy:.6g})")
    return f"symmetry: {where}"


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
