"""A set-up whose sizes and moduli do not match (moduli a million times off the loads) gets one
warning line on stderr, ``pacto: warning: ...``, from the initial design's first linear
analysis, and the run goes on; a consistent one (the ``pacto new`` finger) gets none."""
import pytest

from pacto_ng.template import TEMPLATE

from test_case_files import run_cli

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


def _finger(folder):
    path = folder / "finger.py"
    path.write_text(TEMPLATE.format(name="finger", file="finger.py"))
    return path


def _warnings(stderr):
    return [line for line in stderr.splitlines() if line.startswith("pacto: warning: ")]


def test_moduli_a_million_times_too_stiff_warn_once_and_the_run_goes_on(tmp_path):
    """E1 = 1e14 Pa where the finger's 1e5 Pa load and E1 = 1e8 Pa move it by 5.6e-4 of its
    length: 5.6e-10 of it, below 1e-9 (--model auto chooses the linear model, whose run
    ends; the Wang model's Newton stalls at such a scale)."""
    code, err = run_cli("run", "--no-part", _finger(tmp_path), "--model", "auto", "--set", "E1=1e14",
                        "--set", "E0=1e8", "--iterations", "1", "--maxh", "0.004", "--out",
                        tmp_path / "run", "--quiet")
    assert code == 0, err
    (line,) = _warnings(err)
    assert "of the domain's size (below 1e-09)" in line and "check the units" in line
    assert err.strip() == line


def test_moduli_a_million_times_too_soft_warn_for_a_nonlinear_model(tmp_path):
    """E1 = 100 Pa (meant as MPa): the linear analysis strains the material about 6e3 (a
    strain of 6e-3 at 1e8 Pa), far beyond what a finite-strain model can carry.  The
    linear model (scale-invariant) is not warned about."""
    from pacto_ng.auto import choose
    from pacto_ng.case import load_case_file

    case = load_case_file(_finger(tmp_path))
    params = case.defaults.replace(E1=100.0, E0=1e-4, maxh=0.004)
    warned = []
    choose(case, params.replace(model="auto"), warnings=warned)
    (line,) = warned
    assert "material strain of" in line and "the wang model" in line
    warned = []
    choose(case, params.replace(model="auto", E1=1e8, E0=1e2), warnings=warned)
    assert warned == []


def test_the_template_finger_at_its_defaults_does_not_warn(tmp_path):
    code, err = run_cli("run", "--no-part", _finger(tmp_path), "--model", "auto", "--iterations", "1",
                        "--maxh", "0.004", "--out", tmp_path / "run", "--quiet")
    assert code == 0, err
    assert _warnings(err) == []
