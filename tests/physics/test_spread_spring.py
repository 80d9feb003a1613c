"""A spring at a point spread over the boundary about it (Spring.spread), as a part's port
spring is: the same total stiffness as the point spring, and a displacement that settles as
the mesh is refined where the point spring's does not (a force at a point has no finite
displacement in elasticity)."""
import numpy as np
import pytest
from ngsolve import CF, Integrate

from pacto_ng.physics.loads import SPREAD_REACH, PointLoad, Spring
from pacto_ng.physics.materials import linear_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from tests.small_cases import unit_square


def square(maxh):
    """The unit square: edges bottom, top, left, right; its top right corner the point
    ``corner``."""
    return unit_square(maxh, {"corner": (1.0, 1.0)})


@pytest.mark.parametrize("spread", [0.0, 0.1, 0.3])
def test_a_translation_stores_the_springs_whole_stiffness(spread):
    """``u`` = a unit translation along the spring: its energy is k/2 whatever the spread
    (the weighted mean of a constant); across the spring, none; the support is the ball of
    SPREAD_REACH spreads about the corner."""
    mesh = square(0.1)
    spring = Spring("corner", 3.0, (2.0, 0.0), spread)
    along = Integrate(spring.energy(mesh, CF((1.0, 0.0))), mesh)
    across = Integrate(spring.energy(mesh, CF((0.0, 1.0))), mesh)
    assert along == pytest.approx(1.5, rel=1e-12)
    assert abs(across) < 1e-14
    support = spring.support(mesh)
    if spread:
        assert support[0] == pytest.approx((1.0, 1.0)) and support[1] == SPREAD_REACH * spread
    else:
        assert support is None


def corner_motion(spread: float, maxh: float) -> float:
    """u_x at the corner of the square clamped at the bottom, pushed along x by 1 N spread
    over the top and held back by a spring of 1 N/m at the corner (E = 1 Pa, ν = 0.3, plane
    strain, 1 m thick, order 2): the spring 7 times the square's own stiffness there."""
    mesh = square(maxh)
    mech = Mechanics(mesh, order=2, energy=lambda G, c: linear_energy(G, 1.0, 0.3, "strain"),
                     supports=Supports(clamp=("bottom",)), loads=(PointLoad("top", (1.0, 0.0)),),
                     springs=(Spring("corner", 1.0, (1.0, 0.0), spread),), thickness=1.0,
                     linear=True)
    mech.forward(np.ones(mesh.ne))
    return float(mech.u(mesh(1.0, 1.0))[0])


def test_the_spread_springs_motion_settles_where_the_point_springs_does_not():
    """Halving the element size from 0.05 to 0.0125 m: at the point spring the corner's
    motion keeps falling by about 8 % per halving (the point's compliance grows without
    bound: the spring holds it back ever more), spread over 0.1 m it changes by 1 % and
    less.  Measured (m): point 0.46306, 0.42536, 0.39307 (differences 3.8e-2, 3.2e-2);
    spread 0.39899, 0.39419, 0.39017 (4.8e-3, 4.0e-3); without the spring the corner's
    motion changes by 1.5e-2 and 6.8e-3 of 6.9 (the clamp's corners)."""
    sizes = (0.05, 0.025, 0.0125)
    point = np.array([corner_motion(0.0, h) for h in sizes])
    spread = np.array([corner_motion(0.1, h) for h in sizes])
    print("point", point, "spread", spread)
    assert np.all(np.abs(np.diff(point)) / point[1:] > 0.07)
    assert np.all(np.abs(np.diff(spread)) / spread[1:] < 0.013)
    assert abs(spread[-1] - spread[-2]) < 0.15 * abs(point[-1] - point[-2])
