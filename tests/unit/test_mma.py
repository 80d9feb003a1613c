"""MMA and GCMMA on a problem with a known optimum (Svanberg's 'toy' problem form)."""
import numpy as np
import pytest

from pacto_ng.optimize.mma import Optimizer


def _problem(x):
    # min (x0-0.8)^2 + (x1-0.3)^2 + (x2-0.6)^2  s.t.  x0 + x1 + x2 <= 1
    t = np.array([0.8, 0.3, 0.6])
    f0 = float(((x - t) ** 2).sum())
    df0 = 2 * (x - t)
    f = np.array([x.sum() - 1.0])
    df = np.ones((1, 3))
    return f0, f, df0, df


@pytest.mark.parametrize("method", ["mma", "gcmma"])
def test_known_optimum(method):
    # KKT: x = t - μ/2 with sum = 1 -> μ = 2 (1.7 - 1)/3
    mu = 2 * 0.7 / 3
    expected = np.array([0.8, 0.3, 0.6]) - mu / 2
    opt = Optimizer(3, 1, method=method, move=0.2)
    x = np.array([0.5, 0.5, 0.5])
    for it in range(1, 60):
        f0, f, df0, df = _problem(x)
        x = opt.update(it, x, f0, df0, f, df, evaluate=lambda z: _problem(z)[:2])
    assert np.allclose(x, expected, atol=1e-4)


def test_move_limit_respected():
    opt = Optimizer(3, 1, method="mma", move=0.05)
    x = np.array([0.5, 0.5, 0.5])
    f0, f, df0, df = _problem(x)
    xn = opt.update(1, x, f0, df0, f, df)
    assert np.max(np.abs(xn - x)) <= 0.05 + 1e-12


@pytest.mark.parametrize("terms", [1, 2])
def test_gcmma_keeps_its_step_when_the_trial_design_cannot_be_analysed(terms):
    """``evaluate`` returns None (a Newton failure on GCMMA's trial design): the update returns
    the first subproblem's step, within the move limit, for one objective and for the worst
    case of two (the bound form's wrapper of ``evaluate`` passes None on, where it raised
    TypeError before)."""
    opt = Optimizer(3, 1, method="gcmma", move=0.2, terms=terms)
    x = np.array([0.5, 0.5, 0.5])
    f0, f, df0, df = _problem(x)
    if terms == 2:
        f0, df0 = np.array([f0, 0.5 * f0]), np.vstack([df0, 0.5 * df0])
    calls = []
    xn = opt.update(1, x, f0, df0, f, df, evaluate=lambda z: calls.append(z.copy()))
    assert len(calls) == 1 and opt.inner_evaluations == 0
    assert np.array_equal(xn, np.clip(calls[0], 0.0, 1.0))
    assert np.max(np.abs(xn - x)) <= 0.2 + 1e-12 and not np.array_equal(xn, x)
