"""What a run modelled is in summary.json: the Darcy solve only for design-dependent loads, the
symmetric half domain, and the mechanics adjoints solved or skipped (compliance of fixed loads on
the linear model: the adjoint is the primal)."""
import json

import numpy as np

from pacto_ng.cli import main


def _summary(tmp_path, name, *args):
    out = tmp_path / name
    assert main(["run", name, *args, "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


def test_mbb_no_darcy_half_domain_no_adjoint_solve(tmp_path):
    s = _summary(tmp_path, "mbb", "--nelx", "30", "--nely", "10",
                 "--iterations", "4")
    assert s["darcy_solve"] is False
    assert s["symmetric_half_domain"] is True
    # one compliance gradient per iteration, none of them solved
    assert s["adjoint_solves"]["solved"] == 0
    assert s["adjoint_solves"]["skipped_self_adjoint"] >= s["iterations"] == 4


def test_pa_inverter_darcy_half_domain_adjoints_solved(tmp_path):
    s = _summary(tmp_path, "pa-inverter", "--model", "linear", "--maxh", "0.01",
                 "--iterations", "2")
    assert s["darcy_solve"] is True
    assert s["symmetric_half_domain"] is True
    # -Δ/SE: its adjoint is not the primal
    assert s["adjoint_solves"]["skipped_self_adjoint"] == 0
    assert s["adjoint_solves"]["solved"] >= s["iterations"] == 2


def test_cantilever_is_not_halved(tmp_path):
    s = _summary(tmp_path, "cantilever", "--model", "linear", "--maxh", "0.05",
                 "--iterations", "1")
    assert s["symmetric_half_domain"] is False and s["darcy_solve"] is False
    assert s["adjoint_solves"]["solved"] == 0 and s["adjoint_solves"]["skipped_self_adjoint"] >= 1


def test_self_adjoint_shortcut_gives_the_solved_gradient():
    """The compliance gradient with λ = u/s equals the one with the adjoint solved."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.threads import compute

    case = get_case("mbb")
    params = case.defaults.with_overrides({"nelx": "24", "nely": "8"})
    with compute(threads=1):
        problem = build_problem(case, params)
        x = np.random.default_rng(5).uniform(0.2, 1.0, problem.field.n)
        f0, _, g0, _ = problem.evaluate(x)
        assert problem.mech.adjoint_solves_skipped == 1 and problem.mech.adjoint_solves == 0
        problem.mech._f_unit = None  # no shortcut from here on
        f1, _, g1, _ = problem.evaluate(x)
        assert problem.mech.adjoint_solves == 1
    assert f1 == f0
    assert np.max(np.abs(g1 - g0)) <= 1e-10 * np.max(np.abs(g0))
