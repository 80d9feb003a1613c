"""The quarter of a thick-walled ring a <= r <= b, the mesh of the tests that check a
pressurised cylinder against Lamé's closed form (tests/post/test_part_analysis.py,
tests/shape)."""
from __future__ import annotations

import math

import ngsolve as ng
from netgen import occ


def quarter_ring(a: float, b: float, maxh: float, curve: int):
    """Edges ``left`` (x = 0), ``bottom`` (y = 0), ``pressure`` (r = a), ``outer`` (r = b);
    points ``inner`` (a, 0) and ``outer_point`` (b, 0); curved to order ``curve``."""
    shape = (occ.Circle((0, 0), b).Face() - occ.Circle((0, 0), a).Face()) \
        * occ.MoveTo(0, 0).Rectangle(b, b).Face()
    for e in shape.edges:
        c = e.center
        e.name = ("left" if abs(c.x) < 1e-9 else "bottom" if abs(c.y) < 1e-9 else
                  "pressure" if math.hypot(c.x, c.y) < 0.5 * (a + b) else "outer")
    shape.vertices.Nearest((a, 0, 0)).name = "inner"
    shape.vertices.Nearest((b, 0, 0)).name = "outer_point"
    mesh = ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
    mesh.Curve(curve)
    return mesh
