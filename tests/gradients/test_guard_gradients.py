"""The adjoint gradient at an equilibrium the quadrature-point guard accepts and the element
guard refused: a void element of the unit-element pa-inverter (24 x 16 Q1, E1 = 1, E0 = 1e-6,
plane stress, Neo-Hookean) folded at a corner (det F < 0 at a vertex) with det F > 0 at every
quadrature point.  The discrete energy, residual and tangent see only the quadrature points,
so the equilibrium is smooth in the design there: the objective's gradient must match central
finite differences (five-point stencil) as everywhere else."""
import numpy as np
import pytest

from pacto_ng.case import build_problem, get_case
from pacto_ng.core import check_gradient

pytestmark = pytest.mark.usefixtures("one_thread")

NELX, NELY = 24, 16


def test_gradient_at_a_state_with_a_folded_void_corner():
    case = get_case("pa-inverter")
    params = case.defaults.with_overrides(dict(
        nelx=str(NELX), nely=str(NELY), unit_elements="1", plane="stress", E1="1", E0="1e-6",
        thickness="0.5", delta_s="1", k_out="0.01", filter_radius="2.5", model="neohookean",
        load="5e-5", newton_rtol="1e-12", robust="0"))
    problem = build_problem(case, params)
    problem.apply_schedule(params.penal, 8.0, 1.0)
    field = problem.field
    c = field.centroids()[field.design_index]
    x0 = 0.5 + 0.4 * np.cos(2 * np.pi * c[:, 0] / NELX) * np.cos(np.pi * c[:, 1] / NELY)
    problem.chain.forward(x=x0)
    mech = problem.mech
    assert mech.guard_points == "quadrature"
    assert mech.result.converged
    assert mech.lowest_jacobian("quadrature")["J"] > 0.0
    assert mech.lowest_jacobian("corners")["J"] < 0.0  # folded at a corner: refused before
    name = problem.objective

    def fun(x):
        return float(problem.chain.forward(x=x)[name])

    def grad(x):
        problem.chain.forward(x=x)
        return problem.chain.gradient(name)

    check = check_gradient(fun, grad, x0, h=1e-4, directions=2, stencil=4, max_cancellation=100)
    assert check.rel_error < 1e-6
    assert mech.lowest_jacobian("corners")["J"] < 0.0  # the perturbed states are folded too
