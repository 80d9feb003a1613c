"""Where Newton's guard is checked: the points an energy declares (EnergyTraits.guard_points).

A Q1 element on the unit square with the corner (1, 1) displaced by (-c, -c) has
``u = -c X Y (1, 1)``, ``F = [[1 - cY, -cX], [-cY, 1 - cX]]`` and ``det F = 1 - c (X + Y)``
(closed form): lowest at the corner (1, 1), ``1 - 2c``, and at the 2 x 2 Gauss points
``1 - 2c (1/2 + 1/(2√3))``.  At c = 0.6 the element is folded at its corner (-0.2) while
every Gauss point sees ``det F = 0.0536 > 0``: the discrete energy, evaluated at the Gauss
points only, is defined there.
"""
import numpy as np
import pytest

from pacto_ng.mesh import Layout, Segment, structured_mesh
from pacto_ng.params import Parameters
from pacto_ng.physics.energy import make_energy
from pacto_ng.physics.materials import jacobian, neohookean_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.quadrature import guard_rules
from pacto_ng.physics.traits import EnergyTraits, declare

pytestmark = pytest.mark.usefixtures("one_thread")

C = 0.6
GAUSS_HI = 0.5 + 0.5 / np.sqrt(3.0)  # the 2 x 2 Gauss point nearest the corner (1, 1)


def unit_square():
    lay = Layout(1.0, 1.0, segments=(
        Segment("left", (0, 0), (0, 1)), Segment("right", (1, 0), (1, 1)),
        Segment("bottom", (0, 0), (1, 0)), Segment("top", (0, 1), (1, 1))))
    return structured_mesh(lay, 1, 1)


def folded(energy):
    """A one-element block with the corner (1, 1) pulled to (1 - C, 1 - C)."""
    from ngsolve import CF, x, y

    mesh = unit_square()
    mech = Mechanics(mesh, order=1, energy=energy, supports=Supports(clamp=("left",)),
                     guard=lambda G, c: jacobian(G))
    mech.set_fields(np.ones(mesh.ne))
    mech.gfu.Set(CF((-C * x * y, -C * x * y)))
    return mech


def neohookean_fn():
    """A fresh Neo-Hookean energy (E = 1, ν = 0.3) that declares nothing yet."""
    def energy(G, c):
        return neohookean_energy(G, 1.0, 0.3)
    return energy


def test_the_rule_is_the_gauss_rule_of_the_closed_form():
    from ngsolve import QUAD

    mech = folded(neohookean_fn())
    pts = sorted(tuple(p[:2]) for p in mech.rules[QUAD].points)
    lo = 1.0 - GAUSS_HI
    # (arrays: pytest 9.2's approx refuses a list of tuples)
    np.testing.assert_allclose(np.array(pts), np.array(sorted(
        [(lo, lo), (lo, GAUSS_HI), (GAUSS_HI, lo), (GAUSS_HI, GAUSS_HI)])), rtol=0, atol=1e-14)
    assert len(guard_rules(mech.rules, "quadrature")[QUAD].points) == 4
    assert len(guard_rules(mech.rules, "element")[QUAD].points) == 4 + 9


def test_a_corner_fold_is_refused_by_the_element_guard_only():
    undeclared = folded(neohookean_fn())  # declares nothing: vertices and edge midpoints too
    assert undeclared.guard_points == "element"
    assert not undeclared.admissible(undeclared.gfu.vec)
    at_quadrature = folded(declare(neohookean_fn(), guard_points="quadrature"))
    assert at_quadrature.guard_points == "quadrature"
    assert at_quadrature.admissible(at_quadrature.gfu.vec)


def test_a_gauss_point_fold_is_refused_by_both():
    """Pulled further (c = 0.7 > 1/(2 · 0.7887) = 0.634), det F < 0 at a Gauss point."""
    from ngsolve import CF, x, y

    for energy in (neohookean_fn(),
                   declare(neohookean_fn(), guard_points="quadrature")):
        mech = folded(energy)
        mech.gfu.Set(CF((-0.7 * x * y, -0.7 * x * y)))
        assert not mech.admissible(mech.gfu.vec)


def test_lowest_jacobian_is_the_closed_form():
    mech = folded(neohookean_fn())
    low = mech.lowest_jacobian("quadrature")
    assert low["J"] == pytest.approx(1.0 - 2 * C * GAUSS_HI, rel=1e-12)
    assert (low["element"], low["point"]) == (0, "quadrature point")
    corner = mech.lowest_jacobian("corners")
    assert corner["J"] == pytest.approx(1.0 - 2 * C, rel=1e-12)
    assert (corner["element"], corner["point"]) == (0, "vertex")
    with pytest.raises(ValueError, match="points"):
        mech.lowest_jacobian("edges")


def test_the_models_declare_their_guard_points():
    from ngsolve import Parameter

    for model in ("neohookean", "wang"):
        energy, guard, _ = make_energy(Parameters(model=model), Parameter(3.0))
        assert guard is not None
        assert energy.traits.guard_points == "quadrature"
    assert EnergyTraits().guard_points == "element"  # an energy that declares nothing
    with pytest.raises(ValueError, match="guard_points"):
        EnergyTraits(guard_points="vertices")
