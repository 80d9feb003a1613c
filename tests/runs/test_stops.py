"""How a run ends when it is stopped from outside (issue 18, part 4): SIGINT, SIGTERM and
SIGHUP end it with one true line and the checkpoint kept; a full disk (a file size limit here)
ends it with one line, the last complete checkpoint kept and nothing half written; kill -9 and
resume give the uninterrupted run's design (the short variant of benchmarks/kill_resume.py)."""
import json
import os
import re
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]


def pacto(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "pacto_ng.cli", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def no_temporaries(folder):
    return [p.name for p in folder.iterdir() if ".tmp" in p.name] == []


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_a_signal_mid_run_keeps_the_checkpoint_and_says_so(tmp_path, sig):
    out = tmp_path / "run"
    proc = pacto("run", "--no-part", "mbb", "--nelx", "30", "--nely", "10", "--iterations", "500",
                 "--out", str(out))
    for line in proc.stdout:
        if line.startswith("it    2/"):
            break
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    with np.load(out / "checkpoint.npz") as ck:
        k = int(ck["k"])
    assert k >= 3
    assert lines[0] == (f"pacto: interrupted by {signal.Signals(sig).name}: the checkpoint after "
                        f"{k} of 500 iterations is kept (continue it: 'pacto resume {out}')")
    assert not (out / "summary.json").exists() and no_temporaries(out)


def test_an_interrupt_before_the_first_checkpoint_says_there_is_none(tmp_path):
    """Ctrl-C while the first iteration runs: no checkpoint claimed; resume starts again."""
    out = tmp_path / "run"
    proc = pacto("run", "--no-part", "pa-inverter", "--nelx", "60", "--nely", "40", "--iterations", "2",
                 "--out", str(out), "--quiet")
    while not (out / "params.json").exists():
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.002)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and len(err.strip().splitlines()) == 1, err
    if (out / "checkpoint.npz").exists():  # the first iteration was faster than the signal
        pytest.skip("the first checkpoint came before the signal")
    assert err.strip() == (f"pacto: interrupted by SIGINT: no iteration was checkpointed; "
                           f"'pacto resume {out}' starts the run again from its params.json")
    r = subprocess.run([sys.executable, "-m", "pacto_ng.cli", "resume", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "summary.json").read_text())["iterations"] == 2


def test_an_interrupt_while_the_problem_is_built_leaves_nothing_to_resume(tmp_path):
    """Ctrl-C while the mesh and chain are built (about 7 s for this mesh; the folder's lock
    is taken before): params.json is written only once the problem is built, so nothing is
    there, and the line says to run the command again, not to resume."""
    out = tmp_path / "run"
    proc = pacto("run", "--no-part", "cantilever", "--maxh", "0.004", "--iterations", "1", "--out",
                 str(out), "--quiet")
    while not (out / ".pacto.lock").exists():
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.002)
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    if (out / "params.json").exists():  # the problem was built before the signal
        pytest.skip("the problem was built before the signal")
    assert err.strip() == ("pacto: interrupted by SIGINT: nothing was written yet (the problem "
                           "was being built): run the command again")
    assert [p.name for p in out.iterdir()] == [".pacto.lock"]


def _file_limit(nbytes):
    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, nbytes))
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # write() then fails with EFBIG
    return limit


MBB = ["mbb", "--nelx", "30", "--nely", "10", "--iterations", "3"]


def test_a_full_disk_in_the_final_writes_keeps_the_checkpoint(tmp_path):
    """design.vtu (133 kB) exceeds the 100 kB limit, the checkpoint (27 kB) does not: one
    line, exit 2, the checkpoint of the last iteration intact, no summary claiming a finished
    run, no temporary left; resume (with room again) writes the results."""
    out = tmp_path / "run"
    proc = pacto("run", "--no-part", *MBB, "--out", str(out), "--quiet", preexec_fn=_file_limit(100_000))
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2 and len(err.strip().splitlines()) == 1, err
    assert err.strip() == (
        f"pacto: error: cannot write '{out}/design.vtu' (the file was cut short: the disk is "
        f"full or a file size limit is reached); the checkpoint after 3 of 3 iterations is kept "
        f"(its final results are not all written: 'pacto resume {out}')")
    with np.load(out / "checkpoint.npz") as ck:
        assert int(ck["k"]) == 3
    assert not (out / "summary.json").exists() and not (out / "design.vtu").exists()
    assert no_temporaries(out)
    r = subprocess.run([sys.executable, "-m", "pacto_ng.cli", "resume", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "summary.json").read_text())["iterations"] == 3


def test_a_full_disk_at_the_first_checkpoint(tmp_path):
    out = tmp_path / "run"
    proc = pacto("run", "--no-part", *MBB, "--out", str(out), "--quiet", preexec_fn=_file_limit(20_000))
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 2 and len(err.strip().splitlines()) == 1, err
    assert re.fullmatch(
        rf"pacto: error: cannot write '{re.escape(str(out))}/checkpoint.npz' \(File too large: "
        rf"the disk is full or a file size limit is reached\); no iteration was checkpointed; "
        rf"'pacto resume {re.escape(str(out))}' starts the run again from its params.json",
        err.strip()), err
    assert sorted(p.name for p in out.iterdir()) == [".pacto.lock", "params.json"]
    assert json.loads((out / "params.json").read_text())["case"] == "mbb"


@pytest.mark.slow
def test_kill_resume_short_study(tmp_path):
    """benchmarks/kill_resume.py --quick: two kill -9 at random moments of a small
    pa-inverter run, each resumed; every resume completes with the uninterrupted design."""
    r = subprocess.run([sys.executable, "-m", "benchmarks.kill_resume", "--quick", "--out",
                        str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=1800,
                       env={**os.environ})
    assert r.returncode == 0, r.stdout + r.stderr
    (res,) = json.loads((tmp_path / "kill_resume.json").read_text())
    assert res["kills"] == 2 and res["completed"] == 2 and res["unreadable_files"] == 0
    assert res["max_abs_dx"] <= 1e-10


def test_an_interrupt_while_resume_starts_names_the_checkpoint_there(tmp_path, monkeypatch,
                                                                     capsys):
    """Ctrl-C while resume builds the problem (before it loads the checkpoint): the line names
    the checkpoint in the folder, which is untouched."""
    from pacto_ng import runner
    from pacto_ng.cli import main

    out = tmp_path / "run"
    assert main(["run", "--no-part", *MBB, "--out", str(out), "--quiet"]) == 0
    before = (out / "checkpoint.npz").read_bytes()

    def interrupted(*args, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(runner, "build_problem", interrupted)
    capsys.readouterr()
    assert main(["resume", str(out), "--iterations", "5", "--quiet"]) == 130
    err = capsys.readouterr().err.strip()
    assert err == (f"pacto: interrupted by SIGINT: the checkpoint after 3 of 5 iterations is "
                   f"kept (continue it: 'pacto resume {out}')")
    assert (out / "checkpoint.npz").read_bytes() == before
