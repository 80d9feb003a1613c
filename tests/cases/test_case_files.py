"""A user's case file outside the repository: every command works on it and on its runs, and a
mistake in it is one line with exit code 2."""
import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

from pacto_ng.cli import main
from pacto_ng.template import TEMPLATE

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

FAST = ["--maxh", "0.003", "--quiet"]


def write_case(folder, name="finger", replace=()):
    text = TEMPLATE.format(name=name, file=f"{name}.py")
    for old, new in replace:
        assert old in text, old
        text = text.replace(old, new)
    path = folder / f"{name}.py"
    path.write_text(text)
    return path


def run_cli(*args):
    """``pacto ARGS`` in a fresh process: exit code and stderr (what a user sees)."""
    r = subprocess.run([sys.executable, "-c", "import sys; from pacto_ng import main; "
                        "sys.exit(main(sys.argv[1:]))", *map(str, args)],
                       capture_output=True, text=True, timeout=300)
    return r.returncode, r.stderr


def test_pacto_new_writes_a_case_that_runs_and_refuses_to_overwrite(tmp_path, capsys):
    assert main(["new", str(tmp_path / "my_finger")]) == 0
    path = tmp_path / "my_finger.py"
    assert path.is_file()
    assert main(["run", str(path), "--iterations", "2", "--out", str(tmp_path / "r"), *FAST]) == 0
    s = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert s["case"] == "my_finger" and np.isfinite(s["objective"]) and s["iterations"] == 2
    before = path.read_text()
    assert main(["new", str(path)]) == 2
    assert "already exists" in capsys.readouterr().err
    assert path.read_text() == before


@pytest.fixture(scope="module")
def user_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("user")
    case = write_case(folder)
    out = folder / "run"
    # 4 iterations: after 3 no element reaches the threshold, and analyse has no part
    assert main(["run", str(case), "--iterations", "4", "--out", str(out), *FAST]) == 0
    return case, out


def test_resume_evaluate_and_check_gradients_on_a_case_file(user_run, tmp_path):
    case, run = user_run
    out = tmp_path / "resumed"
    shutil.copytree(run, out)  # the other tests see the module's run as it was made
    info = json.loads((out / "params.json").read_text())
    assert info["case_file"] == str(case.resolve())
    # resume finds the case through the run folder alone
    assert main(["resume", str(out), "--iterations", "5", "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["iterations"] == 5
    # the run's own checkpoint: its design variables at its last penalty and β, so the run's
    # response again
    ev = tmp_path / "ckpt"
    assert main(["evaluate", str(case), "--density", str(out / "checkpoint.npz"), "--out",
                 str(ev), *FAST]) == 0
    e = json.loads((ev / "summary.json").read_text())
    assert e["output_displacement"] == pytest.approx(s["output_displacement"], rel=1e-8)
    assert e["strain_energy"] == pytest.approx(s["strain_energy"], rel=1e-8)
    # its design.vtu: the same ρ̄ (evaluated at the final penalty, 3, where the run at
    # iteration 4 of its continuation had 1.12: the same volume, another response)
    ev = tmp_path / "vtu"
    assert main(["evaluate", str(case), "--density", str(out / "design.vtu"), "--out", str(ev),
                 *FAST]) == 0
    e = json.loads((ev / "summary.json").read_text())
    assert e["volume_fraction"] == pytest.approx(s["volume_fraction"], rel=1e-12)
    assert main(["check-gradients", str(case), "--quiet"]) == 0


def test_analyse_export_and_compare_on_a_case_file(user_run, tmp_path):
    case, out = user_run
    assert main(["analyse", str(out), "--pressures", "1e4", "--kinds", "darcy",
                 "--keep-threshold", "--quiet"]) in (0, 1)
    assert (out / "analysis" / "analysis.json").is_file()
    stl = tmp_path / "part.stl"
    assert main(["export", str(out), "--format", "stl", "--out", str(stl), "--quiet"]) == 0
    assert stl.stat().st_size > 0
    pic = tmp_path / "cmp.png"
    assert main(["compare", str(out), str(out), "--out", str(pic), "--quiet"]) == 0
    assert pic.is_file()


def test_sweep_runs_a_case_file(user_run, tmp_path):
    pytest.importorskip("distributed")
    case, _ = user_run
    out = tmp_path / "sweep"
    assert main(["sweep", str(case), "--loads", "5e4", "--workers", "1", "--iterations", "2",
                 "--maxh", "0.003", "--out", str(out), "--quiet"]) == 0
    assert (out / "sweep.csv").is_file()


#: (what is wrong, the change to the template, what the one line must say)
MISTAKES = [
    ("python error", [("L, H = LENGTH, HEIGHT", "L, H = LENGTH, HEIGTH")],
     "NameError: name 'HEIGTH' is not defined"),  # file:line checked exactly below
    ("syntax error", [("import pacto_ng as pn", "import pacto_ng as pn)")], "SyntaxError"),
    ("error at import", [("import pacto_ng as pn", "import pacto_ng as pn\n1 / 0")],
     "ZeroDivisionError"),
    ("no CASE", [("CASE = pn.Case(", "KASE = pn.Case(")], "defines no CASE"),
    ("CASE of the wrong type", [("CASE = pn.Case(", "CASE = dict(")], "not a pacto_ng.Case"),
    ("missing boundary", [('clamp=("fixed",)', 'clamp=("fixd",)')],
     "clamp 'fixd' is not a boundary or point of the geometry (boundaries: fixed, inlet, outer"),
    ("missing region", [('void=("chamber",)', 'void=("chamber", "hole")')],
     "passive void 'hole' is not a region of the geometry (regions: chamber, design)"),
    ("port off the geometry", [('Port("tip"', 'Port("tip2"')],
     "output port 'tip2' is not a boundary or point"),
    ("port direction of the wrong dimension", [("(0.0, -1.0)", "(0.0, -1.0, 0.0)")],
     "has 3 components, the mesh is 2D"),
    ("overlapping passive regions", [('void=("chamber",)', 'void=("chamber",), solid=("chamber",)')],
     "region 'chamber' is both passive solid and passive void"),
    ("no design face", [('design.faces.name = "design"', 'design.faces.name = "body"')],
     "no face is named 'design'"),
    ("a bad parameter default", [("volfrac=0.35", "volfrac=1.5")], "volfrac: must lie in (0, 1)"),
    ("setup returns the wrong type", [("    return pn.Setup(", "    return dict(")],
     "setup(params) returned a dict, not a Setup"),
    ("error inside geometry()", [("chamber = occ.WorkPlane().Circle(0.35 * L, 0.5 * H, CHAMBER_R).Face()",
                                  "chamber = occ.WorkPlane().Circle(0.35 * L, 0.5 * H, CHAMBER_R).Fase()")],
     "AttributeError"),
    ("chain returns the wrong type", [("    setup=setup,\n", "    setup=setup,\n    chain=lambda b: b.design(),\n")],
     "chain(b) returned a DesignChain, not a Problem"),
    ("error inside chain()", [("    setup=setup,\n", "    setup=setup,\n    chain=lambda b: b.desing(),\n")],
     "AttributeError: 'Builder' object has no attribute 'desing'"),
]


@pytest.mark.parametrize("what,changes,expect", MISTAKES, ids=[m[0] for m in MISTAKES])
def test_a_mistake_in_a_case_file_is_one_line_with_exit_2(what, changes, expect, tmp_path):
    case = write_case(tmp_path, replace=changes)
    code, err = run_cli("run", case, "--iterations", "1", "--out", tmp_path / "out", *FAST)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert "Traceback" not in err
    assert expect in lines[0], lines[0]


def test_the_line_of_a_python_error_is_the_users(tmp_path):
    case = write_case(tmp_path, replace=[("L, H = LENGTH, HEIGHT", "L, H = LENGTH, HEIGTH")])
    line = 1 + case.read_text().splitlines().index("    L, H = LENGTH, HEIGTH")
    code, err = run_cli("run", case, "--out", tmp_path / "out", *FAST)
    assert code == 2
    assert err.strip() == (f"pacto: error: {case}:{line}: NameError: name 'HEIGTH' is not "
                           "defined")


def test_inlet_that_touches_no_design_domain(tmp_path):
    """An inlet on the far edge of a passive solid pad pressurises nothing."""
    from netgen import occ

    import pacto_ng as pn
    from pacto_ng.params import InputError

    def geometry(p):
        design = occ.WorkPlane().MoveTo(0, 0).Rectangle(0.02, 0.01).Face()
        design.faces.name = "design"
        pad = occ.WorkPlane().MoveTo(-0.004, 0).Rectangle(0.004, 0.01).Face()
        pad.faces.name = "pad"
        shape = occ.Glue([design, pad])
        shape.edges.Min(occ.X).name = "inlet"
        shape.edges.Max(occ.X).name = "fixed"
        shape.vertices.Nearest((0.02, 0, 0)).name = "out"
        return shape

    case = pn.Case("pad", "an inlet on a pad", "test", pn.Parameters(maxh=0.002, delta_s=0.002),
                   geometry, lambda p: pn.Setup(pn.Supports(clamp=("fixed",)), solid=("pad",),
                                                port=pn.Port("out", (1.0, 0.0)),
                                                pressure=pn.Pressure(("inlet",), ("fixed",)),
                                                objective="output"))
    with pytest.raises(InputError, match="pressure inlet 'inlet' touches no design domain "
                                         r"\(it borders pad\)"):
        pn.run(case, out=tmp_path, iterations=1)


def test_unknown_case_name_and_missing_case_file(tmp_path):
    code, err = run_cli("run", "no-such-case")
    assert code == 2 and "unknown case 'no-such-case'" in err and len(err.strip().splitlines()) == 1
    code, err = run_cli("run", tmp_path / "nothing.py")
    assert code == 2 and "does not exist" in err and len(err.strip().splitlines()) == 1


def test_a_case_built_in_a_script_runs_from_python(tmp_path, capsys):
    """pn.run(CASE) on a Case made in the script itself returns its Result; the CLI, which can
    find only built-in cases and case files again, says how to load such a run."""
    import pacto_ng as pn
    from pacto_ng.case import load_case_file

    case = load_case_file(write_case(tmp_path))
    case = pn.Case(case.name + "-script", case.summary, case.source, case.defaults,
                   case.geometry, case.setup, load_unit="Pa")
    res = pn.run(case, out=tmp_path / "r", iterations=2, maxh=0.003)
    assert res.exit_code == 0 and len(res.history) == 2
    assert np.isfinite(res.objective) and res.rho_bar.shape == (res.mesh.ne,)
    assert res.summary["output_displacement"] == pytest.approx(
        float(res.problem.values["delta"]), rel=1e-10)
    assert main(["export", str(tmp_path / "r"), "--format", "stl", "--quiet"]) == 2
    assert "built in a script" in capsys.readouterr().err
