"""``order = 0`` (the default) resolves to the case's order for the model (Case.model_orders)."""
import dataclasses

import pytest

from pacto_ng import sweep_plan
from pacto_ng.case import get_case
from pacto_ng.cli import main
from pacto_ng.params import InputError, Parameters


def test_resolve_uses_the_model_table_only_when_order_is_not_given():
    case = dataclasses.replace(get_case("mbb"), model_orders={"linear": 2})
    assert case.order_for("linear") == 2 and case.order_for("neohookean") == 1
    assert case.resolve(Parameters(model="linear")).order == 2
    assert case.resolve(Parameters(model="neohookean")).order == 1
    assert case.resolve(Parameters(model="linear", order=3)).order == 3  # given: kept
    assert case.resolve(Parameters(model="auto")).order == 0  # resolved after the choice


def test_sweep_resolves_each_model_separately():
    case = dataclasses.replace(get_case("mbb"), model_orders={"linear": 2})
    lin, nh = sweep_plan.sweep_grid(("linear", "neohookean"), (1.0,))
    assert sweep_plan.run_parameters(Parameters(), lin, case).order == 2
    assert sweep_plan.run_parameters(Parameters(), nh, case).order == 1
    assert sweep_plan.run_parameters(Parameters(order=3), nh, case).order == 3


def test_cantilever_default_orders():
    """The cantilever's linear and Wang defaults are order 2 (the knees of their trade curves:
    order 1 is 1.0 % and 1.23 % from the finest objective); gnl and Neo-Hookean keep order 1
    (docs/studies.md, "Where the defaults sit")."""
    case = get_case("cantilever")
    assert case.defaults.order == 0
    assert [case.order_for(m) for m in ("linear", "gnl", "neohookean", "wang")] == [2, 1, 1, 2]


def test_order_zero_is_accepted_and_four_is_refused():
    Parameters(order=0)
    with pytest.raises(InputError, match="^order:"):
        Parameters(order=4)


def test_summary_records_the_resolved_order(tmp_path):
    import json

    out = tmp_path / "run"
    assert main(["run", "--no-part", "cantilever", "--maxh", "0.05", "--iterations", "1", "--quiet",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    p = json.loads((out / "params.json").read_text())
    assert s["element_order"] == 2 and p["params"]["order"] == 2
