"""A case's own geometry as the part: ``pacto analyse CASE --as-built``.

Designers compare an optimised part with the actuator they have.  Here the part is the case's
geometry as it stands — all its material (the design region and the passive solids; the
passive void regions, e.g. the chambers, removed), no optimisation — analysed by the flow of
:mod:`.analyse` from its step 3: the pressure on the chamber walls (the set-up's inlet
boundaries, ``--set inlet`` if given, are the wetted walls, renamed ``pressure``), ``fixed``
and/or ``follower``, with any model and material (``--model``, ``--set material=PRESET``,
every ``--set`` a run accepts), each region of the geometry named ``stiff`` with E2 and every
other region with E1 (:func:`~.part_analysis.solid_fields`), and the same files and report
(no expected Δ, no seal of a density: instead :func:`chambers` checks that the inlet walls
bound a chamber).

The part's mesh (:func:`as_built_mesh`) is Netgen's own sub-mesh of the case's mesh
(``Mesh.GetSubMesh``) over its non-void regions.  Chosen over the two ways of building it
anew (a netgen ``Mesh`` filled with the kept elements by ``AddPoints``/``AddElements``, or the
netgen.occ shape less its void faces meshed again) because it keeps, in one call, every
element of any type (triangles, quadrilaterals, tetrahedra, hexahedra), every boundary, edge
and point name (supports, ports and springs act by name), *and* the geometry the mesh was
made from, so that a curved wall is curved to the displacement order (``Mesh.Curve``): the
thick ring of the tests meets Lamé's closed form to the discretisation error of the
analysis, not of a polygon.  It works for every geometry source of a case (netgen.occ shapes,
CAD files, Layouts, structured quads and hexahedra, mesh files); a shape meshed anew would
not cover the last three, and AddElements would lose the geometry.  The part is the
optimisation's own mesh, so an as-built analysis and a run share their element size
(``--maxh`` sets the case's).
"""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
from netgen.meshing import NgException

from .. import resources
from ..case import mesh_for
from ..errors import InputError
from ..setup_names import check_setup_names
from ..threads import compute
from .analysis_options import DEFAULT_ORDER, analysis_params, check_kinds, default_pressures
from .boundary import named_points
from .finish import Subject, finish
from .grid import mesh_to_pyvista
from .materials import STIFF
from .part import Part
from .part3d import Part3D
from .part_resources import TIME_LIMIT, check_resources
from .remesh import PRESSURE
from .seal import check_seal

#: the kinds of a part as built (the ``darcy`` kind needs a design's Darcy field)
KINDS = ("fixed", "follower")


def as_built_mesh(mesh, void=(), inlet=(), order: int = 1):
    """The case's ``mesh`` without the regions ``void`` (Netgen's sub-mesh: the module
    docstring), its boundaries named in ``inlet`` renamed ``pressure`` (the wetted walls),
    curved to ``order`` where the mesh has a geometry.  InputError when nothing is left."""
    import ngsolve

    keep = sorted(set(mesh.GetMaterials()) - set(void))
    if not keep:
        raise InputError("as built: every region of the case is a void region")
    pattern = "|".join(re.escape(n) for n in keep)
    ngm = mesh.ngmesh
    sub = ngm.GetSubMesh(**{"domains" if mesh.dim == 3 else "faces": pattern})
    for i, name in enumerate(sub.GetRegionNames(codim=1)):
        if name in set(inlet):
            sub.SetBCName(i, PRESSURE)
    part = ngsolve.Mesh(sub)
    if part.ne == 0:
        raise InputError("as built: the case's mesh has no element outside its void regions")
    if order > 1 and sub.GetGeometry() is not None:
        try:
            part.Curve(order)
        except NgException:  # a geometry that cannot curve the part: it stays straight-sided
            pass
    return part


def chambers(mesh, setup, inlet):
    """Whether the inlet walls bound a chamber: the seal check (:func:`~.seal.check_seal`) of
    the case's geometry as built (ρ = 1 outside the void regions, the void regions passive
    void): each chamber, the void behind an inlet wall, must reach no zero-pressure
    boundary.  An inlet on the geometry's outer boundary has no void behind it (the fluid is
    beyond it): no chamber."""
    return check_seal(mesh, np.ones(mesh.ne), 0.5, inlet=tuple(inlet),
                      zero=setup.pressure.zero, exclude=tuple(setup.void))


def _stl_solid(mesh) -> Part3D:
    """A 3D part's closed surface for its STL (the outer faces of its elements, outward)."""
    grid = mesh_to_pyvista(mesh)
    surface = grid.extract_surface(algorithm="dataset_surface").triangulate().clean()
    surface = surface.compute_normals(consistent_normals=True, auto_orient_normals=True,
                                      cell_normals=True, point_normals=False)
    volume = float(surface.volume)
    return Part3D(surface, grid, 1.0, volume, volume, 1, 0)


def as_built_part(mesh, setup, inlet, order: int) -> Part:
    """The case's meshed geometry ``mesh`` as the part (:func:`as_built_mesh`), with its
    measure, wetted walls, chambers (:func:`chambers`) and named points."""
    import ngsolve

    check_setup_names(mesh, setup)
    part_mesh = as_built_mesh(mesh, setup.void, inlet, order)
    if PRESSURE not in part_mesh.GetBoundaries():
        raise InputError(f"as built: no inlet boundary ({', '.join(inlet)}) bounds the part: "
                         f"the pressure has no wall to act on")
    measure = float(ngsolve.Integrate(1.0, part_mesh))
    wetted = float(ngsolve.Integrate(1.0, part_mesh, ngsolve.BND,
                                     definedon=part_mesh.Boundaries(PRESSURE)))
    stiff = STIFF in set(part_mesh.GetMaterials())
    part = Part(part_mesh, mesh.dim, None, {"note": "as built"}, measure, measure, wetted,
                chambers(mesh, setup, inlet), "as built", "as built" if stiff else None,
                (_stl_solid(part_mesh) if mesh.dim == 3 else None, None),
                {name: (pt, pt) for name, pt in named_points(part_mesh).items()})
    return part


def analyse_as_built(case, params, *, pressures=None, kinds=None, order: int | None = None,
                     out=None, quiet: bool = False, time_limit: float = TIME_LIMIT,
                     contact: bool = False) -> int:
    """``pacto analyse CASE --as-built``: the case's geometry (with ``params``: ``--set``,
    ``--model``, ``--maxh``) analysed as its part (the module docstring), written to ``out``
    (default ``output/CASE-as-built``).  Returns the exit code (0)."""
    t0 = time.perf_counter()
    if kinds is not None and "darcy" in kinds:
        raise InputError("--kinds: darcy is the Darcy pressure of a design; a part as built "
                         "takes the pressure on its inlet walls (fixed, follower)")
    kinds = check_kinds(KINDS if kinds is None else kinds, KINDS)
    params = case.resolve(params)  # a mesh size the case does not give: derived
    setup = case.make_setup(params)
    if setup.pressure is None:
        raise InputError(f"analyse: case '{case.name}' has no pressure load: as built, the "
                         f"pressure acts on its inlet walls")
    if not setup.ports:
        raise InputError(f"analyse: case '{case.name}' has no output port")
    inlet = tuple(params.inlet.split("|")) if params.inlet else tuple(setup.pressure.inlet)
    analysis_params(params, None, order or 1)  # a bad --order or model: before meshing
    with compute():
        meshed = mesh_for(case, params)
    mesh, h, dim = meshed.mesh, float(meshed.h), meshed.mesh.dim
    params = analysis_params(params, None, order or DEFAULT_ORDER[dim])
    pressures = default_pressures(params.load) if pressures is None else list(pressures)
    _say(quiet, f"analyse {case.name} as built: model {params.model}"
                + (f", material {params.material}" if params.material else "")
                + f", order {params.order}, reference load {params.load:g} {case.load_unit}")
    part = as_built_part(mesh, setup, inlet, params.order)
    solver = "umfpack" if "follower" in kinds else "sparsecholesky"
    est = resources.estimate_mesh(part.mesh, params.order, solver=solver)
    seconds = check_resources(est, f"--maxh = {params.maxh:g}", dim=dim, kinds=kinds,
                              n_pressures=len(pressures), model=params.model,
                              mesh_time_limit=params.mesh_time_limit, time_limit=time_limit)
    _say(quiet, f"  the part: {part.mesh.ne} elements, {est.dofs:.3g} dofs, "
                f"{part.measure:.4g} {'m²' if dim == 2 else 'm³'}, wetted {part.wetted:.4g} "
                f"{'m' if dim == 2 else 'm²'}; " + _chamber_line(part.seal)
                + f"; the analysis about {seconds:.3g} s")
    out = Path(out) if out else Path("output") / f"{case.name}-as-built"
    run = {"as_built": True, "dir": str(out), "case": case.name, "case_file": case.file or None,
           "model": params.model, "load": float(params.load), "load_unit": case.load_unit,
           "mesh_h": h, "dim": dim, "load_path_note": None}
    subject = Subject(case, params, setup, mesh, part, out, run, h,
                      measures={"part": part.measure, "wetted": part.wetted},
                      contact=contact, time_limit=time_limit)
    if not part.seal.sealed:
        subject.warnings.append("the inlet walls do not bound a closed chamber: "
                                + _chamber_line(part.seal) + "; the pressure is applied to "
                                "the walls as if the chamber held it")
    return finish(subject, kinds, pressures, dict(threshold=None, threshold_choice=None,
                                                  threshold2=None, maxh=float(params.maxh)),
                  quiet=quiet, t0=t0)


def _chamber_line(seal) -> str:
    if not seal.chambers:
        return "no chamber (the inlet is on the part's outer boundary)"
    return "; ".join(
        f"chamber '{c.name}' closed" if c.sealed else
        f"chamber '{c.name}' OPEN to '{c.boundary}' near ("
        + ", ".join(f"{v:.3g}" for v in c.opening) + ")" for c in seal.chambers)


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)
