"""The finite-difference checker itself: both stencils converge at their order, a wrong
gradient is caught, and nearly stationary directions are drawn again."""
import numpy as np
import pytest

from pacto_ng.core import check_gradient

A = np.random.default_rng(3).normal(size=(6, 6))


def fun(x):
    return float(np.sum(np.sin(A @ x)) + 0.1 * np.sum(x ** 4))


def grad(x):
    return A.T @ np.cos(A @ x) + 0.4 * x ** 3


X0 = np.linspace(0.2, 0.7, 6)


@pytest.mark.parametrize("stencil, order", [(2, 2), (4, 4)])
def test_stencil_error_falls_at_its_order(stencil, order):
    errs = [check_gradient(fun, grad, X0, h=h, stencil=stencil).rel_error
            for h in (1e-1, 5e-2)]
    rate = np.log2(errs[0] / errs[1])
    assert abs(rate - order) < 0.3, (errs, rate)


def test_five_point_stencil_catches_a_wrong_gradient():
    wrong = lambda x: grad(x) * (1 + 1e-4 * np.arange(6))  # noqa: E731
    assert check_gradient(fun, grad, X0, h=1e-3, stencil=4).rel_error < 1e-9
    assert check_gradient(fun, wrong, X0, h=1e-3, stencil=4).rel_error > 1e-5


def test_nearly_stationary_directions_are_redrawn():
    g = np.array([1.0, -1.0, 1.0, -1.0])  # g·d cancels for many random d
    lin = lambda x: float(g @ x)  # noqa: E731
    free = check_gradient(lin, lambda x: g, np.zeros(4), h=1e-3, directions=20, seed=1)
    kept = check_gradient(lin, lambda x: g, np.zeros(4), h=1e-3, directions=20, seed=1,
                          max_cancellation=10.0)
    assert free.cancellation > 10.0
    assert kept.cancellation <= 10.0


def test_bounds_leave_room_for_the_wide_stencil():
    with pytest.raises(ValueError, match="lower bound"):
        check_gradient(fun, grad, np.full(6, 1.5e-4), h=1e-4, lower=0.0, stencil=4)
