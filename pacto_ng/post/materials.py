"""Two materials in the part: the soft and the stiff region of a two-material design
(docs/theory.md §1, thesis eq. 6.1: ``E = (1-ρ̄1^p) E0 + ρ̄1^p [(1-ρ̄2^p) E1 + ρ̄2^p E2]``).

The rule: ρ̄1 is thresholded as for one material (:func:`~.threshold.threshold`: the solid is
where the nodal ρ̄1 >= t1, the part kept on the clamp); inside that part, the *stiff* region
(material 2, E2) is where the nodal ρ̄2 (the same area-weighted vertex average) is >= t2, the
*soft* region (material 1, E1) the rest.  ρ̄2 outside the solid plays no part.

The remesh keeps the interface between the two as an internal boundary (:func:`split_part`):
the part's face is cut by the stiff region's face (the thresholded ρ̄2 polygons, moved off the
domain where they run along its boundary, so that the cut never runs along the part's own
boundary), giving faces named ``soft`` and ``stiff`` glued along edges named ``interface``
(a piece of either material smaller than h²/2 or thinner on average than h/2 -- a sliver
between the part's edge and the stiff region's -- joins the material around it);
Netgen meshes both conformingly, so every element carries its material exactly and the
interface is a polyline of element edges (``mode`` ``"body-fitted"``).  Should OCC or Netgen
fail on that geometry, the one-material part is meshed and every element is given the material
of the nodal ρ̄2 interpolated at its centroid (``mode`` ``"element-wise (...)"``: the interface
is a staircase of element edges, not a named boundary).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .domain import BoundaryCurves, material_domain
from .domain_part import build_domain_geometry
from .grid import nodal_density
from .sampler import pressure_sampler
from .threshold import threshold
from .traced import build_geometry

SOFT, STIFF, INTERFACE = "soft", "stiff", "interface"
MATERIALS = (SOFT, STIFF)
#: pieces of one material smaller than this times h², or thinner on average (2 area /
#: perimeter) than this times h (h the source mesh's element size), join the other material
#: (:func:`split_part`)
SLIVER = 0.5


@dataclass(frozen=True, eq=False)
class StiffRegion:
    """ρ̄2 thresholded at ``threshold``: ``thresholded`` is the
    :class:`~.threshold.Thresholded` of ρ̄2 (None when no vertex reaches the threshold: no stiff
    material); ``nodal`` the nodal ρ̄2 on the source mesh's vertices."""

    threshold: float
    thresholded: object
    nodal: np.ndarray


def stiff_region(mesh, rho2, value: float = 0.5, *, exclude=()) -> StiffRegion:
    """Threshold the stiff-material field ρ̄2 at ``value`` (the rule of the module docstring);
    specks smaller than 4 h² are dropped as for ρ̄1."""
    if not (0.0 < float(value) < 1.0):
        raise ValueError(f"threshold2 must lie in (0, 1), got {value!r}")
    nodal = np.asarray(nodal_density(mesh, rho2), dtype=float)
    if float(np.max(nodal)) < float(value):
        return StiffRegion(float(value), None, nodal)
    th = threshold(mesh, rho2, float(value), exclude=exclude)
    return StiffRegion(float(value), th if th.components else None, th.nodal)


def _stiff_shape(stiff: StiffRegion, domain=None):
    """The face of the stiff region: on a domain geometry, the polygons' runs along the
    domain's boundary moved off it (:func:`~.domain_part.build_domain_geometry` without the
    final intersection); else the traced geometry."""
    from netgen import occ

    th = stiff.thresholded
    if domain is not None:
        dom = material_domain(domain, th.excluded)
        curves = BoundaryCurves(dom, 0.05 * th.h)
        bb = dom.bounding_box
        pad = 10.0 * th.h
        box = occ.Rectangle(bb[1][0] - bb[0][0] + 2 * pad, bb[1][1] - bb[0][1] + 2 * pad).Face()
        box = box.Move(occ.Vec(bb[0][0] - pad, bb[0][1] - pad, 0.0))
        shape = build_domain_geometry(th.components, th.h, box, curves=curves)
    else:
        shape = build_geometry(th.components, th.h)
    shape.edges.name = INTERFACE
    return shape


def split_part(part, stiff: StiffRegion, domain=None):
    """The part's shape cut into faces ``soft`` and ``stiff`` glued along ``interface`` edges
    (the part's own edges keep their names).  Returns the shape; a part with no stiff material
    is all ``soft``."""
    from netgen import occ

    if stiff.thresholded is None:
        part.faces.name = SOFT
        return part
    region = _stiff_shape(stiff, domain)
    hard = part * region
    soft = part - region
    # slivers between the two iso-lines (where the stiff region's edge runs close to the
    # part's) leave faces Netgen cannot mesh: a piece of either material smaller than
    # SLIVER h² joins the material around it
    h = stiff.thresholded.h

    def sliver(f):  # small, or thin: mean width 2 area / perimeter
        return f.mass < SLIVER * h * h or 2.0 * f.mass < SLIVER * h * sum(e.mass for e in f.edges)

    tiny_soft = [f for f in soft.faces if sliver(f)]
    tiny_hard = [f for f in hard.faces if sliver(f)]
    if tiny_soft or tiny_hard:
        for f in tiny_soft:
            region = region + f
        for f in tiny_hard:
            region = region - f
        hard = part * region
        soft = part - region
    faces = []
    for piece, name in ((soft, SOFT), (hard, STIFF)):
        for f in piece.faces:
            f.name = name
            faces.append(f)
    if not faces:
        raise ValueError("the part and its material regions do not overlap")
    shape = occ.Glue(faces) if len(faces) > 1 else faces[0]
    for e in shape.edges:
        if e.name is None:
            e.name = INTERFACE
    return shape


def assign_elementwise(ngm, stiff: StiffRegion, source) -> None:
    """Give every element of the Netgen mesh ``ngm`` (one material) the material of the nodal
    ρ̄2 interpolated at its centroid: ``stiff`` where >= the threshold, else ``soft``."""
    ngm.SetMaterial(1, SOFT)
    if stiff.thresholded is None:
        return
    coords = np.asarray(ngm.Coordinates(), dtype=float)
    cen = np.array([coords[[v.nr - 1 for v in el.vertices]].mean(axis=0)
                    for el in ngm.Elements2D()])
    val = pressure_sampler(stiff.nodal, source)(cen)
    hard = val >= stiff.threshold
    if not hard.any():
        return
    idx = ngm.AddRegion(STIFF, dim=2)
    for el, h in zip(ngm.Elements2D(), hard):
        if h:
            el.index = idx


def material_areas(mesh) -> dict:
    """Area (2D) or volume (3D) of every material of an NGSolve mesh (``{name: m²}`` or
    ``m³``)."""
    import ngsolve

    return {m: float(ngsolve.Integrate(mesh.MaterialCF({m: 1.0}, default=0.0), mesh))
            for m in sorted(set(mesh.GetMaterials()))}


def interface_length(mesh) -> float:
    """Length of the ``interface`` boundary (0 when the mesh has none)."""
    import ngsolve

    if INTERFACE not in mesh.GetBoundaries():
        return 0.0
    return float(ngsolve.Integrate(ngsolve.CF(1.0), mesh,
                                   definedon=mesh.Boundaries(INTERFACE)))


def modulus_cf(mesh, E):
    """Young's modulus as a CoefficientFunction: ``E`` a number, or ``{material: E}`` covering
    every material of ``mesh`` (ValueError otherwise)."""
    if not isinstance(E, dict):
        return float(E)
    missing = sorted(set(mesh.GetMaterials()) - set(E))
    if missing:
        raise ValueError(f"no Young's modulus for the material(s) {', '.join(missing)} of the "
                         f"mesh (given: {', '.join(sorted(E))})")
    return mesh.MaterialCF({k: float(v) for k, v in E.items()}, default=0.0)
