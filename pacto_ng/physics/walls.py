"""The loads on a part's walls: a pressure fixed or following the deformation, and a design's
Darcy pressure field as a body force, with the outward normal they need.

Loads, on the wall ``Γp`` (``boundary``) with ``N0`` the outward unit normal of the solid
(:func:`outward_normal`), or in the volume, with the pressure ``P`` as the load factor of
:class:`~pacto_ng.physics.mechanics.Mechanics`:

``fixed``
    deformation independent, the potential term ``-t ∫_Γp P N0 · u dA0``: the residual gains
    ``t ∫ P N0 · v dA0``, the traction ``-P N0`` pushes into the solid.  A linear model is one
    linear solve per pressure (the block's linear route).
``follower``
    the pressure on the deformed wall, ``-P n da = -P cof(F) N0 dA0`` (Nanson's formula,
    ``cof F = J F⁻ᵀ``; Bonet and Wood 2008, *Nonlinear continuum mechanics for finite element
    analysis*, 2nd ed., the area change and the linearised work of a follower pressure; docs/
    theory.md §4): the residual gains ``t ∫_Γp P cof(F̃) N0 · v dA0`` with
    ``F̃ = I + ∇_Γ u`` (``Grad(u).Trace()``, the surface gradient, the only gradient NGSolve
    gives on a boundary).  It is exact: ``F̃ T = F T`` on every tangent ``T`` and ``F̃ N0 =
    N0``, and ``cof(A) N0`` depends only on ``A T`` -- in 3D ``cof(F̃) N0 = F T1 × F T2`` for
    tangents with ``T1 × T2 = N0``, in 2D ``cof(A) = R A Rᵀ`` (``R = ((0, 1), (-1, 0))``)
    gives ``cof(F̃) N0 = R F T`` for ``N0 = R T``, the identity ``J F⁻ᵀ N0 = Rot(F T)``
    (docs/theory.md §4).  In plane stress the change of thickness is not followed.  Not the
    derivative of a potential: a residual term, with its load stiffness from
    ``AssembleLinearization`` (an unsymmetric tangent); Newton for every model.
``darcy``
    a Darcy pressure field ``p`` of the design (thesis §6.1.1, "deformation-independent load
    analysis"; docs/theory.md §4) as the body force ``-∇p`` on the part, scaled with
    ``P / P_in``: the residual gains ``-t ∫ (P/P_in) (-∇p) · v dΩ0``.  ``p`` is a field at inlet
    pressure ``P_in`` on any mesh (the design's, on which the Darcy block solved it), set onto
    an H1 space of the part (:func:`pressure_body_force`: NGSolve's ``Set`` evaluates a field
    of another mesh by point search) and differentiated there.  Deformation independent and
    conservative: a linear model is one linear solve per pressure, as ``fixed``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from ngsolve import (BND, H1, Cof, CoefficientFunction, FacetFESpace, Grad, GridFunction, Id,
                     Integrate, LinearForm, ds, dx, specialcf, x, y, z)


def outward_normal(mesh, boundary: str):
    """The outward unit normal ``N0`` of the solid on ``boundary`` (a CF for ``ds``).

    NGSolve orients a boundary element's normal by the element's own orientation: on the edges
    of a hole in 2D it points into the body.  The sign is decided per facet, all at once: on a
    facet of the boundary ``∫ n_T dA`` of its one volume element ``T`` (``dx(element_boundary
    =True)``, the element's outward normal) equals ``±∫ n dA`` of the boundary element; the
    sign of their dot product, on ``FacetFESpace(order=0)``, multiplies
    ``specialcf.normal(d)``.  ValueError if a facet of ``boundary`` lies inside the mesh
    (its two elements' normals cancel): a wall must bound the solid.
    """
    fes = FacetFESpace(mesh, order=0)
    dot, size = _facet_orientation(fes, _element_normals(fes), boundary)
    on = size > 0
    if np.any(np.abs(dot[on]) < 0.5 * size[on]):
        raise ValueError(f"boundary '{boundary}' runs inside the part: the pressure must act on "
                         f"walls that bound the solid")
    sign = GridFunction(fes)
    sign.vec.FV().NumPy()[:] = np.where(dot < 0.0, -1.0, 1.0)
    return sign * specialcf.normal(mesh.dim)


def _element_normals(fes) -> list:
    """Per facet of ``fes`` (``FacetFESpace(order=0)``), each component of ``∫ n_T dA`` of
    the volume elements beside it (0 on an interior facet, whose two sides cancel)."""
    q, n = fes.TestFunction(), specialcf.normal(fes.mesh.dim)
    return [LinearForm(n[i] * q * dx(element_boundary=True)).Assemble().vec.FV().NumPy()
            for i in range(fes.mesh.dim)]


def _facet_orientation(fes, elem, boundary: str):
    """Per facet of ``fes``: the dot product of the volume elements' normals ``elem``
    (:func:`_element_normals`) with ``∫ n dA`` of ``boundary``'s element on it, and the
    latter's squared size (0 off the boundary; see :func:`outward_normal`)."""
    q, n = fes.TestFunction(), specialcf.normal(fes.mesh.dim)
    wall = [LinearForm(n[i] * q * ds(boundary)).Assemble().vec.FV().NumPy()
            for i in range(fes.mesh.dim)]
    return sum(a * b for a, b in zip(elem, wall)), sum(b * b for b in wall)


def solid_boundaries(mesh) -> tuple[str, ...]:
    """The named boundaries of ``mesh`` whose every facet bounds the solid (not an interface
    between two of its domains), sorted: the surfaces that can come into contact."""
    fes = FacetFESpace(mesh, order=0)
    elem = _element_normals(fes)
    out = []
    for name in sorted(set(mesh.GetBoundaries())):
        dot, size = _facet_orientation(fes, elem, name)
        on = size > 0
        if np.any(on) and np.all(np.abs(dot[on]) >= 0.5 * size[on]):
            out.append(name)
    return tuple(out)


@dataclass(frozen=True)
class WallPressure:
    """The fixed wall pressure as a load of :class:`~pacto_ng.physics.mechanics.Mechanics`:
    work ``W(u) = -t ∫ p N0 · u dA0`` (``p`` the pressure per unit load factor, ``N0`` from
    :func:`outward_normal`)."""

    boundary: str
    pressure: object
    thickness: float
    normal: object

    def work(self, mesh, u, scale=1.0):
        return (scale * (-self.thickness) * self.pressure * (self.normal * u)) * ds(self.boundary)


def follower_terms(boundary: str, pressure, thickness: float, normal, dim: int) -> Callable:
    """Residual terms ``(u, v, s) -> s t ∫ p cof(I + ∇_Γ u) N0 · v dA0`` on a mesh of
    dimension ``dim`` (see the module)."""
    def terms(u, v, load):
        Ft = Id(dim) + Grad(u).Trace()
        return (load * thickness * pressure * ((Cof(Ft) * normal) * v)) * ds(boundary)

    return terms


def volume_change(u, boundary: str, normal, thickness: float, origin) -> float:
    """The change of the volume the wall ``boundary`` encloses (a chamber, in 2D its area
    times ``thickness``) under the displacement ``u`` (a GridFunction), by Nanson's formula
    on the reference wall: ``ΔV = -(t/d) ∫_Γ [(X - x0 + u) · cof(F̃) N0 - (X - x0) · N0] dA0``
    (``N0`` the solid's outward normal, into the chamber; ``F̃`` as for the follower load).
    The chamber's other faces contribute nothing where they are planes through ``origin``
    ``x0`` (symmetry planes: give a point on all of them) or held fixed (a clamp)."""
    mesh = u.space.mesh
    d = mesh.dim
    X = CoefficientFunction((x, y, z)[:d]) - CoefficientFunction(tuple(origin))
    Ft = Id(d) + Grad(u).Trace()
    change = (X + u) * (Cof(Ft) * normal) - X * normal
    order = 2 * u.space.globalorder + 2
    return float(-thickness / d * Integrate(change, mesh, BND, order=order,
                                              definedon=mesh.Boundaries(boundary)))


def held_planes_origin(mesh, held) -> tuple:
    """A point on every region held in one direction, ``held`` = the region names held in x,
    in y (and in z): symmetry planes.  Per axis the mean coordinate of its regions' vertices
    (0 where none): the origin of :func:`volume_change`."""
    out = np.zeros(mesh.dim)
    for axis, names in enumerate(tuple(held)[:mesh.dim]):
        on = [mesh[v].point[axis] for el in mesh.Elements(BND) if el.mat in names
              for v in el.vertices]
        if on:
            out[axis] = float(np.mean(on))
    return tuple(out)


def pressure_body_force(p, order: int = 1) -> Callable:
    """A body-force callable ``mesh -> -∇p`` for the ``darcy`` kind.

    ``p`` is a pressure field (a GridFunction or CF, e.g. the Darcy pressure of the thresholded
    design on the design's mesh at inlet pressure ``P_in``, which the analysis then takes as
    ``body_pressure``); it is set onto an H1 space of ``order`` on the part's mesh (NGSolve's
    ``Set`` evaluates a field of another mesh by point search; a point a little outside it,
    as the smoothed 3D part's, takes the nearest element's value) and differentiated there.
    """

    def body(mesh):
        gp = GridFunction(H1(mesh, order=order))
        gp.Set(p)
        return -Grad(gp)

    return body
