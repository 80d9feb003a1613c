"""What ``pacto evaluate`` reports: every response it computed, Newton's own iterations, and a
failed analysis written down (exit 1) instead of lost."""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def _summary(folder):
    return json.loads((folder / "summary.json").read_text())


def test_the_strain_energy_of_a_compliance_run_is_half_its_compliance(tmp_path):
    """Linear elasticity under a force without springs: f·u = 2 SE (Clapeyron), so the reported
    strain energy, which the compliance chain does not compute, must be half the compliance."""
    np.save(tmp_path / "rho.npy", np.full((4, 12), 0.7))
    out = tmp_path / "ev"
    assert main(["evaluate", "cantilever", "--nelx", "12", "--nely", "4", "--density",
                 str(tmp_path / "rho.npy"), "--out", str(out), "--quiet"]) == 0
    s = _summary(out)
    assert s["objective_name"] == "compliance"
    assert s["strain_energy"] == pytest.approx(0.5 * s["compliance"], rel=1e-8)


def test_a_neohookean_evaluation_reports_its_newton_iterations(tmp_path):
    np.save(tmp_path / "rho.npy", np.full((10, 20), 0.5))
    out = tmp_path / "ev"
    assert main(["evaluate", "pa-inverter", "--model", "neohookean", "--nelx", "20", "--nely",
                 "10", "--density", str(tmp_path / "rho.npy"), "--out", str(out),
                 "--quiet"]) == 0
    s = _summary(out)
    assert s["newton_iterations_total"] >= 2  # a nonlinear solve takes more than one step
    assert s["newton_iterations_total"] == sum(s["newton_iterations"])


def test_a_failed_evaluation_writes_the_load_it_reached(tmp_path, capsys):
    # the continuation gives up at an increment of 0.1 of the load: it stops at 0.25 after 104
    # Newton iterations (measured; 0.05 stopped at 0.84 after 190)
    np.save(tmp_path / "rho.npy", np.full((10, 20), 0.5))
    out = tmp_path / "ev"
    code = main(["evaluate", "pa-inverter", "--model", "neohookean", "--nelx", "20", "--nely",
                 "10", "--load", "1e10", "--set", "newton_min_increment=0.1", "--density",
                 str(tmp_path / "rho.npy"), "--out", str(out), "--quiet"])
    assert code == 1
    s = _summary(out)
    assert s["converged"] is False and s["stopped"] == "newton"
    assert 0 <= s["load_factor_reached"] < 1
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) <= 2 and "load" in err[-1]


@pytest.mark.parametrize("array, words", [
    (np.full((8, 12, 1), 0.5), "shape (8, 12, 1)"),
    (np.full(96, 0.5 + 0.1j), "complex"),
    (np.full((12, 8), 0.5), "12 x 8 grid"),
])
def test_density_arrays_of_other_shapes_or_types_are_refused(tmp_path, capsys, array, words):
    np.save(tmp_path / "rho.npy", array)
    assert main(["evaluate", "pa-inverter", "--nelx", "12", "--nely", "8", "--density",
                 str(tmp_path / "rho.npy"), "--out", str(tmp_path / "ev")]) == 2
    assert words in capsys.readouterr().err


def test_a_grid_is_read_top_row_first(tmp_path):
    """The nely x nelx grid and the same values as one column in NGSolve's element order (row 0
    of the grid is the top row of elements; NGSolve numbers from the bottom) give one result:
    equal but for the round-off of a parallel assembly (two threads sum in a varying order;
    rows read in the wrong order change the objective in its first digits)."""
    rng = np.random.default_rng(3)
    grid = rng.uniform(0.2, 1.0, (8, 12))
    np.save(tmp_path / "grid.npy", grid)
    np.save(tmp_path / "column.npy", grid[::-1].reshape(-1, 1))
    objectives = []
    for name in ("grid", "column"):
        out = tmp_path / name
        assert main(["evaluate", "pa-inverter", "--nelx", "12", "--nely", "8", "--density",
                     str(tmp_path / f"{name}.npy"), "--out", str(out), "--quiet"]) == 0
        objectives.append(_summary(out)["objective"])
    assert objectives[0] == pytest.approx(objectives[1], rel=1e-12, abs=0)
