"""A passive wall around the pressure inlet (``inlet_wall``) holds the pressure by itself.

With every design element void, the Darcy flow out through the zero-pressure boundaries is
that of an open chamber without the wall (the pressure reaches the outer faces), and that of
a closed chamber with a wall one element thick: the chamber is sealed by construction."""
import numpy as np
import pytest

from pacto_ng.case import build_problem, get_case
from pacto_ng.outputs import leak


def _leak(name: str, maxh: float, wall: float):
    case = get_case(name)
    problem = build_problem(case, case.resolve(case.defaults.replace(maxh=maxh,
                                                                     inlet_wall=wall)))
    problem.chain.forward(x=np.zeros(problem.field.n))
    return leak(problem), problem


@pytest.mark.parametrize("name, maxh", [("pneunet", 0.004), ("pneunet-3d", 0.005)])
def test_a_wall_one_element_thick_seals_an_empty_design(name, maxh):
    open_leak, _ = _leak(name, maxh, 0.0)
    sealed_leak, problem = _leak(name, maxh, maxh)
    assert problem.field.solid.any() and not problem.field.solid[problem.field.void].any()
    assert open_leak > 0.1
    assert abs(sealed_leak) < 1e-3 * open_leak
