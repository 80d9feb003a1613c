"""Frictionless self-contact in a part's analysis (pacto_ng/physics/contact.py), in 2D.

A block 1 x 1 m with a slot open at one end (0.02 m high, from x = 0.3 to the end), clamped
on the side the slot does not reach, is squeezed by a pressure of 3 kPa on its top and bottom
faces (E = 1 MPa): the slot's two walls close at its open end.  Without contact they pass
through each other (the walls' vertical gap falls to -0.037 m, linear, and -0.039 m,
Neo-Hookean); with the slot's walls in self-contact the gap stays at the penalty's overlap,
contact pressure / k, which shrinks tenfold when k grows tenfold (k = 1e2 and 1e3 E/h:
measured -1.70e-6 and -1.69e-7 m linear, -1.73e-6 and -1.72e-7 m Neo-Hookean)."""
import numpy as np
import pytest
from netgen.occ import MoveTo, OCCGeometry, X, Y
from ngsolve import Mesh

from pacto_ng import Parameters, Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.post.part_analysis import PartAnalysis

LOW, HIGH = 0.49, 0.51  # the slot's walls


def slotted():
    body = MoveTo(0, 0).Rectangle(1, 1).Face() - MoveTo(0.3, LOW).Rectangle(0.8, 0.02).Face()
    body.edges.name = "free"
    body.edges.Min(X).name = "fixed"
    body.edges.Max(Y).name = "pressure"
    body.edges.Min(Y).name = "pressure"
    for edge in body.edges:
        if LOW - 0.01 < edge.center.y < HIGH + 0.01 and edge.center.x > 0.29:
            edge.name = "slot"
    return Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.05))


def smallest_gap(mesh, analysis) -> float:
    u = analysis.mech.gfu
    return min(HIGH + u(mesh(x, HIGH))[1] - LOW - u(mesh(x, LOW))[1]
               for x in np.linspace(0.35, 0.99, 30))


def squeeze(mesh, model: str, contact=(), penalty: float = 1e3):
    params = Parameters(model=model, E1=1e6, E0=1.0, nu=0.3, plane="strain", thickness=1.0,
                        order=2)
    an = PartAnalysis(mesh, "fixed", params=params, supports=Supports(clamp=("fixed",)),
                      ports=Port("pressure", (0.0, -1.0)), contact=contact,
                      contact_penalty=penalty)
    point = an.solve(3e3)
    assert point.converged
    return smallest_gap(mesh, an)


@pytest.mark.parametrize("model", ["linear", "neohookean"])
def test_slot_walls_pass_through_each_other_without_contact_and_not_with_it(model):
    mesh = slotted()
    assert squeeze(mesh, model) < -0.03
    coarse, fine = (squeeze(mesh, model, ("slot",), penalty=k) for k in (1e2, 1e3))
    assert -1e-4 * (HIGH - LOW) < fine < 0 and coarse < 0
    assert coarse / fine == pytest.approx(10.0, rel=0.05)  # the overlap is p / k

