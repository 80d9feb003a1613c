"""No silent data loss (issue 18, part 3): a folder that holds a run is refused, --overwrite
removes the earlier run's files first (and nothing else), two writers of one folder are
refused, evaluate never rewrites a run, resume never rewrites params.json needlessly."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.case import read_run_params
from pacto_ng.cli import main
from pacto_ng.files import LOCK_NAME, FolderLock
from top88_reference import TOP88_OPTIMISER

MBB = ["mbb", "--nelx", "12", "--nely", "4", "--iterations", "2"]
PA = ["pa-inverter", "--nelx", "12", "--nely", "8", "--iterations", "1"]


def snapshot(folder):
    """Every file's bytes (the lock file aside)."""
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and p.name != LOCK_NAME}


def one_error_line(capsys):
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.fixture(scope="module")
def pa_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "pa"
    assert main(["run", *PA, "--out", str(out), "--quiet"]) == 0
    return out


def test_a_second_run_into_a_run_folder_is_refused(pa_run, capsys):
    before = snapshot(pa_run)
    assert "pressure.png" in before and "checkpoint.npz" in before
    assert main(["run", *MBB, "--out", str(pa_run), "--quiet"]) == 2
    line = one_error_line(capsys)
    assert line.startswith(f"pacto: error: run: '{pa_run}' already holds a run")
    assert f"'pacto resume {pa_run}'" in line and "another --out" in line and "--overwrite" in line
    assert snapshot(pa_run) == before


def test_evaluate_into_a_run_folder_is_refused(pa_run, capsys):
    before = snapshot(pa_run)
    assert main(["evaluate", *PA, "--density", str(pa_run / "checkpoint.npz"),
                 "--out", str(pa_run), "--quiet"]) == 2
    line = one_error_line(capsys)
    assert "evaluate:" in line and "already holds a run" in line and "--overwrite" in line
    assert snapshot(pa_run) == before
    # --overwrite would remove the very file it is asked to read: refused as well
    assert main(["evaluate", *PA, "--density", str(pa_run / "checkpoint.npz"),
                 "--out", str(pa_run), "--overwrite", "--quiet"]) == 2
    assert "one of the files it would remove" in one_error_line(capsys)
    assert snapshot(pa_run) == before


def test_evaluate_writes_beside_the_run_by_default(pa_run, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["evaluate", *PA, "--density", str(pa_run / "checkpoint.npz"), "--quiet"]) == 0
    out = tmp_path / "output" / "pa-inverter-linear-evaluate"
    assert sorted(p.name for p in out.iterdir()) == [LOCK_NAME, "design.vtu", "summary.json"]
    # a second evaluation into the same folder is refused too (its results would be lost)
    assert main(["evaluate", *PA, "--density", str(pa_run / "checkpoint.npz"), "--quiet"]) == 2
    assert main(["evaluate", *PA, "--density", str(pa_run / "checkpoint.npz"), "--quiet",
                 "--overwrite"]) == 0


def test_overwrite_removes_the_earlier_runs_files_only(tmp_path):
    out = tmp_path / "run"
    assert main(["run", *PA, "--out", str(out), "--quiet"]) == 0
    (out / "analysis").mkdir()
    (out / "analysis" / "analysis.json").write_text("{}")
    (out / "notes.txt").write_text("the user's")
    assert main(["run", *MBB, "--out", str(out), "--quiet", "--overwrite"]) == 0
    names = sorted(p.name for p in out.iterdir())
    # the mbb's own part.stl if its design made a part; its part is not analysed (no part.png)
    made = json.loads((out / "summary.json").read_text())["part"]["made"]
    assert names == sorted([LOCK_NAME, "checkpoint.npz", "convergence.png", "design.png",
                            "design.vtu", "history.csv", "notes.txt", "params.json",
                            "summary.json"] + (["part.stl"] if made else []))
    # (no pressure.png, part.png or analysis/ of the pa-inverter)
    assert (out / "notes.txt").read_text() == "the user's"
    assert json.loads((out / "summary.json").read_text())["case"] == "mbb"
    assert json.loads((out / "params.json").read_text())["case"] == "mbb"
    with np.load(out / "checkpoint.npz") as ck:
        assert ck["x"].size == 12 * 4 and int(ck["k"]) == 2


def test_a_run_refused_while_building_its_problem_writes_nothing(tmp_path, capsys):
    """A filter radius larger than the domain is refused by the design chain's builder, once
    the mesh is built: no params.json is left behind, in a new folder nor in a folder of the
    user's."""
    refused = [*MBB, "--set", "filter_radius=100"]
    new = tmp_path / "new"
    assert main(["run", *refused, "--out", str(new)]) == 2
    assert one_error_line(capsys).startswith("pacto: error: filter_radius: 100 is larger than")
    assert snapshot(new) == {}
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("the user's")
    before = snapshot(mine)
    assert main(["run", *refused, "--out", str(mine), "--quiet"]) == 2
    assert snapshot(mine) == before


@pytest.mark.slow
def test_a_run_that_fails_at_iteration_0_never_resumes_the_old_design(tmp_path, capsys):
    """--overwrite removes the earlier checkpoint before the new run starts: when the new run
    fails in its first iteration, resume repeats the new run, not the old design."""
    out = tmp_path / "run"
    assert main(["run", *MBB, "--out", str(out), "--quiet"]) == 0
    failing = ["cantilever", "--model", "neohookean", "--load", "1e8", "--maxh", "0.04",
               "--iterations", "2", "--set", "load_adapt=0", "--set", "newton_min_increment=0.1",
               "--out", str(out), "--quiet"]
    before = snapshot(out)
    assert main(["run", *failing]) == 2  # refused: the mbb run is kept as it was
    assert snapshot(out) == before
    capsys.readouterr()
    assert main(["run", *failing, "--overwrite"]) == 1
    assert not (out / "checkpoint.npz").exists()  # the mbb checkpoint is gone, not reused
    assert json.loads((out / "summary.json").read_text())["case"] == "cantilever"
    assert main(["resume", str(out), "--quiet"]) == 1  # the cantilever again, from iteration 0
    s = json.loads((out / "summary.json").read_text())
    assert s["case"] == "cantilever" and s["iterations"] == 0 and s["stopped"] == "newton"


def test_a_folder_another_process_writes_is_refused(tmp_path, capsys):
    out = tmp_path / "busy"
    assert main(["run", *MBB, "--out", str(out), "--quiet"]) == 0
    before = snapshot(out)
    with FolderLock(out, "run"):  # as another process would hold it (another descriptor)
        for cmd in (["run", *MBB, "--out", str(out), "--quiet", "--overwrite"],
                    ["resume", str(out), "--quiet"]):
            assert main(cmd) == 2
            line = one_error_line(capsys)
            assert "is being written by another pacto process" in line
            assert "another --out" in line
    assert snapshot(out) == before


def test_two_runs_started_at_once_one_is_refused(tmp_path):
    out = tmp_path / "both"
    cmd = [sys.executable, "-m", "pacto_ng.cli", "run", "mbb", "--nelx", "30", "--nely", "10",
           "--iterations", "15", "--out", str(out), "--quiet"]
    procs = [subprocess.Popen(cmd + ["--set", f"volfrac={v}"], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for v in (0.4, 0.6)]
    res = [(p.wait(300), p.stderr.read()) for p in procs]
    codes = sorted(c for c, _ in res)
    assert codes == [0, 2], res
    winner = 0.4 if res[0][0] == 0 else 0.6
    err = next(e for c, e in res if c == 2).strip()
    assert len(err.splitlines()) == 1
    assert ("being written by another pacto process" in err) or ("already holds a run" in err)
    s = json.loads((out / "summary.json").read_text())
    assert s["parameters"]["volfrac"] == winner and s["iterations"] == 15
    assert json.loads((out / "params.json").read_text())["params"]["volfrac"] == winner


def test_resume_leaves_params_json_alone_unless_the_cap_changes(tmp_path):
    out = tmp_path / "run"
    assert main(["run", *MBB, "--out", str(out), "--quiet"]) == 0
    f = out / "params.json"
    before, stamp = f.read_bytes(), f.stat().st_mtime_ns
    assert main(["resume", str(out), "--quiet"]) == 0
    assert f.read_bytes() == before and f.stat().st_mtime_ns == stamp
    assert main(["resume", str(out), "--iterations", "3", "--quiet"]) == 0
    info = json.loads(f.read_text())
    assert info["params"]["iterations"] == 3 and "model_choice" in info
    assert json.loads((out / "summary.json").read_text())["iterations"] == 3


def test_resume_before_the_first_checkpoint_starts_again(tmp_path):
    """A run killed after writing params.json but before its first checkpoint: resume runs it
    from iteration 0 and ends as an uninterrupted run."""
    full, part = tmp_path / "full", tmp_path / "part"
    assert main(["run", *MBB, "--out", str(full), "--quiet"]) == 0
    part.mkdir()
    (part / "params.json").write_bytes((full / "params.json").read_bytes())
    assert main(["resume", str(part), "--quiet"]) == 0
    a = json.loads((full / "summary.json").read_text())
    b = json.loads((part / "summary.json").read_text())
    assert b["iterations"] == a["iterations"] == 2
    assert np.allclose(a["objective_history"], b["objective_history"], rtol=1e-9, atol=0)


def test_a_resumed_run_repeats_the_uninterrupted_one_bit_for_bit(tmp_path):
    """With one NGSolve thread a run stopped after 2 iterations and resumed to 6 ends with the
    design and history of a 6-iteration run, exactly: the resumed process assembles its first
    design the way the uninterrupted one assembles every design after its first (the
    linear pa-inverter: element matrices in the Darcy block and the linear system)."""
    env = {**os.environ, "PACTO_THREADS": "1"}

    def pacto(*args):
        r = subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args, "--quiet"], env=env,
                           capture_output=True, text=True, timeout=600)
        assert r.returncode == 0, r.stderr

    args = ["pa-inverter", "--nelx", "24", "--nely", "16"]
    full, part = tmp_path / "full", tmp_path / "part"
    pacto("run", *args, "--iterations", "6", "--no-refine", "--out", str(full))
    pacto("run", *args, "--iterations", "2", "--no-refine", "--out", str(part))
    pacto("resume", str(part), "--iterations", "6", "--no-refine")
    with np.load(full / "checkpoint.npz") as a, np.load(part / "checkpoint.npz") as b:
        assert int(a["k"]) == int(b["k"]) == 6
        assert np.array_equal(a["x"], b["x"])
    ha = json.loads((full / "summary.json").read_text())["objective_history"]
    hb = json.loads((part / "summary.json").read_text())["objective_history"]
    assert ha == hb


def test_resume_of_a_converged_run_killed_in_its_final_writes(tmp_path):
    """The checkpoint of the iteration at which the run converged, results not yet written:
    resume writes them and reports the run converged there (no iteration added)."""
    out = tmp_path / "run"
    args = ["mbb", "--nelx", "12", "--nely", "4", "--iterations", "100", "--set", "tol=0.5",
            *TOP88_OPTIMISER, "--out", str(out), "--quiet"]  # no continuation: converges early
    assert main(["run", *args]) == 0
    a = json.loads((out / "summary.json").read_text())
    assert a["converged"] and a["iterations"] < 100
    for name in ("summary.json", "history.csv", "design.vtu", "design.png", "convergence.png"):
        (out / name).unlink()
    assert main(["resume", str(out), "--quiet"]) == 0
    b = json.loads((out / "summary.json").read_text())
    assert b["converged"] and b["stopped"] == "converged" and b["message"] == a["message"]
    assert b["objective_history"] == a["objective_history"]
    assert b["objective"] == pytest.approx(a["objective"], rel=1e-12)


def test_a_run_folder_from_before_the_compiled_forms_choice_still_resumes(tmp_path):
    """Run folders written before 2026-12-06 hold realcompile as true / false: read as on (1)
    / off (0), as those runs ran, and the run resumes."""
    out = tmp_path / "run"
    assert main(["run", *MBB, "--no-part", "--out", str(out), "--quiet"]) == 0
    info = json.loads((out / "params.json").read_text())
    for old, now in ((False, 0), (True, 1)):
        info["params"]["realcompile"] = old
        (out / "params.json").write_text(json.dumps(info))
        assert read_run_params(out, "resume")[2].realcompile == now
    assert main(["resume", str(out), "--iterations", "3", "--no-part", "--quiet"]) == 0
