"""The example cases written with the public API only: soft-finger and jaw-gripper (built in)
and examples/cad_actuator (a STEP file written by make_step.py, then a case file run by path).

Each: a 3-iteration run that ends with a finite objective, and the finite-difference check of
the whole chain (the built-in ones' objective histories are pinned in
tests/cases/test_case_pins.py)."""
import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

ROOT = Path(__file__).resolve().parents[2]
CAD_EXAMPLE = ROOT / "examples" / "cad_actuator"


def _finite_run(args, out):
    assert main(["run", "--no-part", *args, "--iterations", "3", "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["iterations"] == 3
    assert math.isfinite(summary["objective"])
    return summary


@pytest.fixture(scope="module")
def cad_case(tmp_path_factory):
    """The CAD example copied outside the repository, its STEP file written there."""
    folder = tmp_path_factory.mktemp("cad_actuator")
    for name in ("make_step.py", "cad_actuator.py"):
        shutil.copy(CAD_EXAMPLE / name, folder / name)
    done = subprocess.run([sys.executable, "make_step.py"], cwd=folder, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert (folder / "actuator.step").is_file()
    return folder / "cad_actuator.py"


@pytest.mark.parametrize("name", ["soft-finger", "jaw-gripper"])
def test_builtin_example_runs(name, tmp_path):
    summary = _finite_run([name], tmp_path / "run")
    assert summary["case"] == name


@pytest.mark.parametrize("name, maxh", [("soft-finger", "0.006"), ("jaw-gripper", "0.01")])
def test_builtin_example_gradients(name, maxh, capsys):
    # a coarse mesh (150-300 triangles) keeps the finite-difference check well under 20 s
    assert main(["check-gradients", name, "--maxh", maxh]) == 0
    assert "pass" in capsys.readouterr().out


def test_cad_example_runs(cad_case, tmp_path):
    summary = _finite_run([str(cad_case)], tmp_path / "run")
    assert summary["case"] == "cad_actuator"


def test_cad_example_gradients(cad_case, capsys):
    assert main(["check-gradients", str(cad_case)]) == 0
    assert "pass" in capsys.readouterr().out


def test_cad_example_without_step_file_says_so(tmp_path, capsys):
    """Running the case file before make_step.py: one line naming the missing file."""
    shutil.copy(CAD_EXAMPLE / "cad_actuator.py", tmp_path / "cad_actuator.py")
    assert main(["run", "--no-part", str(tmp_path / "cad_actuator.py"), "--iterations", "1",
                 "--out", str(tmp_path / "run"), "--quiet"]) == 2
    assert "make_step.py" in capsys.readouterr().err
