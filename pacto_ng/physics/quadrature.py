"""The quadrature of the mechanics (and Darcy) forms: one rule for every form of a block, and
the points where the ``det F`` guard is checked (the rule's own points, or those and the
element's vertices, edge midpoints and centroid: :data:`GUARD_POINTS`).

Rules exist for every element type a mesh of this toolkit has: triangles and quadrilaterals
(2D), tetrahedra and hexahedra (3D); a dictionary of rules holds all four, so that one serves
a mesh of either dimension.
"""
from __future__ import annotations

import itertools

#: the reference elements by NGSolve's type name: their vertices and edges (vertex pairs)
_SQUARE = [(0, 0), (1, 0), (1, 1), (0, 1)]
_CUBE = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
REFERENCE = {
    "TRIG": ([(0, 0), (1, 0), (0, 1)], [(0, 1), (1, 2), (2, 0)]),
    "QUAD": (_SQUARE, [(0, 1), (1, 2), (2, 3), (3, 0)]),
    "TET": ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
            list(itertools.combinations(range(4), 2))),
    "HEX": (_CUBE, [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                    (0, 4), (1, 5), (2, 6), (3, 7)]),
}


def _types():
    """``[(ngsolve element type, name)]`` of the element types of :data:`REFERENCE`."""
    import ngsolve

    return [(getattr(ngsolve, name), name) for name in REFERENCE]


def integration_rules(order: int):
    """The one quadrature rule used by every form of an order-``order`` displacement, per
    element type (triangle, quadrilateral, tetrahedron, hexahedron)."""
    from ngsolve import IntegrationRule

    return {et: IntegrationRule(et, order) for et, _ in _types()}


def mechanics_rules(order: int, bubble: bool = False):
    """The rule of a mechanics block whose displacement is of order ``order`` (``bubble``: the
    mixed formulation's bubble of ``order + 1``): degree ``2 (order + bubble)``, except on
    triangles and tetrahedra at order 1 without the bubble.  There ``∇u`` is constant on each
    (straight-sided) element, and with it every energy density of ``∇u`` and of element-wise
    fields; a term linear in an order-1 field and in ``v`` or ``∇v`` (the Darcy pressure's
    fixed or follower load) is affine: the rule of degree 1, one point, integrates them
    exactly (instead of 3 points on a triangle, 4 on a tetrahedron)."""
    from ngsolve import TET, TRIG, IntegrationRule

    rules = integration_rules(2 * (order + bubble))
    if order == 1 and not bubble:
        rules.update({et: IntegrationRule(et, 1) for et in (TRIG, TET)})
    return rules


def stiffness_rules(order: int, rules):
    """The rules of a stiffness ``∫ (C ∇u) : ∇v`` with ``C`` constant on each element and a
    displacement of order ``order``: on triangles and tetrahedra (straight-sided, so affine)
    the integrand is a polynomial of degree ``2 (order - 1)``, which a rule of that degree
    integrates exactly (4 points instead of 14 on an order-2 tetrahedron: the assembly took
    1.96 against 2.86 s at 463 926 dofs, the matrices equal to 2e-14); quadrilaterals and
    hexahedra, whose maps need not be affine, keep ``rules``."""
    from ngsolve import TET, TRIG, IntegrationRule

    return {et: IntegrationRule(et, 2 * (order - 1)) if et in (TRIG, TET) else rule
            for et, rule in rules.items()}


def centroid_rules():
    """One point per element, its centroid (weight: the reference element's measure), per
    element type: for element-wise constants evaluated with ``MapToAllElements``."""
    from ngsolve import IntegrationRule

    out = {}
    for et, name in _types():
        verts = REFERENCE[name][0]
        c = tuple(sum(v[k] for v in verts) / len(verts) for k in range(len(verts[0])))
        out[et] = IntegrationRule([c], [IntegrationRule(et, 0).weights[0]])
    return out


#: where a guard can be checked: ``"quadrature"``, the points of the forms' rule (where the
#: discrete energy is evaluated, so where it must be defined), or ``"element"``, those and the
#: vertices, edge midpoints and centroid (an element can fold at a corner while every Gauss
#: point still sees J > 0)
GUARD_POINTS = ("quadrature", "element")


def element_points(name: str):
    """``(points, kinds)``: the reference-element vertices, edge midpoints and centroid of the
    element type ``name`` (``"TRIG"``, ``"QUAD"``, ``"TET"``, ``"HEX"``), in this order, and
    what each is (``"vertex"``, ``"edge midpoint"``, ``"centroid"``)."""
    verts, edges = REFERENCE[name]
    dim = len(verts[0])
    mids = [tuple(0.5 * (verts[a][k] + verts[b][k]) for k in range(dim)) for a, b in edges]
    centroid = tuple(sum(v[k] for v in verts) / len(verts) for k in range(dim))
    points = [tuple(float(c) for c in v) for v in verts] + mids + [centroid]
    kinds = ["vertex"] * len(verts) + ["edge midpoint"] * len(edges) + ["centroid"]
    return points, kinds


def guard_rules(rules, points: str = "element"):
    """The quadrature points of ``rules``, with ``points="element"`` (default) followed by the
    vertices, edge midpoints and centroid (:func:`element_points`), per element type."""
    from ngsolve import IntegrationRule

    if points not in GUARD_POINTS:
        raise ValueError(f"guard points must be one of {', '.join(GUARD_POINTS)} (got '{points}')")
    out = {}
    for et, name in _types():
        dim = len(REFERENCE[name][0][0])
        pts = [tuple(p[:dim]) for p in rules[et].points]
        if points == "element":
            pts += element_points(name)[0]
        out[et] = IntegrationRule(pts, [0.0] * len(pts))
    return out
