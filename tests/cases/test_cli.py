"""The pacto command: listing, parameters, bad input (one line, exit 2), evaluate, resume."""
import json
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args], capture_output=True,
                          text=True, timeout=300)


def test_cases_lists_every_case(capsys):
    assert main(["cases"]) == 0
    out = capsys.readouterr().out
    for name in ("mbb", "cantilever", "inverter"):
        assert name in out


def test_show_parameters(capsys):
    assert main(["run", "cantilever", "--show-parameters",
                 "--set", "E1=2e9"]) == 0
    out = capsys.readouterr().out
    e1 = next(line.split() for line in out.splitlines() if line.split()[:1] == ["E1"])
    assert e1[1:3] == ["2000000000", "Pa"] and "volfrac" in out  # floats to 10 digits


@pytest.mark.parametrize("args, field", [
    (["run", "nonexistent"], "unknown case"),
    (["run", "mbb", "--set", "bogus=1"], "bogus"),
    (["run", "mbb", "--set", "E1=-3"], "E1"),
    (["run", "mbb", "--set", "nu=0.5"], "nu"),
    (["run", "mbb", "--set", "volfrac=1.2"], "volfrac"),
    (["run", "mbb", "--set", "volfrac=0"], "volfrac"),
    (["run", "mbb", "--model", "rubber"], "model"),
    (["run", "mbb", "--order", "5"], "order"),
    (["evaluate", "mbb", "--density", "/nonexistent/file.npy"], "--density"),
    (["analyse", "output/any", "--set", "E1=2e9"], "--set"),
    (["analyse", "pneunet", "--as-built", "--kinds", "darcy"], "--kinds"),
    (["analyse", "pneunet", "--as-built", "--order", "5"], "--order"),
])
def test_bad_input_one_line_exit_2(args, field):
    r = run_cli(*args)
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert field in lines[0] and "Traceback" not in r.stderr


def test_unwritable_output_folder(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    r = run_cli("run", "mbb", "--nelx", "12", "--nely", "4", "--iterations", "1",
                "--out", str(blocker / "sub"))
    assert r.returncode == 2 and "--out" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_wrongly_sized_and_unreadable_density(tmp_path):
    bad = tmp_path / "d.npy"
    np.save(bad, np.ones((3, 3)))
    r = run_cli("evaluate", "mbb", "--nelx", "12", "--nely", "4", "--density", str(bad),
                "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and "4 x 12" in r.stderr
    junk = tmp_path / "d.csv"
    junk.write_text("a,b\nc,d\n")
    r = run_cli("evaluate", "mbb", "--nelx", "12", "--nely", "4", "--density", str(junk),
                "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and "cannot read" in r.stderr


def test_evaluate_matches_88_line_compliance(tmp_path):
    from top88_reference import mbb_compliance

    grid = np.random.default_rng(3).uniform(0.1, 1.0, (6, 18))
    f = tmp_path / "rho.csv"
    np.savetxt(f, grid, delimiter=",")
    out = tmp_path / "ev"
    assert main(["evaluate", "mbb", "--nelx", "18", "--nely", "6", "--density", str(f),
                 "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    ref = mbb_compliance(grid)
    assert abs(s["compliance"] - ref) / ref < 1e-8
    assert abs(s["volume_fraction"] - grid.mean()) < 1e-12
    assert (out / "design.vtu").exists()


def test_run_writes_the_output_contract(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "mbb", "--nelx", "30", "--nely", "10", "--iterations", "5", "--out",
                 str(out), "--quiet"]) == 0
    for name in ("summary.json", "history.csv", "design.vtu", "design.png", "convergence.png",
                 "checkpoint.npz", "params.json"):
        assert (out / name).exists(), name
    s = json.loads((out / "summary.json").read_text())
    for key in ("case", "model", "parameters", "iterations", "objective", "objective_history",
                "volume_fraction", "load_reached", "converged", "newton_iterations",
                "wall_time_s", "mesh", "element_order"):
        assert key in s, key
    assert s["iterations"] == 5 and len(s["objective_history"]) == 5
    assert s["objective_history"][-1] < s["objective_history"][0]


def test_resume_after_kill_gives_the_same_design(tmp_path):
    """Kill a run mid-way (a real SIGKILL), resume it, and compare with an uninterrupted run."""
    import signal

    args = ["run", "inverter", "--nelx", "30", "--nely", "15", "--iterations", "24"]
    full = tmp_path / "full"
    assert main(args + ["--out", str(full), "--quiet"]) == 0
    part = tmp_path / "part"
    proc = subprocess.Popen([sys.executable, "-m", "pacto_ng.cli", *args, "--out", str(part)],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    # wait until some iterations have been checkpointed, then kill without warning
    for line in proc.stdout:
        if line.startswith("it   10/"):
            break
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    with np.load(part / "checkpoint.npz") as ck:
        k_killed = int(ck["k"])
    assert 0 < k_killed < 24
    assert main(["resume", str(part), "--quiet"]) == 0
    a = json.loads((full / "summary.json").read_text())
    b = json.loads((part / "summary.json").read_text())
    assert b["iterations"] == a["iterations"] == 24
    assert np.allclose(a["objective_history"], b["objective_history"], rtol=1e-9, atol=0)
    # a resumed run ends with its part, as an uninterrupted one
    assert b["part"]["made"] and (part / "part.stl").is_file()
    assert b["part"]["threshold"] == a["part"]["threshold"]
    with np.load(full / "checkpoint.npz") as fa, np.load(part / "checkpoint.npz") as fb:
        assert np.max(np.abs(fa["x"] - fb["x"])) < 1e-9


def test_resume_raises_the_iteration_cap(tmp_path):
    """A run that stopped at its cap, continued with ``resume --iterations``, ends where an
    uninterrupted run with the higher cap ends; a lower cap is refused."""
    args = ["run", "inverter", "--nelx", "30", "--nely", "15", "--quiet"]
    full, part = tmp_path / "full", tmp_path / "part"
    assert main(args + ["--iterations", "20", "--out", str(full)]) == 0
    assert main(args + ["--iterations", "10", "--out", str(part)]) == 0
    t10 = json.loads((part / "summary.json").read_text())["wall_time_s"]
    assert main(["resume", str(part), "--iterations", "20", "--quiet"]) == 0
    a = json.loads((full / "summary.json").read_text())
    b = json.loads((part / "summary.json").read_text())
    assert b["iterations"] == a["iterations"] == 20
    assert b["parameters"]["iterations"] == 20
    assert np.allclose(a["objective_history"], b["objective_history"], rtol=1e-9, atol=0)
    assert b["wall_time_s"] > t10  # the first part's time is carried over
    assert main(["resume", str(part), "--iterations", "5", "--quiet"]) == 2


@pytest.mark.parametrize("args", [
    ["mbb"], ["cantilever"], ["cantilever", "--model", "neohookean", "--load", "1e5"],
    # slow (11 s and 13 s of the default run): the Wang and GNL chains are checked by default
    # in tests/gradients/test_nonlinear_gradients.py::
    # test_adjoint_matches_finite_differences[wang-*, gnl-*] (this
    # cantilever's chain), the command with the Wang model in
    # tests/cases/test_pa_cases.py::test_check_gradients_nonlinear[pa-inverter-wang-*]
    pytest.param(["cantilever", "--model", "wang", "--load", "1e5"], marks=pytest.mark.slow),
    ["inverter"],
    pytest.param(["inverter", "--model", "gnl", "--load", "0.05"], marks=pytest.mark.slow),
])
def test_check_gradients_passes(args, capsys):
    assert main(["check-gradients", *args, "--tol", "1e-5"]) == 0
    out = capsys.readouterr().out
    assert "pass" in out and "worst relative error" in out


def test_check_gradients_fails_on_a_wrong_gradient(monkeypatch, capsys):
    """The check has teeth: a deliberately broken backward pass is caught (exit 1)."""
    from pacto_ng import filters

    real = filters.HeavisideProjection.backward
    monkeypatch.setattr(filters.HeavisideProjection, "backward",
                        lambda self, g: (1.01 * real(self, g)[0],))
    assert main(["check-gradients", "cantilever", "--tol", "1e-5"]) == 1
    assert "FAIL" in capsys.readouterr().out
