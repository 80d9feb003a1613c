"""Neo-Hookean pressure-actuated design beyond the thesis's pressure limit (slow).

The thesis (COMSOL) could not optimise the pressure-actuated inverter with the Neo-Hookean model
above 1e7 Pa: the grey designs of the first iterations deform excessively under the full load.
pacto_ng ramps the load over the first iterations (``load_ramp``), warm-starts Newton from the
previous equilibrium and cuts its load increments; the Wang model (Neo-Hookean in solid, linear
in void) keeps the near-void elements from inverting (plain Neo-Hookean with the same settings
stopped at iteration 46 with a Newton failure, measured).  This test reproduces the result of
docs/studies.md ("Nonlinear pressure-actuated design and extreme pressures") on its coarse
mesh: the run finishes without a Newton failure at the full load, meets the volume constraint,
improves the objective over iteration 0 and moves the output the desired way (Δ = -u_x > 0).

Run with ``pytest -m slow tests/cases/test_extreme_pressure.py`` (the same run from the CLI took
260 s on a loaded 2-core machine).
"""
from __future__ import annotations

import json

import pytest

from pacto_ng.cli import main

PRESSURE = 1e7  # Pa; the thesis's Neo-Hookean limit for pa-inverter is 1e7 Pa
ARGS = ["--model", "wang", "--load", str(PRESSURE), "--maxh", "0.008", "--iterations", "80",
        "--set", "filter_radius=0.024", "--set", "load_ramp=20", "--set", "newton_increment=0.25"]


@pytest.mark.slow
def test_pa_inverter_wang_high_pressure(tmp_path):
    out = tmp_path / "pa-inverter-wang"
    assert main(["run", "--no-part", "pa-inverter", *ARGS, "--out", str(out), "--quiet"]) == 0
    summ = json.loads((out / "summary.json").read_text())
    assert summ["stopped"] != "newton", summ["message"]
    assert summ["load_reached"] == pytest.approx(PRESSURE)  # the full pressure, not a cut one
    assert summ["volume_fraction"] <= summ["parameters"]["volfrac"] * 1.01
    hist = summ["objective_history"]
    # iteration 0 (uniform design, 1/20 of the load) moves the output with the pressure (Δ < 0,
    # objective > 0); the design must turn it round
    assert summ["objective"] < hist[0]
    assert summ["objective"] < 0
    assert summ["output_displacement"] > 0  # Δ = -u_x: the output moves towards the inlet


@pytest.mark.slow
@pytest.mark.parametrize("model, extra", [
    ("wang", []),
    ("neohookean", ["--set", "E0=3e5"]),  # plain Neo-Hookean with a void of 1e-4 E1
])
def test_pa_inverter_5e7_pa_on_the_thesis_mesh(model, extra, tmp_path):
    """5e7 Pa (five times the thesis's limit) on the thesis mesh with the load ramped over the
    first 100 of 160 iterations (docs/studies.md, runs inv_w_5e7_r100 and
    inv_nh_5e7_e4_r100: 83 s and 47 s): a valid design at the full load, and its part,
    thresholded at 0.4, reaches the output and moves it the working way under a Neo-Hookean
    analysis at 5e7 Pa with the follower pressure."""
    from pacto_ng.post.analyse import analyse_run

    out = tmp_path / model
    assert main(["run", "--no-part", "pa-inverter", "--model", model, "--order", "1", "--load", "5e7",
                 "--set", "load_ramp=100", "--set", "load_adapt=1.2", *extra, "--out", str(out),
                 "--quiet"]) == 0
    summ = json.loads((out / "summary.json").read_text())
    assert summ["load_factor_reached"] == 1.0 and summ["stopped"] != "newton", summ["message"]
    assert summ["volume_fraction"] <= 0.2 + 0.002
    assert summ["objective"] < 0 and summ["output_displacement"] > 0.03  # 42.7 / 41.4 mm
    assert analyse_run(out, pressures=[5e7], threshold_value=0.4, kinds=("follower",),
                       quiet=True) == 0
    res = json.loads((out / "analysis" / "analysis.json").read_text())
    assert res["remesh"]["output_port_shift"] < 1e-3  # the part reaches the output
    row = res["pressures"][0]
    assert row["pressure"] == 5e7 and row["follower"]["converged"]
    assert row["follower"]["delta"] > 0.03  # 50.6 / 51.3 mm measured


@pytest.fixture(scope="module")
def pneunet_1e6(tmp_path_factory):
    """The PneuNet at 1e6 Pa (ten times the thesis's limit; docs/studies.md, runs pn_lin_1e6
    and pn_w_1e6_init_b8): the linear design of that pressure, then the Wang optimisation
    started from it (``init_design``) with the schedule continued at p = 3, β = 8."""
    root = tmp_path_factory.mktemp("pneunet_1e6")
    lin, wang = root / "lin", root / "wang"
    mesh = ["--maxh", "0.003", "--load", "1e6", "--quiet"]
    assert main(["run", "--no-part", "pneunet", "--model", "linear", *mesh, "--out", str(lin)]) == 0
    assert main(["run", "--no-part", "pneunet", "--model", "wang", *mesh, "--set", f"init_design={lin}",
                 "--set", "load_ramp=30", "--set", "load_adapt=1.2", "--set", "penal_start=3",
                 "--set", "beta=8", "--out", str(wang)]) == 0
    return wang


@pytest.mark.slow
def test_pneunet_1e6_pa_from_the_linear_design(pneunet_1e6):
    """A valid design at the full load that improves on its first full-load iteration and
    moves the output down (0.43 mm measured on 2026-12-02 morning, 0.51 mm at 03:50)."""
    summ = json.loads((pneunet_1e6 / "summary.json").read_text())
    assert summ["load_factor_reached"] == 1.0 and summ["stopped"] != "newton", summ["message"]
    assert summ["volume_fraction"] <= 0.2 + 0.002
    hist = summ["objective_history"]
    assert summ["objective"] < hist[29]  # better than at its first iteration at the full load
    assert summ["output_displacement"] > 0


@pytest.fixture(scope="module")
def pneunet_1e6_part(pneunet_1e6):
    """``pacto analyse`` of that design at 1e6 Pa (threshold 0.5 asked; the connectivity check
    lowers it until the part on the clamp contains the output corner)."""
    from pacto_ng.post.analyse import analyse_run

    assert analyse_run(pneunet_1e6, pressures=[1e6], threshold_value=0.5,
                       kinds=("darcy", "fixed"), quiet=True) == 0
    return json.loads((pneunet_1e6 / "analysis" / "analysis.json").read_text())


@pytest.mark.slow
def test_pneunet_1e6_part_reaches_the_output(pneunet_1e6_part):
    """The part reaches the output corner.  Before the connectivity check of ``pacto analyse``
    the 0.5 part missed the output in three of five runs of this pipeline (by 18, 18 and 54 mm:
    its joint to the output is grey).  With it, in five runs that differ by round-off (one
    thread; machine code; two threads with machine code; two threads, twice) the threshold came
    to 0.459, 0.472, 0.459 (meshed at 0.454 after Netgen failed at 0.459), 0.5 and 0.5, and the
    port moved 0 m in each (2026-12-02)."""
    res = pneunet_1e6_part
    ch = res["settings"]["threshold_choice"]
    assert ch["reaches_output"] and not ch["missed"] and 0.1 <= ch["used"] <= 0.5
    assert res["remesh"]["output_port_shift"] < 1e-3  # the part reaches the output


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason=(
    "what the part does at 1e6 Pa is not robust, because what the design does is not (five runs "
    "of this pipeline, 2026-12-02): one design has several equilibria at 1e6 Pa (Δ = 5.1e-4 m in "
    "the optimisation, 7.3e-5 m loaded from rest in one step, 3.2e-5 m by load stepping, all "
    "converged to 1e-12), and its part moved the output -6.2e-5 m (darcy); the part of another, "
    "at threshold 0.5, balloons (max |u| 33 mm at 1e5 Pa) and its Neo-Hookean analysis fails "
    "above 1e5 Pa (fixed) and 3e5 Pa (darcy); the other three moved the output down under both "
    "loads (darcy +5.4e-5, +1.3e-4, +5.1e-5 m; fixed +2.3e-5, +9.8e-5, +6.5e-5 m)"))
def test_pneunet_1e6_part_moves_the_output_down(pneunet_1e6_part):
    """Under a Neo-Hookean analysis at 1e6 Pa, with the Darcy load and the fixed pressure, the
    part's analyses converge and move the output down."""
    row = pneunet_1e6_part["pressures"][0]
    assert row["darcy"]["converged"] and row["fixed"]["converged"]
    assert row["darcy"]["delta"] > 0 and row["fixed"]["delta"] > 0
