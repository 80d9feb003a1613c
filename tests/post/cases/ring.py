"""A thick ring a <= r <= b (a quarter: symmetry on x = 0, ``left``, and y = 0, ``bottom``)
around a chamber, the quarter disc r < a (the passive void ``chamber``, its arc the
``inlet``), plane strain: as built, Lamé's thick-walled cylinder under the inner pressure,
``u_r(a) = (1+ν) a² P / (E (b² - a²)) ((1-2ν) a + b²/a)`` at the point ``inner`` (a, 0).
For tests/post/test_as_built.py.  ``ZERO`` names the zero-pressure boundaries (the outer arc;
a test adds the chamber's own symmetry edge to open it)."""
from netgen import occ

import pacto_ng as pn

A, B = 0.01, 0.02
ZERO = ("outer",)


def geometry(p):
    quarter = occ.MoveTo(0, 0).Rectangle(B, B).Face()
    ring = (occ.Circle((0, 0), B).Face() - occ.Circle((0, 0), A).Face()) * quarter
    chamber = occ.Circle((0, 0), A).Face() * quarter
    ring.faces.name, chamber.faces.name = "design", "chamber"
    shape = occ.Glue([ring, chamber])
    for e in shape.edges:
        c = e.center
        r = (c.x ** 2 + c.y ** 2) ** 0.5
        if abs(c.x) < 1e-12:
            e.name = "left" if c.y > A else "chamber_left"
        elif abs(c.y) < 1e-12:
            e.name = "bottom" if c.x > A else "chamber_bottom"
        else:
            e.name = "inlet" if r < 0.5 * (A + B) else "outer"
    shape.vertices.Nearest((A, 0, 0)).name = "inner"
    return shape


def setup(p):
    return pn.Setup(supports=pn.Supports(fix_x=("left",), fix_y=("bottom",)),
                    pressure=pn.Pressure(inlet=("inlet",), zero=ZERO),
                    port=pn.Port("inner", (1.0, 0.0)), void=("chamber",),
                    objective="mechanism", objective_ref=1.0)


CASE = pn.Case(
    name="ring", summary="thick ring under inner pressure (Lamé), as built",
    source="tests/post/cases/ring.py",
    defaults=pn.Parameters(model="linear", maxh=0.0015, plane="strain", thickness=1e-3,
                           E1=1e6, E0=1e0, nu=0.3, volfrac=0.5, load=1e3),
    geometry=geometry, setup=setup, load_unit="Pa")
