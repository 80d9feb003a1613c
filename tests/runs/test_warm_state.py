"""The mechanics block's warm state (displacement, whether it is an equilibrium, Newton's first
increment of its last ramp from zero) goes through a run's checkpoint whole, and a checkpoint
written before the ramp's increment was kept is still read (the default first increment)."""
import numpy as np
import pytest

from pacto_ng.case import build_problem, get_case
from pacto_ng.cli import main
from pacto_ng.runner import load_checkpoint

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

ARGS = ["pa-inverter", "--model", "neohookean", "--nelx", "20", "--nely", "10"]


@pytest.fixture(scope="module")
def nh_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("warm") / "nh"
    assert main(["run", *ARGS, "--iterations", "2", "--out", str(out), "--quiet"]) == 0
    return out


def _problem():
    case = get_case("pa-inverter")
    return build_problem(case, case.parameters({"model": "neohookean", "nelx": 20,
                                                "nely": 10}))


def test_the_checkpoint_restores_the_whole_warm_state(nh_run):
    with np.load(nh_run / "checkpoint.npz") as ck:
        u, warm, ramp = ck["u"].copy(), bool(ck["warm"]), float(ck["ramp_first"])
    assert warm and 0 < ramp <= 1  # the first design was ramped from zero
    problem = _problem()
    load_checkpoint(nh_run / "checkpoint.npz", problem)
    state = problem.mech.state
    assert state.converged and state.ramp_first == ramp
    assert np.array_equal(state.u, u) and np.abs(u).max() > 0


def test_a_checkpoint_without_the_ramp_increment_is_read_and_resumed(nh_run, tmp_path):
    old = tmp_path / "old"
    old.mkdir()
    for name in ("params.json", "checkpoint.npz"):
        (old / name).write_bytes((nh_run / name).read_bytes())
    with np.load(old / "checkpoint.npz") as ck:
        arrays = {k: ck[k] for k in ck.files if k != "ramp_first"}
    np.savez(old / "checkpoint.npz", **arrays)
    problem = _problem()
    load_checkpoint(old / "checkpoint.npz", problem)
    state = problem.mech.state
    assert state.converged and state.ramp_first is None
    assert np.array_equal(state.u, arrays["u"])
    assert main(["resume", str(old), "--iterations", "3", "--quiet"]) == 0
    with np.load(old / "checkpoint.npz") as ck:
        assert int(ck["k"]) == 3 and "ramp_first" in ck.files
