"""``--set init_design=DIR``: a run starts from another run's design (a warm start across loads)."""
import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

BASE = ["run", "--no-part", "mbb", "--nelx", "12", "--nely", "4", "--quiet"]


def test_a_run_starts_from_the_design_of_another(tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    assert main(BASE + ["--iterations", "5", "--out", str(first)]) == 0
    x_first = np.load(first / "checkpoint.npz")["x"]
    assert np.ptp(x_first) > 0.05  # five iterations moved it away from the uniform start
    assert main(BASE + ["--iterations", "1", "--set", f"init_design={first}", "--out",
                        str(second)]) == 0
    import json

    hist = json.loads((second / "summary.json").read_text())["objective_history"]
    ref = json.loads((first / "summary.json").read_text())["objective_history"]
    # iteration 0 of the second run analyses the first run's last design at the restarted
    # schedule's first values: not the uniform design's objective
    assert abs(hist[0] - ref[0]) > 1e-3 * abs(ref[0])


def test_init_design_errors_name_the_field(tmp_path, capsys):
    assert main(BASE + ["--set", f"init_design={tmp_path / 'nowhere'}", "--out",
                        str(tmp_path / "a")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("pacto: error: init_design:") and "nowhere" in err[0]
    other = tmp_path / "other"
    assert main(["run", "--no-part", "mbb", "--nelx", "8", "--nely", "4", "--quiet", "--iterations", "1",
                 "--out", str(other)]) == 0
    capsys.readouterr()
    assert main(BASE + ["--set", f"init_design={other}", "--out", str(tmp_path / "b")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "init_design:" in err[0] and "design variables" in err[0]
