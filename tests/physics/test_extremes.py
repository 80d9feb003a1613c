"""Runs at the extremes of the parameters (issue "speed against accuracy, stability at the
extremes"): void stiffness E0/E1 = 1e-9, projection β = 128, ν = 0.49, solid flow coefficient
Ks/Kv = 1e-9, and pressures at and far past what Neo-Hookean reaches.

Each run either works (exit code 0, finite objective, volume and output displacement) or stops
by the reliability rules (a Newton failure: exit code 1, a one-line ``run stopped: ...``
message, the outputs of the last good design written).  In both cases no NaN or inf reaches
a written file: summary.json, history.csv and every array of design.vtu are checked.
The fast tests run 2 iterations on a coarse mesh; ``-m slow`` runs longer ones.
"""
from __future__ import annotations

import csv
import json
import math
import subprocess
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

COARSE = ["--maxh", "0.01"]


class _Proc:
    """What a finished CLI run left: exit code, stdout, stderr."""

    def __init__(self, returncode, stdout, stderr):
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr


def run_cli(*args, capsys=None):
    """Run ``pacto`` in this process (captured by ``capsys``) or, without it, in a subprocess."""
    if capsys is not None:
        from pacto_ng.cli import main

        capsys.readouterr()
        code = main(list(args))
        cap = capsys.readouterr()
        return _Proc(code, cap.out, cap.err)
    return subprocess.run([sys.executable, "-m", "pacto_ng.cli", *args], capture_output=True,
                          text=True, timeout=600)


def _all_finite_json(obj, where="summary.json"):
    """Every number in a JSON document is finite (json writes NaN/Infinity as bare words)."""
    if isinstance(obj, float):
        assert math.isfinite(obj), f"non-finite number in {where}"
    elif isinstance(obj, dict):
        for k, v in obj.items():
            _all_finite_json(v, f"{where}:{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            _all_finite_json(v, f"{where}[{i}]")


def check_outputs(out):
    """summary.json, history.csv and design.vtu exist and hold finite numbers only."""
    text = (out / "summary.json").read_text()
    for word in ("NaN", "Infinity"):
        assert word not in text, f"summary.json contains {word}"
    summ = json.loads(text)
    _all_finite_json(summ)
    with open(out / "history.csv") as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
    assert "objective" in (reader.fieldnames or []), "history.csv has no header"
    # one row per finished iteration: none when Newton failed in the very first one
    assert len(rows) == summ["iterations"], (len(rows), summ["iterations"])
    for row in rows:
        for key, val in row.items():
            try:
                v = float(val)
            except (TypeError, ValueError):
                continue
            assert math.isfinite(v), f"history.csv: {key} = {val}"
    import meshio

    m = meshio.read(out / "design.vtu")
    assert len(m.points) > 0 and np.all(np.isfinite(m.points))
    names = set(m.point_data) | set(m.cell_data)
    assert {"rho_bar", "u"} <= names, names
    for name, arr in m.point_data.items():
        assert np.all(np.isfinite(arr)), f"design.vtu point data {name}"
    for name, blocks in m.cell_data.items():
        for arr in blocks:
            assert np.all(np.isfinite(arr)), f"design.vtu cell data {name}"
    return summ, rows


def check_run(proc, out, n_iterations):
    """A run that worked, or stopped cleanly by a Newton failure."""
    assert proc.returncode in (0, 1), proc.stderr[-2000:]
    summ, rows = check_outputs(out)
    if proc.returncode == 0:
        assert len(rows) == summ["iterations"] == n_iterations
        assert math.isfinite(summ["objective"]) and 0.0 <= summ["volume_fraction"] <= 1.0
    else:
        lines = [ln for ln in proc.stdout.splitlines() if ln.strip()]
        stopped = [ln for ln in lines if ln.startswith("run stopped:")]
        assert len(stopped) == 1, proc.stdout[-2000:]
        assert "Newton" in stopped[0] or "newton" in stopped[0], stopped[0]
        assert "Traceback" not in proc.stderr, proc.stderr[-2000:]
    return summ


# ---- fast: each works (linear model) -------------------------------------------------------
@pytest.mark.parametrize("name, sets", [
    ("E0/E1=1e-9", ["E0=3"]),                                   # E1 = 3e9
    ("beta=128", ["beta=128", "beta_max=128"]),
    ("nu=0.49", ["nu=0.49"]),
    ("Ks/Kv=1e-9", ["Ks=1e-9"]),
])
def test_linear_extremes_work(name, sets, tmp_path, capsys):
    out = tmp_path / "run"
    args = ["run", "--no-part", "pa-inverter", *COARSE, "--iterations", "2", "--out", str(out), "--quiet"]
    for s in sets:
        args += ["--set", s]
    proc = run_cli(*args, capsys=capsys)
    assert proc.returncode == 0, (name, proc.stdout[-1000:], proc.stderr[-2000:])
    summ = check_run(proc, out, 2)
    assert summ["parameters"][sets[0].split("=")[0]] == pytest.approx(float(sets[0].split("=")[1]))
    # the run did something: a finite, non-zero output displacement
    assert summ["output_displacement"] != 0.0


def test_neohookean_far_past_the_limit_stops_cleanly(tmp_path, capsys):
    """1e13 Pa on a Neo-Hookean pa-inverter (even the smallest load increment, 1/1024 of it,
    is 1000x the thesis's limit): Newton must fail, and the run must stop with exit code 1,
    one line, finite outputs.  A very coarse mesh and 5 Newton iterations per step keep the
    failure quick."""
    out = tmp_path / "run"
    proc = run_cli("run", "--no-part", "pa-inverter", "--maxh", "0.02", "--set", "robust=0", "--model", "neohookean",
                   "--iterations", "2", "--set", "load=1e13", "--set", "newton_max_iter=5",
                   "--out", str(out), "--quiet", capsys=capsys)
    assert proc.returncode == 1, (proc.stdout[-1000:], proc.stderr[-2000:])
    summ = check_run(proc, out, 2)
    assert summ["load_factor_reached"] < 1.0


@pytest.mark.slow
def test_neohookean_below_its_load_names_the_model_that_carries_it(tmp_path, capsys):
    """The coarse pa-inverter at 1e7 Pa from a linear design (p = 3, β = 8): plain
    Neo-Hookean cannot carry the full load on that design (its crushed void elements invert;
    measured: load factor 0.587), so the run exits 1 and its last line names ``--model wang``;
    the same run with ``--model wang`` exits 0 at the full load (docs/studies.md, "Extreme
    pressures at defaults").  Slow: ~3 CPU minutes."""
    lin = tmp_path / "linear"
    proc = run_cli("run", "--no-part", "pa-inverter", *COARSE, "--iterations", "80", "--out", str(lin),
                   "--quiet", capsys=capsys)
    assert proc.returncode == 0, proc.stdout[-1000:]
    common = [*COARSE, "--load", "1e7", "--iterations", "1", "--set", "load_ramp=0",
              "--set", f"init_design={lin}", "--set", "penal_start=3", "--set", "beta=8",
              "--quiet"]
    nh = run_cli("run", "--no-part", "pa-inverter", "--model", "neohookean", *common,
                 "--out", str(tmp_path / "nh"), capsys=capsys)
    assert nh.returncode == 1, nh.stdout[-1000:]
    last = [ln for ln in nh.stdout.splitlines() if ln.strip()][-1]
    assert last.startswith("run stopped:") and "--model wang carries such loads" in last, last
    summ = check_run(nh, tmp_path / "nh", 1)
    assert 0.0 < summ["load_factor_reached"] < 1.0
    wang = run_cli("run", "--no-part", "pa-inverter", "--model", "wang", *common,
                   "--out", str(tmp_path / "wang"), capsys=capsys)
    assert wang.returncode == 0, wang.stdout[-1000:]
    assert check_run(wang, tmp_path / "wang", 1)["load_factor_reached"] == 1.0


# ---- slow: Neo-Hookean at the extremes, and at the thesis's limit -----------------------------
@pytest.mark.slow
@pytest.mark.parametrize("sets", [
    ["E0=3"], ["beta=128", "beta_max=128", "beta_every=1"], ["nu=0.49"], ["Ks=1e-9"],
    ["load=1e7"],
])
def test_neohookean_extremes_work_or_stop_cleanly(sets, tmp_path):
    out = tmp_path / "run"
    args = ["run", "--no-part", "pa-inverter", *COARSE, "--model", "neohookean", "--iterations", "5",
            "--out", str(out), "--quiet"]
    for s in sets:
        args += ["--set", s]
    check_run(run_cli(*args), out, 5)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["gnl", "wang"])
def test_other_models_at_extreme_void_work_or_stop_cleanly(model, tmp_path):
    out = tmp_path / "run"
    check_run(run_cli("run", "--no-part", "pa-inverter", *COARSE, "--model", model, "--iterations", "5",
                      "--set", "E0=3", "--set", "load=1e7", "--out", str(out), "--quiet"),
              out, 5)


@pytest.mark.parametrize("iterations, code", [(3, 0), (4, 1)])
def test_adaptive_load_continuation_goes_on_past_a_newton_failure(iterations, code, tmp_path, capsys):
    """1e9 Pa on a coarse Neo-Hookean pa-inverter, at the full load from the first iteration
    (``load_ramp=0``, not the ramp chosen from the load): without ``load_adapt`` the first analysis
    fails and the run stops at iteration 0 (measured; the far-past-the-limit test above checks
    such a stop); with ``load_adapt=1.5`` every iteration runs at the load factor Newton reached
    (history.csv: all below 1) and the run finishes its iterations.  The final design is then
    analysed at the full load: after 3 iterations it carries it (exit 0, load factor 1 in
    summary.json); after 4 it does not, and the run exits 1 with the last analysed design
    reported at the load it carried.  Every file finite either way."""
    out = tmp_path / "run"
    args = ["run", "--no-part", "pa-inverter", "--maxh", "0.02", "--set", "robust=0", "--model", "neohookean",
            "--iterations", str(iterations), "--set", "load=1e9", "--set", "newton_max_iter=8",
            "--set", "newton_min_increment=0.0625", "--set", "load_ramp=0", "--out", str(out),
            "--quiet"]
    proc = run_cli(*args, "--set", "load_adapt=1.5", capsys=capsys)
    assert proc.returncode == code, (proc.stdout[-1000:], proc.stderr[-2000:])
    summ = check_run(proc, out, iterations)
    with open(out / "history.csv") as fh:
        loads = [float(row["load"]) for row in csv.DictReader(fh)]
    assert len(loads) == iterations and all(0.0 < ld < 1.0 for ld in loads)
    assert summ["stopped"] == "iterations"
    assert "adaptive load continuation" in summ["message"]
    expected = 1.0 if code == 0 else loads[-1]
    assert summ["load_factor_reached"] == pytest.approx(expected)


def test_adaptive_load_continuation_is_the_default(tmp_path, capsys):
    """The same 1e9 Pa run without ``load_adapt``: adaptive continuation is on by default
    (1.2), so the run finishes its iterations at the load factors Newton reached; with
    ``load_adapt=0`` it stops at iteration 0 with exit code 1 and the one-line message."""
    args = ["run", "--no-part", "pa-inverter", "--maxh", "0.02", "--set", "robust=0", "--model", "neohookean", "--iterations",
            "2", "--set", "load=1e9", "--set", "newton_max_iter=8",
            "--set", "newton_min_increment=0.0625", "--quiet"]
    out = tmp_path / "default"
    proc = run_cli(*args, "--out", str(out), capsys=capsys)
    summ = check_run(proc, out, 2)
    assert summ["parameters"]["load_adapt"] == 1.2
    assert summ["stopped"] == "iterations" and "adaptive load continuation" in summ["message"]
    with open(out / "history.csv") as fh:
        assert [0.0 < float(r["load"]) < 1.0 for r in csv.DictReader(fh)] == [True, True]
    off = tmp_path / "off"
    proc = run_cli(*args, "--set", "load_adapt=0", "--out", str(off), capsys=capsys)
    assert proc.returncode == 1
    summ = check_run(proc, off, 2)
    assert summ["stopped"] == "newton" and summ["iterations"] == 0


@pytest.mark.slow
def test_pneunet_part_at_1e6_pa(tmp_path, capsys):
    """The PneuNet part at 1e6 Pa (docs/studies.md, "PneuNet at 1e6 Pa"): Wang with the
    follower load inside the optimisation and the leak limit converges at the full load with
    a sealed chamber, and its part's follower analysis converges at every pressure and moves
    the tip the intended way (Δ > 0).  Slow: ~7 CPU minutes."""
    out = tmp_path / "pn"
    proc = run_cli("run", "--no-part", "pneunet", "--model", "wang", "--load", "1e6", "--set",
                   "load_type=follower", "--set", "leak_max=1e-3", "--out", str(out),
                   "--quiet", capsys=capsys)
    assert proc.returncode == 0, proc.stdout[-1000:]
    summ = json.loads((out / "summary.json").read_text())
    assert summ["converged"] and summ["load_factor_reached"] == 1.0
    assert summ["leak"] <= 1e-3
    an = run_cli("analyse", str(out), "--pressures", "1e5,3e5,1e6", "--quiet", capsys=capsys)
    assert an.returncode == 0, an.stdout[-1000:]
    rows = json.loads((out / "analysis" / "analysis.json").read_text())["pressures"]
    assert [r["pressure"] for r in rows] == [1e5, 3e5, 1e6]
    for r in rows:
        assert r["follower"]["converged"] and r["follower"]["delta"] > 0, r
