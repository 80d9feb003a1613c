"""A β continuation that advances when its stage has settled (``beta_settle``): the run's
history records the β it used, resume continues it exactly, and the run's final analysis and
``pacto evaluate`` of its checkpoint take that β (the formula of the iteration count would
not)."""
import csv
import json

import numpy as np
import pytest

from pacto_ng.cli import main

MBB = ["mbb", "--nelx", "24", "--nely", "8", "--set", "penal_start=0", "--set", "beta=1",
       "--set", "beta_max=8", "--set", "beta_every=50", "--set", "beta_settle=0.01",
       "--set", "tol=0", "--set", "obj_tol=0", "--quiet"]


def _history(folder):
    with open(folder / "history.csv") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("settled")
    assert main(["run", "--no-part", *MBB, "--iterations", "40", "--out", str(root / "whole")]) == 0
    assert main(["run", "--no-part", *MBB, "--iterations", "24", "--out", str(root / "cut")]) == 0
    assert main(["resume", str(root / "cut"), "--iterations", "40", "--quiet"]) == 0
    return root


def test_beta_doubles_where_the_last_five_changes_fall_below_the_tolerance(runs):
    rows = _history(runs / "whole")
    beta, stage = 1.0, 0
    for k, row in enumerate(rows):  # the rule, from the recorded objectives
        if k >= 6 and stage >= 6 and beta < 8:
            f = np.array([r["objective"] for r in rows[k - 6:k]])
            if np.max(np.abs(np.diff(f))) < 0.01 * abs(f[-1]):
                beta, stage = 2 * beta, 0
        assert row["beta"] == beta, k
        stage += 1
    doublings = [k for k in range(1, 40) if rows[k]["beta"] != rows[k - 1]["beta"]]
    assert len(doublings) >= 2 and doublings[0] < 50  # earlier than beta_every


def test_resume_continues_the_settled_continuation_exactly(runs):
    whole, cut = _history(runs / "whole"), _history(runs / "cut")
    assert len(cut) == len(whole) == 40
    for a, b in zip(whole, cut):
        assert a["beta"] == b["beta"]
        assert abs(a["objective"] - b["objective"]) <= 1e-10 * abs(a["objective"])


def test_the_final_analysis_and_evaluate_use_the_beta_of_the_last_iteration(runs, tmp_path):
    run = runs / "whole"
    last_beta = _history(run)[-1]["beta"]
    assert last_beta > 1.0
    summary = json.loads((run / "summary.json").read_text())
    out = tmp_path / "ev"
    assert main(["evaluate", *MBB, "--density", str(run / "checkpoint.npz"),
                 "--out", str(out)]) == 0
    evaluated = json.loads((out / "summary.json").read_text())
    assert abs(evaluated["objective"] - summary["objective"]) <= 1e-10 * summary["objective"]
    # the same design at the β the iteration count alone would give (1: the stage of 50 has
    # not ended) is another analysis
    out1 = tmp_path / "ev1"
    assert main(["evaluate", *MBB[:-1], "--set", "beta_settle=0", "--quiet", "--density",
                 str(run / "checkpoint.npz"), "--out", str(out1)]) == 0
    other = json.loads((out1 / "summary.json").read_text())
    assert abs(other["objective"] - summary["objective"]) > 1e-3 * summary["objective"]
