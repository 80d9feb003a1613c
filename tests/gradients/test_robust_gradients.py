"""Finite-difference checks of the robust chains (``--set robust=1`` and ``2``,
:mod:`pacto_ng.robust`) on a small pa-inverter: every realisation's objective, the worst case
and every constraint, for the linear, Neo-Hookean and Wang models, fixed and follower Darcy
load.

The check's design is a random field at β = 2 (not β_max = 32): at β = 32 the eroded design
(η + Δη = 0.6) of a random field ρ̃ ≈ 0.5 is nearly void everywhere, and the Neo-Hookean
equilibrium under the pressure then does not exist.
"""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng.case import build_problem, get_case
from pacto_ng.core import check_gradient

pytestmark = pytest.mark.usefixtures("one_thread")


def _problem(robust, model, load_type):
    case = get_case("pa-inverter")
    params = case.defaults.replace(robust=robust, model=model, load_type=load_type, nelx=12,
                                   nely=6, order=1, newton_rtol=1e-12)
    problem = build_problem(case, params)
    problem.apply_schedule(3.0, 2.0, 1.0)
    return problem


@pytest.mark.parametrize("load_type", ["fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean", "wang"])
@pytest.mark.parametrize("robust", [1, 2])
def test_robust_chain_gradients(robust, model, load_type):
    problem = _problem(robust, model, load_type)
    n_terms = 3 if robust == 1 else 2
    assert len(problem.objective_terms) == n_terms
    assert len(problem.extra_mechanics) == n_terms - 1
    names = list(problem.objective_terms) + [problem.objective] + problem.constraints
    rng = np.random.default_rng(1)
    x0 = rng.uniform(0.3, 0.7, problem.field.n)
    for name in names:
        def fun(x, nm=name):
            return float(problem.chain.forward(x=x)[nm])

        def grad(x, nm=name):
            problem.chain.forward(x=x)
            return np.asarray(problem.chain.gradient(nm))

        res = check_gradient(fun, grad, x0, h=1e-4, directions=2, seed=2, stencil=4,
                             max_cancellation=100.0)
        assert res.rel_error < 1e-5, (name, res)


def test_robust_realisations_differ_and_the_worst_is_their_maximum():
    problem = _problem(1, "linear", "fixed")
    x = np.random.default_rng(3).uniform(0.3, 0.7, problem.field.n)
    F0, f = problem.evaluate_terms(x, gradients=False)
    vals = problem.values
    # eroded <= intermediate <= dilated density everywhere (the thresholds η+Δη > η > η-Δη)
    assert np.all(vals["rho_bar_e"] <= vals["rho_bar"] + 1e-15)
    assert np.all(vals["rho_bar"] <= vals["rho_bar_d"] + 1e-15)
    assert vals["vol_d"] > vals["vol_i"]
    assert len(set(np.round(F0, 12))) == 3
    assert vals[problem.objective] == pytest.approx(max(F0), rel=0, abs=0)
    assert problem.constraints[0] == "volume_d"
