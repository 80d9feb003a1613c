"""The quadrature of the mechanics (and Darcy) forms: one rule for every form of a block, and
the points where the ``det F`` guard is checked (the rule's own points, or those and the
element's vertices, edge midpoints and centroid: :data:`GUARD_POINTS`)."""
from __future__ import annotations


def integration_rules(order: int):
    """The one quadrature rule used by every form of an order-``order`` displacement."""
    from ngsolve import QUAD, TRIG, IntegrationRule

    return {TRIG: IntegrationRule(TRIG, order), QUAD: IntegrationRule(QUAD, order)}


#: where a guard can be checked: ``"quadrature"``, the points of the forms' rule (where the
#: discrete energy is evaluated, so where it must be defined), or ``"element"``, those and the
#: vertices, edge midpoints and centroid (an element can fold at a corner while every Gauss
#: point still sees J > 0)
GUARD_POINTS = ("quadrature", "element")

#: reference-element points of the ``"element"`` guard besides the quadrature points
_EXTRA_GUARD_POINTS = {
    "TRIG": [(0, 0), (1, 0), (0, 1), (0.5, 0), (0.5, 0.5), (0, 0.5), (1 / 3, 1 / 3)],
    "QUAD": [(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0), (1, 0.5), (0.5, 1), (0, 0.5), (0.5, 0.5)],
}


def guard_rules(rules, points: str = "element"):
    """The quadrature points of ``rules``, with ``points="element"`` (default) followed by the
    vertices, edge midpoints and centroid (:data:`GUARD_POINTS`)."""
    from ngsolve import QUAD, TRIG, IntegrationRule

    if points not in GUARD_POINTS:
        raise ValueError(f"guard points must be one of {', '.join(GUARD_POINTS)} (got '{points}')")
    out = {}
    for et, key in ((TRIG, "TRIG"), (QUAD, "QUAD")):
        pts = [tuple(p[:2]) for p in rules[et].points]
        if points == "element":
            pts += _EXTRA_GUARD_POINTS[key]
        out[et] = IntegrationRule(pts, [0.0] * len(pts))
    return out
