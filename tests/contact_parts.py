"""Parts whose walls touch under pressure, for the contact tests: the slotted block (2D) and
the slotted slab (its extrusion).

The block is 1 x 1 m with a slot 0.02 m high open at its right end (from x = 0.3), its left
edge ``left``, its top and bottom edges ``pressure``, the slot's walls ``slot``, the right
edges ``right`` and the top right corner ``corner``; a pressure on ``pressure`` squeezes the
slot shut (E = 1 MPa, plane strain: the walls meet at about 1 kPa)."""
from netgen import occ
from ngsolve import Mesh


def slotted_block(maxh=0.1):
    """The slotted block, triangles of ``maxh``."""
    body = (occ.MoveTo(0, 0).Rectangle(1, 1).Face()
            - occ.MoveTo(0.3, 0.49).Rectangle(0.8, 0.02).Face())
    body.edges.name = "slot"
    body.edges.Min(occ.X).name = "left"
    body.edges.Max(occ.Y).name = "pressure"
    body.edges.Min(occ.Y).name = "pressure"
    for e in body.edges:
        if abs(e.center.x - 1.0) < 1e-9:
            e.name = "right"
    body.vertices.Nearest((1.0, 1.0, 0.0)).name = "corner"
    return Mesh(occ.OCCGeometry(body, dim=2).GenerateMesh(maxh=maxh))


def slotted_slab(maxh=0.1):
    """The slotted block extruded 0.2 m in z, its faces z = 0 and 0.2 held in z."""
    body = occ.Box((0, 0, 0), (1, 1, 0.2)) - occ.Box((0.3, 0.49, -1), (1.5, 0.51, 1))
    body.faces.name = "slot"
    body.faces.Min(occ.X).name = "left"
    body.faces.Max(occ.Y).name = "pressure"
    body.faces.Min(occ.Y).name = "pressure"
    body.faces.Min(occ.Z).name = "front"
    body.faces.Max(occ.Z).name = "back"
    body.vertices.Nearest((1.0, 1.0, 0.0)).name = "corner"
    return Mesh(occ.OCCGeometry(body).GenerateMesh(maxh=maxh))
