"""The quadrature of the mechanics (and Darcy) forms: one rule for every form of a block, and
the points where the ``det F`` guard is checked."""
from __future__ import annotations


def integration_rules(order: int):
    """The one quadrature rule used by every form of an order-``order`` displacement."""
    from ngsolve import QUAD, TRIG, IntegrationRule

    return {TRIG: IntegrationRule(TRIG, order), QUAD: IntegrationRule(QUAD, order)}


#: reference-element points where ``det F`` is checked besides the quadrature points:
#: vertices, edge midpoints and centroid ("J <= 0 anywhere is rejected", SPEC §3) — an
#: element can fold at a corner while every Gauss point still sees J > 0
_EXTRA_GUARD_POINTS = {
    "TRIG": [(0, 0), (1, 0), (0, 1), (0.5, 0), (0.5, 0.5), (0, 0.5), (1 / 3, 1 / 3)],
    "QUAD": [(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 0), (1, 0.5), (0.5, 1), (0, 0.5), (0.5, 0.5)],
}


def guard_rules(rules):
    """The quadrature points of ``rules`` plus vertices, edge midpoints and centroid."""
    from ngsolve import QUAD, TRIG, IntegrationRule

    out = {}
    for et, key in ((TRIG, "TRIG"), (QUAD, "QUAD")):
        pts = [tuple(p[:2]) for p in rules[et].points] + _EXTRA_GUARD_POINTS[key]
        out[et] = IntegrationRule(pts, [0.0] * len(pts))
    return out
