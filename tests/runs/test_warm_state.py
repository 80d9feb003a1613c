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
    assert main(["run", "--no-part", *ARGS, "--iterations", "2", "--out", str(out), "--quiet"]) == 0
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


def test_a_robust_run_resumes_from_every_realisations_equilibrium(tmp_path):
    """The robust realisations' warm states go through the checkpoint too (``u_1``, ...), so
    that a resumed robust run does not ramp them from zero again (on the PneuNet at 1e6 Pa:
    214 Newton iterations for the eroded design from zero, 10 from its last equilibrium).  A
    robust Wang run stopped after 2 iterations and resumed to 4 repeats the uninterrupted
    4-iteration run to round-off (measured 1.3e-13 in x)."""
    args = ["pa-inverter", "--model", "wang", "--nelx", "20", "--nely", "10", "--load", "3e5",
            "--set", "robust=2"]
    full, part = tmp_path / "full", tmp_path / "part"
    assert main(["run", "--no-part", *args, "--iterations", "4", "--out", str(full), "--quiet"]) == 0
    assert main(["run", "--no-part", *args, "--iterations", "2", "--out", str(part), "--quiet"]) == 0
    with np.load(part / "checkpoint.npz") as ck:
        u1, warm1 = ck["u_1"].copy(), bool(ck["warm_1"])
    assert warm1 and np.abs(u1).max() > 0
    case = get_case("pa-inverter")
    problem = build_problem(case, case.parameters({"model": "wang", "nelx": 20, "nely": 10,
                                                   "load": 3e5, "robust": 2}))
    load_checkpoint(part / "checkpoint.npz", problem)
    assert np.array_equal(problem.extra_mechanics[0].state.u, u1)
    assert main(["resume", str(part), "--iterations", "4", "--quiet"]) == 0
    with np.load(full / "checkpoint.npz") as a, np.load(part / "checkpoint.npz") as b:
        assert int(a["k"]) == int(b["k"]) == 4
        np.testing.assert_allclose(b["x"], a["x"], rtol=0, atol=1e-12)


def test_a_checkpoint_from_before_a_history_column_resumes_and_writes_history(nh_run, tmp_path):
    """A run resumed from a checkpoint whose rows lack a column added since (``design_cuts``)
    writes history.csv with every row, that column empty in the old rows (before: a traceback
    at the end of the run, nothing written), and ``load_result`` reads it (NaN there)."""
    import json

    from pacto_ng.api import load_result

    old = tmp_path / "old"
    old.mkdir()
    for name in ("params.json", "checkpoint.npz"):
        (old / name).write_bytes((nh_run / name).read_bytes())
    with np.load(old / "checkpoint.npz") as ck:
        arrays = {k: ck[k] for k in ck.files}
    rows = json.loads(str(arrays["history"]))
    for row in rows:
        del row["design_cuts"]
    arrays["history"] = json.dumps(rows)
    np.savez(old / "checkpoint.npz", **arrays)
    assert main(["resume", str(old), "--iterations", "3", "--quiet"]) == 0
    lines = (old / "history.csv").read_text().splitlines()
    header = lines[0].split(",")
    cuts = header.index("design_cuts")
    assert len(lines) == 4
    assert [line.split(",")[cuts] for line in lines[1:]] == ["", "", "0"]
    result = load_result(old)
    assert np.isnan(result.history[0]["design_cuts"]) and result.history[2]["design_cuts"] == 0
