"""The pressure-actuated cases (pa-inverter, pa-gripper, pneunet, mm-gripper).

Fast: a few optimisation iterations per case on a coarse mesh (objective goes down, every
output file written, leakage and material fractions in summary.json), the finite-difference
gradient check of each case's full chain with the load sensitivity on, the leakage figure on
hand-made designs, and bad input through the CLI (one line on stderr, exit code 2).
Slow (``-m slow``): each case's default run must give a working mechanism.
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.cli import main

COARSE = {"pa-inverter": ["--maxh", "0.01"], "pa-gripper": ["--maxh", "0.01"],
          "pneunet": ["--maxh", "0.005"], "mm-gripper": ["--maxh", "0.01"]}
OUTPUTS = ("summary.json", "history.csv", "design.vtu", "design.png", "convergence.png",
           "pressure.png", "checkpoint.npz", "params.json")


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args], capture_output=True,
                          text=True, timeout=300)


def _history(out):
    with open(out / "history.csv") as fh:
        return list(csv.DictReader(fh))


def _check_run(out, n_iterations):
    for name in OUTPUTS:
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert (out / "pressure.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summ = json.loads((out / "summary.json").read_text())
    hist = _history(out)
    assert len(hist) == summ["iterations"] == n_iterations
    obj = [float(h["objective"]) for h in hist]
    assert obj[-1] < obj[0], obj
    assert isinstance(summ["leakage"], float) and 0.0 <= summ["leakage"] <= 1.0
    assert summ["leakage_detail"]["skin"] > 0 and summ["leakage_detail"]["cavity_elements"] > 0
    return summ


# ---- smoke tests -------------------------------------------------------------------------
@pytest.mark.parametrize("case", ["pa-inverter", "pa-gripper", "pneunet", "mm-gripper"])
def test_smoke_run(case, tmp_path):
    out = tmp_path / case
    assert main(["run", case, *COARSE[case], "--iterations", "6", "--out", str(out),
                 "--quiet"]) == 0
    summ = _check_run(out, 6)
    assert summ["load_unit"] == "Pa" and summ["objective_name"] == "objective"
    if case == "mm-gripper":
        assert (out / "materials.png").is_file()
        mf = summ["material_fractions"]
        assert abs(mf["material1_soft"] + mf["material2_stiff"] - mf["solid"]) < 1e-12
        assert abs(mf["solid"] - summ["volume_fraction"]) < 1e-12


def test_smoke_structured_and_unit_elements(tmp_path):
    """Structured quads on the physical domain, and the unit-element set-up of the MATLAB
    codes (1 x 1 elements, plane stress, E = 1, P_in = 1, Δs and k_out in element units)."""
    out = tmp_path / "quads"
    assert main(["run", "pa-gripper", "--nelx", "40", "--nely", "20", "--iterations", "6",
                 "--out", str(out), "--quiet"]) == 0
    summ = _check_run(out, 6)
    assert summ["mesh"]["structured"] and summ["mesh"]["elements"] == 800
    out = tmp_path / "unit"
    assert main(["run", "pa-inverter", "--nelx", "40", "--nely", "20", "--iterations", "6",
                 "--set", "unit_elements=1", "--set", "plane=stress", "--set", "E1=1",
                 "--set", "E0=1e-6", "--set", "load=1", "--set", "delta_s=1",
                 "--set", "filter_radius=2.5",
                 "--set", "k_out=0.01", "--set", "thickness=1",
                 "--out", str(out), "--quiet"]) == 0
    summ = _check_run(out, 6)
    assert summ["mesh"]["h"] == 1.0 and summ["parameters"]["plane"] == "stress"


# ---- gradients -----------------------------------------------------------------------------
@pytest.mark.parametrize("case, extra", [
    ("pa-inverter", []),
    ("pa-gripper", []),
    ("pneunet", []),
    ("mm-gripper", []),
    ("mm-gripper", ["--set", "volfrac2=0.1"]),
    ("pa-gripper", ["--set", "objective=output_se"]),
    ("pa-inverter", ["--nelx", "16", "--nely", "8"]),
])
def test_check_gradients(case, extra, capsys):
    assert main(["check-gradients", case, "--set", "load_sensitivity=1", *extra]) == 0
    out = capsys.readouterr().out
    assert "pass" in out and "d(objective)/dx" in out
    if "output_se" in extra:
        assert "d(se_limit)/dx" in out
    if "volfrac2=0.1" in extra:
        assert "d(volume2)/dx" in out


@pytest.mark.parametrize("load_type", ["fixed", "follower"])
@pytest.mark.parametrize("model", ["neohookean", "wang"])
@pytest.mark.parametrize("case", ["pa-inverter", "pa-gripper", "pneunet", "mm-gripper"])
def test_check_gradients_nonlinear(case, model, load_type, capsys):
    """The whole chain x -> ... -> p -> u -> objective and constraints, for every pressure case
    with each nonlinear model and each Darcy load type, against central finite differences."""
    code = main(["check-gradients", case, "--model", model, "--set", f"load_type={load_type}"])
    out = capsys.readouterr().out
    assert code == 0, out[-2000:]
    assert "pass" in out and f"{case}/{model}: d(objective)/dx" in out


def test_check_gradients_sees_a_missing_load_sensitivity(capsys):
    """Without the Darcy load sensitivity the gradient is wrong, and the check says so."""
    assert main(["check-gradients", "pa-inverter", "--set", "load_sensitivity=0"]) == 1
    assert "FAIL" in capsys.readouterr().out


# ---- leakage --------------------------------------------------------------------------------
def _leakage_of(wall_density):
    """pa-inverter mesh; the cavity x < 0.06, y < 0.08 (void, open to the inlet) closed by a
    wall of density ``wall_density`` (x < 0.08 outside it), then void, a solid block on
    0.14 <= x < 0.16, void."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.physics.darcy import leakage

    case = get_case("pa-inverter")
    pb = build_problem(case, case.defaults.with_overrides({"maxh": "0.0025"}))
    cx, cy = pb.field.centroids().T
    rho = np.where((cx < 0.08) & ((cx >= 0.06) | (cy >= 0.08)), wall_density, 0.0)
    rho[(cx >= 0.14) & (cx < 0.16)] = 1.0
    rho[pb.field.solid] = 1.0
    pb.chain.forward(rho_bar=rho)
    blk = pb.pressure_block
    pv = blk.gfp.vec.FV().NumPy()[:pb.mesh.nv] / blk.p_in
    wet_face = max((pv[[v.nr for v in el.vertices]].mean()
                    for el, r, x, y in zip(pb.mesh.Elements(), rho, cx, cy)
                    if r >= 0.9 and x < 0.07 and y < 0.08), default=0.0)
    return leakage(blk, rho, pb.h), wet_face


def test_leakage_sealed_wall_and_grey_wall():
    sealed, wet_face = _leakage_of(1.0)
    assert wet_face > 0.5  # the wall's wet face carries the pressure: not counted as leakage
    assert sealed["leakage"] < 1e-3 and sealed["leakage_any"] < 1e-3
    assert sealed["cavity_elements"] > 0 and sealed["elements_checked"] > 0
    # ρ̄ = 0.6 is not a wall for the pressure (thesis B.5: it drops where ρ̄ > 0.6): the
    # pressure runs through the grey top wall to the passive clamp block beyond the skin
    grey, _ = _leakage_of(0.6)
    assert grey["leakage"] > 0.1
    assert grey["leakage_any"] >= grey["leakage"] and grey["where"][1] > 0.08


# ---- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize("args, field", [
    (["run", "pa-inverter", "--maxh", "0.02", "--set", "inlet=nowhere"], "inlet"),
    (["run", "pneunet", "--set", "delta_s=-0.001"], "delta_s"),
    (["run", "pa-gripper", "--set", "Ks=1"], "Ks"),
    (["run", "pa-gripper", "--set", "Ks=2"], "Ks"),
    (["run", "mm-gripper", "--set", "r=1.5"], "r:"),
    (["run", "pa-inverter", "--set", "r=0"], "r:"),
    (["run", "mbb", "--set", "inlet=inlet", "--iterations", "1"], "inlet"),
])
def test_bad_input_one_line_exit_2(args, field, tmp_path):
    r = run_cli(*args, "--out", str(tmp_path / "o"))
    assert r.returncode == 2, r.stderr
    lines = [ln for ln in r.stderr.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert field in lines[0] and "Traceback" not in r.stderr


# ---- full runs (slow) ------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("case, mesh", [
    ("pa-inverter", []), ("pa-gripper", []), ("pneunet", []), ("mm-gripper", []),
    ("pa-inverter", ["--nelx", "120", "--nely", "60"]),
    ("pa-gripper", ["--nelx", "120", "--nely", "60"]),
    ("pneunet", ["--nelx", "120", "--nely", "60"]),
    ("mm-gripper", ["--nelx", "120", "--nely", "60"]),
])
def test_full_run_gives_a_working_mechanism(case, mesh, tmp_path):
    out = tmp_path / case
    assert main(["run", case, "--model", "linear", *mesh, "--out", str(out), "--quiet"]) == 0
    summ = json.loads((out / "summary.json").read_text())
    assert summ["output_displacement"] > 0  # Δ = -u_x (inverter), -u_y (gripper, PneuNet)
    assert summ["leakage"] < 0.05
    assert summ["volume_fraction"] <= summ["parameters"]["volfrac"] * 1.01
    if case == "mm-gripper":
        mf = summ["material_fractions"]
        assert mf["material1_soft"] > 0.02 and mf["material2_stiff"] > 0.02
