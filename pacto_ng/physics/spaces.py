"""The unknowns' spaces of a mechanics block (:class:`~pacto_ng.physics.mechanics.Mechanics`):
the displacement's ``VectorH1`` with the regions the block's
:class:`~pacto_ng.physics.mechanics.Supports` name as Dirichlet conditions, and the mixed
formulation's ``(u, ϑ, p̃)`` (:mod:`~pacto_ng.physics.mixed`)."""
from __future__ import annotations

import numpy as np

from ..parallel import total
from .mixed import Mixed


def dirichlet_options(mesh, supports) -> dict:
    """The ``VectorH1`` options ``dirichlet{x,y,z}{,_bbnd,_bbbnd}`` that fix, per component,
    the regions ``supports`` names (boundaries, then in 2D points or in 3D edges, then in 3D
    points); ValueError for a name that is no region of ``mesh``."""
    # the named regions by codimension: boundaries, then (2D) points or (3D) edges, then
    # (3D) points
    regions = {"": mesh.GetBoundaries(), "_bbnd": mesh.GetBBoundaries()}
    if mesh.dim == 3:
        regions["_bbbnd"] = mesh.GetBBBoundaries()
    for name in supports.names():
        if not any(name in known for known in regions.values()):
            raise ValueError(f"support region '{name}' is not a boundary, edge or point of "
                             f"the mesh")
    kw = {}
    for axis, names in zip("xyz", supports.per_component(mesh.dim)):
        for suffix, known in regions.items():
            on = [n for n in names if n in known]
            if on:
                kw[f"dirichlet{axis}{suffix}"] = "|".join(on)
    return kw


def block_spaces(mesh, order: int, supports, formulation: str) -> tuple:
    """``(kw, fes, mixed, space)``: the displacement space ``fes`` (``VectorH1`` of ``order``
    with the options ``kw``), the :class:`~pacto_ng.physics.mixed.Mixed` formulation or None,
    and the unknowns' space (``fes``, or the mixed formulation's).  ValueError for an unknown
    formulation or a structure without supports."""
    from ngsolve import VectorH1

    kw = dirichlet_options(mesh, supports)
    if formulation not in ("displacement", "mixed"):
        raise ValueError(f"formulation must be 'displacement' or 'mixed' (got "
                         f"'{formulation}')")
    if formulation == "mixed":
        kw.update(Mixed.displacement_options(mesh, order))
    fes = VectorH1(mesh, order=order, **kw)
    if total(mesh, np.count_nonzero(~np.array(list(fes.FreeDofs()), dtype=bool))) == 0:
        raise ValueError("the structure has no supports: add a clamp or fixed boundary")
    if formulation == "mixed":
        mixed = Mixed(mesh, fes, order)
        return kw, fes, mixed, mixed.space
    return kw, fes, None, fes
