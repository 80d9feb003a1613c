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

import meshio
import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

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
#: the cases whose default is the robust formulation: their objective is the worst case
OBJECTIVE = {"pa-inverter": "worst_case"}


@pytest.mark.parametrize("case", ["pa-inverter", "pa-gripper", "pneunet", "mm-gripper"])
def test_smoke_run(case, tmp_path):
    out = tmp_path / case
    assert main(["run", "--no-part", case, *COARSE[case], "--iterations", "6", "--out", str(out),
                 "--quiet"]) == 0
    summ = _check_run(out, 6)
    assert summ["load_unit"] == "Pa" and summ["objective_name"] == OBJECTIVE.get(case,
                                                                                "objective")
    if case == "mm-gripper":
        assert (out / "materials.png").is_file()
        mf = summ["material_fractions"]
        assert abs(mf["material1_soft"] + mf["material2_stiff"] - mf["solid"]) < 1e-12
        assert abs(mf["solid"] - summ["volume_fraction"]) < 1e-12


@pytest.mark.slow
@pytest.mark.parametrize("case", ["pa-inverter", "pa-gripper", "pneunet", "mm-gripper"])
def test_default_run_gives_a_working_mechanism(case, tmp_path):
    """The full default run (the case's mesh, 160 iterations, linear): the output moves the
    working way, the volume is met, the objective improved, the design is nearly black and
    white and the pressure stays in the cavity and its skin."""
    out = tmp_path / case
    assert main(["run", "--no-part", case, "--out", str(out), "--quiet"]) == 0
    summ = _check_run(out, 160)
    assert summ["output_displacement"] > 0.0
    assert summ["volume_fraction"] <= 0.2 + 0.002
    obj = [float(h["objective"]) for h in _history(out)]
    assert obj[-1] < min(0.0, obj[0])
    data = meshio.read(out / "design.vtu").point_data
    rho = np.asarray(data["rho_bar"] if "rho_bar" in data else data["rho_bar1"])
    grey = float(np.mean((rho > 0.1) & (rho < 0.9)))
    assert grey < 0.1, grey
    assert summ["leakage"] < 0.05


def test_smoke_structured_and_unit_elements(tmp_path):
    """Structured quads on the physical domain, and the unit-element set-up of the MATLAB
    codes (1 x 1 elements, plane stress, E = 1, P_in = 1, Δs and k_out in element units)."""
    out = tmp_path / "quads"
    assert main(["run", "--no-part", "pa-gripper", "--nelx", "40", "--nely", "20", "--iterations", "6",
                 "--out", str(out), "--quiet"]) == 0
    summ = _check_run(out, 6)
    assert summ["mesh"]["structured"] and summ["mesh"]["elements"] == 800
    out = tmp_path / "unit"
    assert main(["run", "--no-part", "pa-inverter", "--nelx", "40", "--nely", "20", "--iterations", "6",
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
    # the output spring and port spread over the right edge's first 0.02 m (output_width)
    ("pa-inverter", ["--nelx", "30", "--nely", "15", "--set", "output_width=0.02"]),
])
def test_check_gradients(case, extra, capsys):
    assert main(["check-gradients", case, "--set", "load_sensitivity=1", *extra]) == 0
    out = capsys.readouterr().out
    assert "pass" in out and f"d({OBJECTIVE.get(case, 'objective')})/dx" in out
    if "output_se" in extra:
        assert "d(se_limit)/dx" in out
    if "volfrac2=0.1" in extra:
        assert "d(volume2)/dx" in out


#: The check's random grey design (x in [0.3, 0.7] at the final β = 32) of the PneuNet has void
#: patches (E0 = 1e-6 E1 = 100 Pa) beside pressure gradients.  A follower load's own stiffness
#: there (of the order of the pressure) exceeds the void's material stiffness once the inlet
#: pressure is ~1e4 Pa, and with Neo-Hookean void Newton finds no equilibrium (load factor
#: 0.56 of 1e4 Pa; measured 2026-12-01).  With E0 = 1e4 Pa the same check converges at 1e4 Pa
#: and passes (1.1e-9), which supports that reading; the Wang model, whose follower load sees
#: I + γ∇u (the fixed load in void, ``follower_wang``), passes at the default 1e5 Pa.  The
#: Neo-Hookean follower chain is therefore checked at 1e3 Pa here, where the equilibrium exists.
_EXTRA = {("pneunet", "neohookean", "follower"): ["--load", "1e3"]}


def _combos():
    for case in ("pa-inverter", "pa-gripper", "pneunet", "mm-gripper"):
        for model in ("neohookean", "wang"):
            for load_type in ("fixed", "follower"):
                # every model x load type runs by default on one case
                marks = [] if case == "pa-inverter" else [pytest.mark.slow]
                yield pytest.param(case, model, load_type, marks=marks,
                                   id=f"{case}-{model}-{load_type}")


@pytest.mark.parametrize("case, model, load_type", list(_combos()))
def test_check_gradients_nonlinear(case, model, load_type, capsys):
    """The whole chain x -> ... -> p -> u -> objective and constraints, for every pressure case
    with each nonlinear model and each Darcy load type, against central finite differences."""
    code = main(["check-gradients", case, "--model", model, "--set", f"load_type={load_type}",
                 *_EXTRA.get((case, model, load_type), [])])
    out = capsys.readouterr().out
    assert code == 0, out[-2000:]
    assert "pass" in out and f"{case}/{model}: d({OBJECTIVE.get(case, 'objective')})/dx" in out


def test_output_width_spreads_the_spring_and_port_over_an_edge():
    """output_width > 0: the boundary "output_edge" (the right edge's first output_width) takes
    the spring and the port (Δ = the edge's mean of -u_x) and gets zero pressure; a width not
    shorter than the edge is a one-line error naming output_width."""
    from ngsolve import BND, Integrate

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.params import InputError
    from pacto_ng.threads import compute

    case = get_case("pa-inverter")
    params = case.defaults.with_overrides({"nelx": "30", "nely": "15", "output_width": "0.02"})
    setup = case.setup(params)
    assert setup.port.region == "output_edge" and setup.springs[0].region == "output_edge"
    assert "output_edge" in setup.pressure.zero
    with compute():
        problem = build_problem(case, params)
        mesh = problem.mech.mesh
        assert Integrate(1.0, mesh, BND, definedon=mesh.Boundaries("output_edge")) \
            == pytest.approx(0.02, rel=1e-12)
        problem.evaluate(np.full(problem.field.n, 0.4))
        u = problem.mech.gfu
        mean_ux = Integrate(u[0], mesh, BND, definedon=mesh.Boundaries("output_edge")) / 0.02
        assert float(problem.values["delta"]) == pytest.approx(-mean_ux, rel=1e-10)
    with pytest.raises(InputError, match="^output_width"):
        build_problem(case, case.defaults.with_overrides({"output_width": "0.1"}))
