"""Nonlinear mechanics on the cantilever and the inverter, through the ``pacto`` command.

Fast: one smoke run per mechanics model (2 optimisation iterations on a tiny mesh).
Slow (``-m slow``): Neo-Hookean and Wang cantilevers at 144 kN converge with filter +
projection and lower the end compliance; the Neo-Hookean inverter at 0.4 N moves its output
against the input; a too-high load ends in a clean Newton failure (exit 1, one line, all files).
"""
import csv
import json
import math
import subprocess
import sys

import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

OUTPUT_FILES = ("params.json", "checkpoint.npz", "summary.json", "history.csv", "design.vtu",
                "design.png", "convergence.png")


def run_cli(*args, timeout=600):
    return subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args], capture_output=True,
                          text=True, timeout=timeout)


def summary(path):
    return json.loads((path / "summary.json").read_text())


# ---- fast smoke tests ---------------------------------------------------------------------
@pytest.mark.parametrize("model", ["linear", "gnl", "neohookean", "wang"])
def test_cantilever_smoke_two_iterations(model, tmp_path):
    out = tmp_path / model
    rc = main(["run", "--no-part", "cantilever", "--model", model, "--load", "144e3", "--nelx", "16",
               "--nely", "4", "--iterations", "2", "--out", str(out), "--quiet"])
    assert rc == 0
    s = summary(out)
    assert s["model"] == model and s["iterations"] == 2 and s["stopped"] == "iterations"
    assert s["load_reached"] == pytest.approx(144e3)
    assert all(math.isfinite(v) and v > 0 for v in s["objective_history"])
    # the first MMA step from the uniform design lowers the compliance
    assert s["objective_history"][1] < s["objective_history"][0]
    if model == "linear":
        assert s["newton_iterations_total"] <= 2  # one linear solve per iteration
    else:
        assert s["newton_iterations"][0] >= 2  # a real Newton solve from u = 0
    for name in ("summary.json", "history.csv", "design.png"):
        assert (out / name).is_file()


# ---- slow studies ----------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.parametrize("model", ["neohookean", "wang"])
def test_cantilever_144kN_converges_with_filter_and_projection(model, tmp_path):
    out = tmp_path / model
    # converged at iteration 135 (Neo-Hookean, order 1) and 201 (Wang, order 2) on 2026-12-02;
    # the cap of 120 these runs had before did not reach the convergence test (also with the
    # code of 2026-12-01: the same objective to 1e-10)
    rc = main(["run", "--no-part", "cantilever", "--model", model, "--load", "144e3", "--maxh", "0.04",
               "--iterations", "250", "--set", "beta_every=6", "--out", str(out), "--quiet"])
    assert rc == 0
    s = summary(out)
    assert s["parameters"]["filter"] == "helmholtz" and s["parameters"]["beta"] > 0
    assert s["converged"] is True and s["stopped"] == "converged", s["message"]
    with open(out / "history.csv") as fh:
        hist = list(csv.DictReader(fh))
    assert float(hist[-1]["beta"]) == 16.0 and float(hist[-1]["penal"]) == 3.0
    assert s["load_reached"] == pytest.approx(144e3)
    assert s["objective"] < 0.5 * s["objective_history"][0]
    assert s["volume_fraction"] <= 0.5 + 1e-3


@pytest.mark.slow
def test_inverter_neohookean_04N_moves_against_input(tmp_path):
    out = tmp_path / "inv"
    # measured (docs/studies.md): 4 iterations at β = 1 complete at 0.4 N; with β raised
    # to 4 by iteration 6 (--set beta_every=3) Newton fails at iteration 7
    rc = main(["run", "--no-part", "inverter", "--model", "neohookean", "--load", "0.4", "--maxh", "3e-6",
               "--iterations", "4", "--out", str(out), "--quiet"])
    assert rc == 0
    s = summary(out)
    assert s["load_reached"] == pytest.approx(0.4)
    # output_displacement is -u_x at the output port: positive = against the +x input force
    assert s["output_displacement"] > 1e-6
    assert s["objective"] == pytest.approx(-s["output_displacement"])


@pytest.mark.slow
def test_too_high_load_ends_in_clean_newton_failure(tmp_path):
    out = tmp_path / "fail"
    # measured (docs/studies.md): the thesis mesh at 300 kN fails at iteration 5 after
    # reaching load factor 0.427, so the failure comes after iterations with a history; the
    # stop at the failure is load_adapt=0 (the default goes on at the load reached)
    r = run_cli("run", "--no-part", "cantilever", "--model", "neohookean", "--load", "300e3", "--maxh", "0.01",
                "--iterations", "8", "--set", "beta_every=6", "--set", "load_adapt=0",
                "--out", str(out), "--quiet", timeout=1200)
    assert r.returncode == 1, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    lines = [ln for ln in (r.stdout + r.stderr).splitlines() if ln.strip()]
    assert len(lines) == 1, lines
    assert lines[0].startswith("run stopped:") and "reached load factor" in lines[0]
    for name in OUTPUT_FILES:
        assert (out / name).is_file(), name
    s = summary(out)
    assert s["stopped"] == "newton" and s["converged"] is False
    assert s["iterations"] >= 1 and len(s["newton_iterations"]) == s["iterations"]
    assert all(math.isfinite(v) for v in s["objective_history"])


def _scalar(m, name):
    import numpy as np

    return np.asarray(m.point_data[name]).reshape(-1)


def _element_gradients(m):
    """∇u of each P1 triangle of a design.vtu (points are per element) from its vertex data."""
    import numpy as np

    tri = m.cells[0].data
    X, U = m.points[tri][:, :, :2], m.point_data["u"][tri][:, :, :2]
    dX = np.stack([X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]], axis=2)  # columns: edge vectors
    dU = np.stack([U[:, 1] - U[:, 0], U[:, 2] - U[:, 0]], axis=2)
    return dU @ np.linalg.inv(dX), tri


def test_design_vtu_holds_green_lagrange_strain_and_second_piola_kirchhoff_stress(tmp_path):
    """design.vtu's E_GL and S of a Neo-Hookean cantilever equal ½(FᵀF - I) and the closed
    form μ(I - C⁻¹) + λ ln J C⁻¹ (plane strain) computed here from the written u and ρ̄."""
    import meshio
    import numpy as np

    out = tmp_path / "nh"
    assert main(["run", "--no-part", "cantilever", "--model", "neohookean", "--load", "3e5", "--maxh", "0.05",
                 "--iterations", "1", "--out", str(out), "--quiet"]) == 0
    m = meshio.read(out / "design.vtu")
    G, tri = _element_gradients(m)
    F = np.eye(2) + G
    C = np.einsum("eki,ekj->eij", F, F)
    E = 0.5 * (C - np.eye(2))
    rho = _scalar(m, "rho_bar")[tri[:, 0]]
    Emod = 3e3 + rho ** 3 * (3e9 - 3e3)
    mu, lam = Emod / 2.8, Emod * 0.4 / (1.4 * 0.2)
    Ci = np.linalg.inv(C)
    S = mu[:, None, None] * (np.eye(2) - Ci) + (lam * np.log(np.linalg.det(F)))[:, None, None] * Ci
    assert np.abs(E).max() > 1e-2  # a real deformation (measured 0.26; errors 6e-15)
    for comp, (i, j) in (("xx", (0, 0)), ("yy", (1, 1)), ("xy", (0, 1))):
        e_vtu = _scalar(m, f"E_GL_{comp}")[tri[:, 0]]
        s_vtu = _scalar(m, f"S_{comp}")[tri[:, 0]]
        assert np.abs(e_vtu - E[:, i, j]).max() < 1e-6 * np.abs(E).max()
        assert np.abs(s_vtu - S[:, i, j]).max() < 1e-6 * np.abs(S).max()


def test_design_vtu_holds_the_wang_strains(tmp_path):
    """Wang: E_W1 = ε + γ² ½GᵀG and E_W2 = ε + γ ½GᵀG (thesis eqs 5.4-5.5) from the written u:
    in solid (γ = 1) both equal E_GL, in void (γ = 0) both equal ε."""
    import meshio
    import numpy as np

    out = tmp_path / "w"
    # order 1: the check reads one displacement gradient per triangle from design.vtu
    assert main(["run", "--no-part", "cantilever", "--model", "wang", "--load", "3e5", "--maxh", "0.05",
                 "--order", "1", "--iterations", "1", "--out", str(out), "--quiet"]) == 0
    m = meshio.read(out / "design.vtu")
    G, tri = _element_gradients(m)
    eps = 0.5 * (G + np.swapaxes(G, 1, 2))
    quad = 0.5 * np.einsum("eki,ekj->eij", G, G)
    rho = _scalar(m, "rho_bar")[tri[:, 0]]
    t = np.tanh
    gam = (t(0.1) + t(100 * (rho ** 3 - 0.001))) / (t(0.1) + t(100 * 0.999))
    scale = np.abs(eps).max()
    for comp, (i, j) in (("xx", (0, 0)), ("yy", (1, 1)), ("xy", (0, 1))):
        w1 = _scalar(m, f"E_W1_{comp}")[tri[:, 0]]
        w2 = _scalar(m, f"E_W2_{comp}")[tri[:, 0]]
        assert np.abs(w1 - (eps + gam[:, None, None] ** 2 * quad)[:, i, j]).max() < 1e-6 * scale
        assert np.abs(w2 - (eps + gam[:, None, None] * quad)[:, i, j]).max() < 1e-6 * scale
        assert np.all(np.isfinite(m.point_data[f"S_{comp}"]))
