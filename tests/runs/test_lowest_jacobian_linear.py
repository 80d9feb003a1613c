"""summary.json's ``lowest_J`` / ``lowest_J_corners`` are null for the linear model: its
displacement is a small-strain one, det(I + ∇u) is no quantity it uses and no Newton guard
applies (a linear run at a large load reported a negative ``lowest_J``)."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("one_thread")

UNIT = ["--nelx", "12", "--nely", "8", "--set", "unit_elements=1", "--set", "plane=stress",
        "--set", "E1=1", "--set", "E0=1e-6", "--set", "thickness=0.5", "--set", "delta_s=1",
        "--set", "k_out=0.01", "--set", "filter_radius=2.5"]


def _evaluate(tmp_path, model, load):
    np.save(tmp_path / "rho.npy", np.full((8, 12), 0.5))
    out = tmp_path / model
    assert main(["evaluate", "pa-inverter", *UNIT, "--model", model, "--load", load,
                 "--density", str(tmp_path / "rho.npy"), "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


def test_a_linear_analysis_reports_no_lowest_jacobian(tmp_path):
    s = _evaluate(tmp_path, "linear", "1")  # a load at which I + ∇u folds elements
    assert s["model"] == "linear"
    assert s["lowest_J"] is None and s["lowest_J_corners"] is None


def test_a_finite_strain_model_without_a_guard_still_reports_it(tmp_path):
    s = _evaluate(tmp_path, "gnl", "0.01")
    assert s["lowest_J"]["point"] == "quadrature point" and 0 < s["lowest_J"]["J"] < 1
    assert s["lowest_J_corners"]["point"] == "vertex"
