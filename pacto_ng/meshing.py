"""A case's geometry meshed (:func:`mesh_geometry`): its mesh settings (:class:`MeshSettings`),
the mesh size derived where a case gives none (:func:`derived_maxh`), the element size before
meshing (:func:`element_size`), and the check of a mesh against this machine's resources
before it is made (:mod:`pacto_ng.resources`).  What the geometry
may be: :mod:`pacto_ng.geometry`.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from . import resources
from .box import Box, box_shape, netgen_box_mesh, structured_box
from .errors import InputError
from .geometry import (CAD_SUFFIXES, MESH_SUFFIXES, bounding_sides, extent, is_occ_shape,
                       is_solid, load_cad, load_mesh)
from .mesh import Layout, Meshed, layout_shape, netgen_mesh, structured_mesh
from .settings import Settings, setting


@dataclass(frozen=True)
class MeshSettings(Settings):
    """How the case's geometry is meshed, and the displacement's element order."""

    maxh: float = setting(0.01, "m", "Netgen element size, triangles or tetrahedra (used when "
                          "nelx = 0)", range="(0, inf)")
    nelx: int = setting(0, "", "structured quads (hexahedra) in x (0: Netgen elements)",
                        range="[0, 100000]")
    nely: int = setting(0, "", "structured quads (hexahedra) in y", range="[0, 100000]")
    nelz: int = setting(0, "", "structured hexahedra in z (a Box; 0 for a 2D domain)",
                        range="[0, 100000]")
    order: int = setting(0, "", "element order of the displacement (1, 2, 3; 0: the case's "
                         "order for the model, see Case.model_orders)", choices=(0, 1, 2, 3))
    unit_elements: bool = setting(False, "", "structured mesh of unit square elements (domain "
                                  "nelx x nely)")
    mesh_time_limit: float = setting(resources.MESH_TIME_LIMIT, "s", "refuse, before "
                                     "meshing, a mesh estimated to take longer to make "
                                     "(pacto_ng/resources.py)", range="(0, inf)")

    def check(self):
        if (self.nelx > 0) != (self.nely > 0):
            raise InputError("nelx, nely: give both (positive) or neither")
        if self.nelz > 0 and self.nelx == 0:
            raise InputError("nelz: needs nelx and nely (a structured hexahedral mesh)")
        if self.unit_elements and self.nelx == 0:
            raise InputError("unit_elements: needs a structured mesh (give --nelx and --nely)")


#: a derived mesh size (``maxh`` given neither by the case nor by the user): this many elements
#: across the smallest side of the domain's bounding box, in 2D and in 3D ...
ACROSS_2D = 30
ACROSS_3D = 10
#: ... coarsened where that would make more elements than this (Netgen's estimate,
#: :mod:`pacto_ng.resources`): a run at defaults stays within minutes (2D: about 0.1 s per
#: linear iteration at 10k triangles here; 3D: the 12-18k-tetrahedron built-in cases take
#: 1-4 min for 150-300 iterations, docs/studies.md)
MAX_DERIVED_TRIANGLES = 40_000
MAX_DERIVED_TETS = 20_000
#: ... and at least this many elements across a filter radius the case gives (the built-in
#: cases have 2.5-4: soft-finger 2.5, pa-inverter 3, pneunet-3d 4)
ACROSS_FILTER = 2.5


def _element_count(geometry):
    """Netgen's element count at a mesh size, as a function of it, for a geometry that Netgen
    meshes (:mod:`pacto_ng.resources`); None for one it cannot (a shape without faces)."""
    if isinstance(geometry, Layout):
        return lambda h: resources.netgen_elements(geometry.width * geometry.height, h, 2)
    if isinstance(geometry, Box):
        return lambda h: resources.netgen_elements(float(np.prod(geometry.size)), h, 3)
    if is_occ_shape(geometry) and len(geometry.faces) > 0:
        return lambda h: resources.shape_elements(geometry, h)
    return None


def derived_maxh(geometry, filter_radius: float = 0.0) -> tuple[float, str] | None:
    """The mesh size of a case that gives none: ``(maxh, how)``, or None where ``maxh`` does
    not apply (a mesh, a mesh file).

    ``side / ACROSS_2D`` (2D) or ``side / ACROSS_3D`` (3D), ``side`` the smallest side of the
    bounding box, or ``filter_radius / ACROSS_FILTER`` where a given filter radius asks for
    finer elements; coarsened to about ``MAX_DERIVED_TRIANGLES`` triangles or
    ``MAX_DERIVED_TETS`` tetrahedra where it would make more (but never coarser than a quarter
    of ``side``), rounded to 3 significant digits."""
    if isinstance(geometry, (str, os.PathLike)) and str(geometry).lower().endswith(CAD_SUFFIXES):
        geometry = load_cad(geometry)
    sides, count = bounding_sides(geometry), _element_count(geometry)
    if sides is None or count is None or not min(sides) > 0:
        return None
    dim, side = len(sides), min(sides)
    across = ACROSS_2D if dim == 2 else ACROSS_3D
    cap, kind = ((MAX_DERIVED_TRIANGLES, "triangles") if dim == 2 else
                 (MAX_DERIVED_TETS, "tetrahedra"))
    maxh = side / across
    how = f"derived: {across} elements across {side:.3g} m"
    if 0 < filter_radius < ACROSS_FILTER * maxh:
        maxh = filter_radius / ACROSS_FILTER
        how = f"derived: {ACROSS_FILTER:g} elements across the filter radius {filter_radius:.3g} m"
    n = count(maxh)
    if n > cap:  # the count scales as maxh^-dim
        maxh = min(maxh * (n / cap) ** (1.0 / dim), side / 4.0)
        how += f", coarsened to about {cap} {kind}"
    return float(f"{maxh:.3g}"), how


def element_size(geometry, *, maxh: float, nelx: int = 0, nely: int = 0,
                 nelz: int = 0) -> float | None:
    """The element size ``h`` that :func:`mesh_geometry` will give
    (:attr:`~pacto_ng.mesh.Meshed.h`) with these mesh options, before meshing; None for a mesh
    or a mesh file (its mean element size is known once it is read)."""
    if isinstance(geometry, Box) and nelx > 0 and nelz > 0:
        return float(min(geometry.size / np.array((nelx, nely, nelz))))
    if isinstance(geometry, Layout) and nelx > 0:
        return min(geometry.width / nelx, geometry.height / nely)
    if nelx > 0:
        return None  # refused by mesh_geometry
    if isinstance(geometry, (Layout, Box)) or is_occ_shape(geometry):
        return maxh
    if isinstance(geometry, (str, os.PathLike)) and str(geometry).lower().endswith(CAD_SUFFIXES):
        return maxh
    return None


def mesh_geometry(geometry, *, maxh: float, nelx: int = 0, nely: int = 0, nelz: int = 0,
                  order: int = 1, mesh_time_limit: float = resources.MESH_TIME_LIMIT,
                  solver: str | None = None, linear_solver: str = "auto") -> Meshed:
    """Mesh a case's geometry (see the module docstring for what it may be).

    Netgen triangles (tetrahedra for a 3D shape or a Box) of size ``maxh``; with ``nelx, nely
    > 0`` structured quads, for a :class:`~pacto_ng.mesh.Layout` only, and with ``nelx, nely,
    nelz > 0`` structured hexahedra, for a :class:`~pacto_ng.box.Box` only.

    Before a mesh is made, its elements, its displacement dofs at ``order`` and a run's memory
    are estimated (:mod:`pacto_ng.resources`; ``solver`` of the
    displacement system, ``sparsecholesky`` or ``umfpack``, None for the larger estimate; in
    3D ``linear_solver``, the ``solver`` setting, decides whether the system is factorised or
    solved iteratively, :func:`pacto_ng.resources.route`): a mesh that would not fit this
    machine's memory, or would take Netgen (or the grid builder)
    longer than ``mesh_time_limit`` seconds to make, is refused with one line.  A mesh file or
    an ``ngsolve.Mesh`` is checked on its own counts."""
    import ngsolve

    geometry, source = _read_file(geometry)
    if isinstance(geometry, Box):
        return _mesh_box(geometry, maxh, (nelx, nely, nelz), order, mesh_time_limit,
                         dict(solver=solver, linear_solver=linear_solver))
    if nelz > 0:
        raise InputError("nelz: structured hexahedra need a box domain (a Box); this case's "
                         "geometry is not one (give --maxh instead)")
    if nelx > 0 and not isinstance(geometry, Layout):
        raise InputError("nelx, nely: structured quads need a rectangular domain (a Layout); "
                         "this case's geometry is not one (give --maxh instead)")
    fits = _fits(mesh_time_limit)
    if isinstance(geometry, ngsolve.Mesh):
        mesh = _checked_mesh(geometry)
        fits(resources.estimate_mesh(mesh, order, solver=solver, linear_solver=linear_solver),
             source,
             "give a coarser mesh or a lower order")
        return Meshed(mesh, _mean_size(mesh), None)
    if isinstance(geometry, Layout):
        return _mesh_layout(geometry, maxh, nelx, nely, order, fits, solver)
    if is_occ_shape(geometry):
        return _mesh_shape(geometry, maxh, order, fits, solver, linear_solver)
    raise InputError(f"geometry: got a {type(geometry).__name__}; a case's geometry must be a "
                     "netgen.occ shape, a Layout, a Box, a CAD or mesh file path, or an "
                     "ngsolve.Mesh")


#: what a refused Netgen mesh says to do
_FINER = "give a larger maxh or a lower order"


def _fits(mesh_time_limit: float):
    """``fits(estimate, what, advice)``: refuse, with one line, a mesh that would not fit this
    machine's memory or would take longer than ``mesh_time_limit`` to make
    (:func:`pacto_ng.resources.check`)."""
    def fits(estimate, what, advice):
        resources.check(estimate, what, mesh_time_limit=mesh_time_limit, advice=advice)

    return fits


def _read_file(geometry) -> tuple:
    """``(geometry, source)``: a CAD file's shape or a mesh file's mesh for a path (the
    geometry itself otherwise), and how a refused mesh names it."""
    if not isinstance(geometry, (str, os.PathLike)):
        return geometry, "the mesh"
    low = str(geometry).lower()
    if low.endswith(CAD_SUFFIXES):
        return load_cad(geometry), "the mesh"
    if low.endswith(MESH_SUFFIXES):
        return load_mesh(geometry), f"mesh file '{geometry}'"
    raise InputError(f"geometry: '{geometry}' is neither a CAD file "
                     f"({', '.join(CAD_SUFFIXES)}) nor a mesh file "
                     f"({', '.join(MESH_SUFFIXES)})")


def _mesh_layout(layout: Layout, maxh, nelx, nely, order, fits, solver) -> Meshed:
    """A Layout as structured quads (``nelx, nely > 0``) or Netgen triangles of ``maxh``,
    checked by ``fits`` (:func:`_fits`) first."""
    if nelx > 0:
        fits(resources.estimate_grid((nelx, nely), order, solver=solver),
             f"nelx x nely = {nelx} x {nely}", "give a smaller nelx, nely or order")
        mesh = structured_mesh(layout, nelx, nely)
        return Meshed(mesh, min(layout.width / nelx, layout.height / nely), None)
    _check_maxh(maxh, min(layout.width, layout.height))
    triangles = resources.netgen_elements(layout.width * layout.height, maxh, 2)
    fits(resources.estimate_netgen(triangles, order, 2, solver=solver), f"maxh = {maxh:g}",
         _FINER)
    return Meshed(netgen_mesh(layout, maxh), maxh, layout_shape(layout))


def _mesh_shape(shape, maxh, order, fits, solver, linear_solver) -> Meshed:
    """A netgen.occ shape as Netgen tetrahedra (a solid) or triangles of ``maxh``, checked by
    ``fits`` (:func:`_fits`) first."""
    import ngsolve
    from netgen import occ

    solid = is_solid(shape)
    if len(shape.faces) == 0:
        raise InputError("geometry: the shape has no face to mesh")
    _check_maxh(maxh, extent(shape))
    fits(resources.estimate_netgen(resources.shape_elements(shape, maxh), order,
                                   3 if solid else 2, solver=solver,
                                   linear_solver=linear_solver), f"maxh = {maxh:g}", _FINER)
    try:
        ngm = occ.OCCGeometry(shape, dim=3 if solid else 2).GenerateMesh(maxh=maxh)
    except RuntimeError as err:
        raise InputError(f"geometry: Netgen could not mesh the shape at maxh = {maxh:g} "
                         f"({err})") from None
    return Meshed(_checked_mesh(ngsolve.Mesh(ngm)), maxh, shape)


def _mesh_box(box: Box, maxh, nel, order, mesh_time_limit, solvers: dict) -> Meshed:
    """A Box as Netgen tetrahedra of ``maxh`` or, with ``nel`` = (nelx, nely, nelz) > 0,
    structured hexahedra; checked against this machine's resources first (``solvers``: the
    estimates' ``solver`` and ``linear_solver``)."""
    fits = _fits(mesh_time_limit)
    nelx, nely, nelz = nel
    if nelx > 0:
        if nelz == 0:
            raise InputError("nelz: a box domain (3D) meshed as hexahedra needs nelx, nely and "
                             "nelz")
        fits(resources.estimate_grid(nel, order, **solvers),
             f"nelx x nely x nelz = {nelx} x {nely} x {nelz}",
             "give a smaller nelx, nely, nelz or order")
        mesh = structured_box(box, nelx, nely, nelz)
        return Meshed(mesh, float(min(box.size / np.array(nel))), None)
    _check_maxh(maxh, float(box.size.min()))
    tets = resources.netgen_elements(float(np.prod(box.size)), maxh, 3)
    fits(resources.estimate_netgen(tets, order, 3, **solvers), f"maxh = {maxh:g}", _FINER)
    return Meshed(netgen_box_mesh(box, maxh), maxh, box_shape(box))


def _check_maxh(maxh: float, extent: float) -> None:
    if maxh > 0.5 * extent:
        raise InputError(f"maxh: {maxh:g} is too coarse for a domain {extent:g} across")


def _checked_mesh(mesh):
    if mesh.dim not in (2, 3):
        raise InputError(f"geometry: a {mesh.dim}D mesh; a domain is 2D or 3D")
    if mesh.ne == 0:
        raise InputError("geometry: the mesh has no element")
    return mesh


def _mean_size(mesh) -> float:
    """The side of the right isosceles triangle (2D) or the cube's sixth, a tetrahedron (3D),
    of the mean element's area or volume."""
    from ngsolve import Integrate

    if mesh.dim == 3:
        return float((6.0 * Integrate(1.0, mesh) / mesh.ne) ** (1.0 / 3.0))
    return float(np.sqrt(2.0 * Integrate(1.0, mesh) / mesh.ne))
