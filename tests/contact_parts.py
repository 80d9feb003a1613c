"""Parts whose walls touch under pressure, for the contact tests: the slotted block (2D),
the slotted slab (its extrusion) and the pressed arch (2D).

The block is 1 x 1 m with a slot 0.02 m high open at its right end (from x = 0.3), its left
edge ``left``, its top and bottom edges ``pressure``, the slot's walls ``slot``, the right
edges ``right`` and the top right corner ``corner``; a pressure on ``pressure`` squeezes the
slot shut (E = 1 MPa, plane strain: the walls meet at about 1 kPa)."""
from netgen import occ
from ngsolve import Mesh

#: the pressed arch: its rise, thickness and the floor plate's thickness (m)
RISE, ARCH, FLOOR = 0.08, 0.03, 0.05


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


def pressed_arch(maxh=0.02):
    """Half of a shallow arch over a floor plate, its ends in the plate (x from 0 to the
    symmetry line x = 0.5, ``sym``): the plate 0.05 m thick on ``fixed`` (y = 0); the arch a
    circular ring ARCH thick whose inner wall spans 0.8 m at the plate's top and rises RISE
    above it; the cavity's walls (the plate's top under the arch and the arch's inner wall)
    ``slot``, the arch's outer wall ``pressure``, its top ``crown`` (a point on ``sym``).
    A pressure on ``pressure`` pushes the arch through a snap (a pressure maximum near
    190 Pa at E = 1 MPa) onto the plate.  Curved to order 2."""
    radius = (0.16 + RISE ** 2) / (2 * RISE)
    centre = (0.5, FLOOR + RISE - radius)
    ring = occ.Circle(centre, radius + ARCH).Face() - occ.Circle(centre, radius).Face()
    body = (occ.MoveTo(0, 0).Rectangle(0.5, FLOOR).Face()
            + ring * occ.MoveTo(0, FLOOR).Rectangle(0.5, 1).Face())
    body.edges.name = "free"
    for e in body.edges:
        c, left = e.center, min(e.start.x, e.end.x)
        if abs(c.y) < 1e-9:
            e.name = "fixed"
        elif abs(c.x - 0.5) < 1e-9:
            e.name = "sym"
        elif abs(c.y - FLOOR) < 1e-9 and c.x > 0.1:
            e.name = "slot"  # the plate's top under the arch
        elif c.y > FLOOR + 1e-9:  # the arch's walls, told apart by where they end
            e.name = "slot" if abs(left - 0.1) < 1e-6 else "pressure"
    body.vertices.Nearest((0.5, FLOOR + RISE + ARCH, 0.0)).name = "crown"
    mesh = Mesh(occ.OCCGeometry(body, dim=2).GenerateMesh(maxh=maxh))
    mesh.Curve(2)
    return mesh
