"""What a run modelled is in summary.json: the Darcy solve only for design-dependent loads, the
symmetric half domain, and the mechanics adjoints solved or skipped (compliance of fixed loads on
the linear model: the adjoint is the primal)."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main


def _summary(tmp_path, name, *args):
    out = tmp_path / name
    assert main(["run", name, *args, "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


#: (case, run options, iterations, darcy_solve, symmetric_half_domain, adjoints solved)
#: -- mbb and cantilever: compliance, every adjoint the primal (none solved, one skipped per
#: iteration at least); pa-inverter: -Δ/SE, whose adjoint is not the primal (none skipped)
RECORDS = [
    ("mbb", ["--nelx", "30", "--nely", "10"], 4, False, True, False),
    ("pa-inverter", ["--model", "linear", "--maxh", "0.01"], 2, True, True, True),
    ("cantilever", ["--model", "linear", "--maxh", "0.05"], 1, False, False, False),
]


@pytest.mark.parametrize("name, args, iterations, darcy, half, solved", RECORDS,
                         ids=[r[0] for r in RECORDS])
def test_summary_records_what_was_modelled(tmp_path, name, args, iterations, darcy, half,
                                           solved):
    s = _summary(tmp_path, name, *args, "--iterations", str(iterations))
    assert s["darcy_solve"] is darcy
    assert s["symmetric_half_domain"] is half
    done, skipped = s["adjoint_solves"]["solved"], s["adjoint_solves"]["skipped_self_adjoint"]
    assert s["iterations"] == iterations
    if solved:
        assert skipped == 0 and done >= iterations
    else:
        assert done == 0 and skipped >= iterations


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
        problem.mech.self_adjoint_shortcut = False  # no shortcut from here on
        f1, _, g1, _ = problem.evaluate(x)
        assert problem.mech.adjoint_solves == 1
    assert f1 == f0
    assert np.max(np.abs(g1 - g0)) <= 1e-10 * np.max(np.abs(g0))
