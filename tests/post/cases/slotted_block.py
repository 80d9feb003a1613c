"""A block 1 x 1 m with a slot open at its right end (0.02 m high, from x = 0.3 to the end),
clamped on its left edge (``fixed``), the pressure on its top and bottom edges (the
``inlet``, the fluid beyond them), plane strain, E = 1 MPa: the pressure squeezes the slot's
walls together (tests/physics/test_contact.py's block, at about 1 kPa they meet).  The output
is the top right corner's downward motion (``corner``).  For tests/post/test_analyse.py
(``pacto analyse CASE --as-built --contact``)."""
from netgen import occ

import pacto_ng as pn

LOW, HIGH = 0.49, 0.51  # the slot's walls


def geometry(p):
    body = (occ.MoveTo(0, 0).Rectangle(1, 1).Face()
            - occ.MoveTo(0.3, LOW).Rectangle(0.8, 0.02).Face())
    body.faces.name = "design"
    body.edges.name = "free"
    body.edges.Min(occ.X).name = "fixed"
    body.edges.Max(occ.Y).name = "top"
    body.edges.Min(occ.Y).name = "bottom"
    body.vertices.Nearest((1.0, 1.0, 0.0)).name = "corner"
    return body


def setup(p):
    return pn.Setup(supports=pn.Supports(clamp=("fixed",)),
                    pressure=pn.Pressure(inlet=("top", "bottom"), zero=("free",)),
                    port=pn.Port("corner", (0.0, -1.0)),
                    objective="mechanism", objective_ref=1.0)


CASE = pn.Case(
    name="slotted_block", summary="a slotted block squeezed shut (contact), as built",
    source="tests/post/cases/slotted_block.py",
    defaults=pn.Parameters(model="linear", maxh=0.1, plane="strain", thickness=1.0,
                           E1=1e6, E0=1e0, nu=0.3, volfrac=0.5, load=1e3),
    geometry=geometry, setup=setup, load_unit="Pa")
