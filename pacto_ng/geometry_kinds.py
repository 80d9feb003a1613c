"""Each kind of geometry a case may give (:mod:`pacto_ng.geometry`) tells what it is before it
is meshed and meshes itself: :func:`kind_of` reads a file and picks the kind, once.

========================  =================================================================
kind                      what it is
========================  =================================================================
:class:`LayoutKind`       a rectangle with regions (:class:`~pacto_ng.mesh.Layout`): Netgen
                          triangles, or structured quads with ``nelx``, ``nely``
:class:`BoxKind`          a box with regions (:class:`~pacto_ng.box.Box`): Netgen tetrahedra,
                          or structured hexahedra with ``nelx``, ``nely``, ``nelz``
:class:`ShapeKind`        a netgen.occ shape, or a CAD file's: Netgen triangles (tetrahedra
                          for a solid)
:class:`MeshKind`         an ``ngsolve.Mesh``, or a mesh file's: used as it is
========================  =================================================================

Every kind gives ``sides`` (its bounding box's, None for a mesh), ``count(h)`` (Netgen's
element count at the size ``h``, None for a kind Netgen does not mesh), ``element_size`` (the
``h`` a mesh with these options will have, before meshing) and ``mesh`` (checked against this
machine's resources first, :mod:`pacto_ng.resources`).
"""
from __future__ import annotations

import os

import ngsolve
import numpy as np
from netgen import occ

from . import resources
from .box import Box, box_shape, netgen_box_mesh, structured_box
from .errors import InputError
from .geometry import CAD_SUFFIXES, MESH_SUFFIXES, is_occ_shape, is_solid, load_cad, load_mesh
from .mesh import Layout, Meshed, layout_shape, netgen_mesh, structured_mesh

#: what a refused Netgen mesh says to do
FINER = "give a larger maxh or a lower order"


class Checks:
    """What a mesh is checked against before it is made: ``fits(estimate, what, advice)``
    refuses, with one line, a mesh that would not fit this machine's memory or would take
    longer than ``mesh_time_limit`` to make; ``solver``, ``linear_solver``: the estimates'
    (:func:`pacto_ng.resources.estimate_netgen`)."""

    def __init__(self, mesh_time_limit: float, solver: str | None, linear_solver: str):
        self.mesh_time_limit = mesh_time_limit
        self.solver, self.linear_solver = solver, linear_solver

    def fits(self, estimate, what: str, advice: str) -> None:
        resources.check(estimate, what, mesh_time_limit=self.mesh_time_limit, advice=advice)


class LayoutKind:
    def __init__(self, layout: Layout):
        self.layout = layout
        self.sides = (float(layout.width), float(layout.height))

    def count(self, h: float) -> float:
        return resources.netgen_elements(self.layout.width * self.layout.height, h, 2)

    def element_size(self, maxh: float, nel: tuple) -> float:
        nelx, nely, _ = nel
        return min(self.layout.width / nelx, self.layout.height / nely) if nelx > 0 else maxh

    def mesh(self, maxh: float, nel: tuple, order: int, checks: Checks) -> Meshed:
        (nelx, nely, nelz), layout = nel, self.layout
        _refuse_hexahedra(nelz)
        if nelx > 0:
            checks.fits(resources.estimate_grid((nelx, nely), order, solver=checks.solver),
                        f"nelx x nely = {nelx} x {nely}", "give a smaller nelx, nely or order")
            return Meshed(structured_mesh(layout, nelx, nely), self.element_size(maxh, nel),
                          None)
        _check_maxh(maxh, min(self.sides))
        checks.fits(resources.estimate_netgen(self.count(maxh), order, 2, solver=checks.solver),
                    f"maxh = {maxh:g}", FINER)
        return Meshed(netgen_mesh(layout, maxh), maxh, layout_shape(layout))


class BoxKind:
    def __init__(self, box: Box):
        self.box = box
        self.sides = tuple(float(v) for v in box.size)

    def count(self, h: float) -> float:
        return resources.netgen_elements(float(np.prod(self.box.size)), h, 3)

    def element_size(self, maxh: float, nel: tuple) -> float | None:
        if nel[0] > 0:
            return float(min(self.box.size / np.array(nel))) if nel[2] > 0 else None
        return maxh

    def mesh(self, maxh: float, nel: tuple, order: int, checks: Checks) -> Meshed:
        solvers = dict(solver=checks.solver, linear_solver=checks.linear_solver)
        if nel[0] > 0:
            if nel[2] == 0:
                raise InputError("nelz: a box domain (3D) meshed as hexahedra needs nelx, nely "
                                 "and nelz")
            checks.fits(resources.estimate_grid(nel, order, **solvers),
                        "nelx x nely x nelz = {} x {} x {}".format(*nel),
                        "give a smaller nelx, nely, nelz or order")
            return Meshed(structured_box(self.box, *nel), self.element_size(maxh, nel), None)
        _check_maxh(maxh, min(self.sides))
        checks.fits(resources.estimate_netgen(self.count(maxh), order, 3, **solvers),
                    f"maxh = {maxh:g}", FINER)
        return Meshed(netgen_box_mesh(self.box, maxh), maxh, box_shape(self.box))


class ShapeKind:
    def __init__(self, shape):
        self.shape, self.solid = shape, is_solid(shape)
        lo, hi = shape.bounding_box
        self.sides = tuple(float(hi[a] - lo[a]) for a in range(3 if self.solid else 2))

    def count(self, h: float) -> float | None:
        return resources.shape_elements(self.shape, h) if len(self.shape.faces) > 0 else None

    def element_size(self, maxh: float, nel: tuple) -> float | None:
        return maxh if nel[0] == 0 else None

    def mesh(self, maxh: float, nel: tuple, order: int, checks: Checks) -> Meshed:
        _refuse_grid(nel)
        if len(self.shape.faces) == 0:
            raise InputError("geometry: the shape has no face to mesh")
        _check_maxh(maxh, min(self.sides))
        checks.fits(resources.estimate_netgen(self.count(maxh), order, 3 if self.solid else 2,
                                              solver=checks.solver,
                                              linear_solver=checks.linear_solver),
                    f"maxh = {maxh:g}", FINER)
        try:
            ngm = occ.OCCGeometry(self.shape, dim=3 if self.solid else 2).GenerateMesh(
                maxh=maxh)
        except RuntimeError as err:
            raise InputError(f"geometry: Netgen could not mesh the shape at maxh = {maxh:g} "
                             f"({err})") from None
        return Meshed(_checked_mesh(ngsolve.Mesh(ngm)), maxh, self.shape)


class MeshKind:
    sides = None  # a mesh's size is known once it is read; maxh does not apply

    def __init__(self, mesh, source: str):
        self.given, self.source = mesh, source

    @staticmethod
    def count(h: float) -> None:
        return None

    @staticmethod
    def element_size(maxh: float, nel: tuple) -> None:
        return None

    def mesh(self, maxh: float, nel: tuple, order: int, checks: Checks) -> Meshed:
        _refuse_grid(nel)
        mesh = _checked_mesh(self.given)
        checks.fits(resources.estimate_mesh(mesh, order, solver=checks.solver,
                                            linear_solver=checks.linear_solver),
                    self.source, "give a coarser mesh or a lower order")
        return Meshed(mesh, _mean_size(mesh), None)


def kind_of(geometry):
    """The kind of a case's geometry (see the module), a CAD or mesh file read."""
    if isinstance(geometry, (str, os.PathLike)):
        low = str(geometry).lower()
        if low.endswith(CAD_SUFFIXES):
            return ShapeKind(load_cad(geometry))
        if low.endswith(MESH_SUFFIXES):
            return MeshKind(load_mesh(geometry), f"mesh file '{geometry}'")
        raise InputError(f"geometry: '{geometry}' is neither a CAD file "
                         f"({', '.join(CAD_SUFFIXES)}) nor a mesh file "
                         f"({', '.join(MESH_SUFFIXES)})")
    if isinstance(geometry, Layout):
        return LayoutKind(geometry)
    if isinstance(geometry, Box):
        return BoxKind(geometry)
    if is_occ_shape(geometry):
        return ShapeKind(geometry)
    if isinstance(geometry, ngsolve.Mesh):
        return MeshKind(geometry, "the mesh")
    raise InputError(f"geometry: got a {type(geometry).__name__}; a case's geometry must be a "
                     "netgen.occ shape, a Layout, a Box, a CAD or mesh file path, or an "
                     "ngsolve.Mesh")


def bounding_sides(geometry) -> tuple[float, ...] | None:
    """The sides of the bounding box of a geometry that Netgen meshes (two in 2D, three in
    3D), None for a mesh or a mesh file."""
    return kind_of(geometry).sides


def extent(geometry) -> float | None:
    """The smallest side of the geometry's bounding box (None for a mesh or a mesh file)."""
    sides = bounding_sides(geometry)
    return None if sides is None else min(sides)


def _refuse_hexahedra(nelz: int) -> None:
    if nelz > 0:
        raise InputError("nelz: structured hexahedra need a box domain (a Box); this case's "
                         "geometry is not one (give --maxh instead)")


def _refuse_grid(nel: tuple) -> None:
    _refuse_hexahedra(nel[2])
    if nel[0] > 0:
        raise InputError("nelx, nely: structured quads need a rectangular domain (a Layout); "
                         "this case's geometry is not one (give --maxh instead)")


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
    if mesh.dim == 3:
        return float((6.0 * ngsolve.Integrate(1.0, mesh) / mesh.ne) ** (1.0 / 3.0))
    return float(np.sqrt(2.0 * ngsolve.Integrate(1.0, mesh) / mesh.ne))
