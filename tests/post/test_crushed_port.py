"""The part stage's line for a part whose analysis stopped short of its load with its lowest
det F at a port whose spring acts at one point (part_stage.crushed_at_port)."""
from types import SimpleNamespace

import numpy as np

from pacto_ng.physics.loads import PointLoad, Port, Spring
from pacto_ng.physics.materials import jacobian, neohookean_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.post.part_stage import crushed_at_port
from tests.small_cases import unit_square


def held_corner():
    """A unit square clamped at the bottom, its top pushed along x by 0.1 N against a spring
    of 10 N/m at its top right corner ``corner`` (Neo-Hookean, E = 1 Pa, ν = 0.3): an
    element at the corner, dragged by the top and held by the spring, has the lowest det F
    (0.41, measured; at 0.3 N Newton stalls at 0.58 of the load, as a part's does).  The top
    left corner is the point ``other``."""
    mesh = unit_square(0.1, {"corner": (1.0, 1.0), "other": (0.0, 1.0)})
    mech = Mechanics(mesh, order=2, energy=lambda G, c: neohookean_energy(G, 1.0, 0.3),
                     supports=Supports(clamp=("bottom",)), loads=(PointLoad("top", (0.1, 0.0)),),
                     springs=(Spring("corner", 10.0, (1.0, 0.0)),), thickness=1.0,
                     guard=lambda G, c: jacobian(G))
    mech.forward(np.ones(mesh.ne))
    return SimpleNamespace(mesh=mesh, mech=mech)


def test_the_line_names_the_port_whose_point_spring_crushes_the_part():
    """At the port with the point spring: one line naming it and the lowest det F; the same
    spring spread, or the port at the other corner, or no spring: no line."""
    ana = held_corner()
    low = ana.mech.lowest_jacobian()
    assert low["J"] < 0.9  # the corner is compressed
    line = crushed_at_port(ana, (Port("corner", (1.0, 0.0), spring=10.0),))
    assert len(line) == 1 and "output 'corner'" in line[0] and f"{low['J']:.2g}" in line[0]
    assert crushed_at_port(ana, (Port("corner", (1.0, 0.0), spring=10.0, spread=0.1),)) == []
    assert crushed_at_port(ana, (Port("other", (1.0, 0.0), spring=10.0),)) == []
    assert crushed_at_port(ana, (Port("corner", (1.0, 0.0)),)) == []
