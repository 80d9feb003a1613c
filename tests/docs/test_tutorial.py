"""docs/tutorial.md runs as written.

Every fenced ```python block of the tutorial is executed, in order, in one namespace, in a
temporary working directory (the tutorial's ``output/``, ``part.step`` and ``plate.msh`` land
there).  The blocks whose first line is ``# my_case.py`` are also saved, one after the other,
as ``my_case.py``, as the tutorial asks its reader to do before section 4.  The test checks
what the text claims: the names the geometry has, a finite objective, the output files, a
closed STL, the one-line error.  The ```bash blocks are the
command-line equivalents of the Python blocks (``pacto run my_case.py``, ``pacto
check-gradients my_case.py``, ``pacto export DIR --format stl``) and are not executed; untagged
fences show printed output.
"""
from __future__ import annotations

import math
import re
import time
from pathlib import Path

import numpy as np
import pytest

TUTORIAL = Path(__file__).resolve().parents[2] / "docs" / "tutorial.md"
CASE_FILE = "my_case.py"
CASE_FILE_MARK = f"# {CASE_FILE}\n"
FENCE = re.compile(r"^```(\w*)[ \t]*\n(.*?)^```[ \t]*$", re.M | re.S)


def fenced_blocks(text: str, lang: str) -> list[str]:
    """The bodies of the fenced blocks tagged ``lang``, in order."""
    return [body for tag, body in FENCE.findall(text) if tag == lang]


def test_the_tutorial_has_python_and_bash_blocks():
    text = TUTORIAL.read_text()
    py, sh = fenced_blocks(text, "python"), fenced_blocks(text, "bash")
    assert len(py) >= 8
    assert any("pacto run my_case.py" in b for b in sh)
    assert any("pacto check-gradients my_case.py" in b for b in sh)
    assert any("--format stl" in b for b in sh)
    # every fence is closed: an odd number of ``` lines would swallow the rest of the text
    assert len(re.findall(r"^```", text, re.M)) % 2 == 0
    assert "default of **100**" in text
    marked = [b for b in py if b.startswith(CASE_FILE_MARK)]
    assert len(marked) == 3 and "CASE = pn.Case(" in marked[-1]


@pytest.fixture
def in_tmp(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_tutorial_runs_as_written(in_tmp, capsys):
    import pacto_ng

    blocks = fenced_blocks(TUTORIAL.read_text(), "python")
    ns: dict = {"__name__": "__tutorial__"}
    start = time.perf_counter()
    for i, code in enumerate(blocks):
        if code.startswith(CASE_FILE_MARK):
            # what the tutorial asks the reader to do: save the marked blocks as my_case.py
            with open(CASE_FILE, "a") as fh:
                fh.write(code + "\n\n")
        try:
            exec(compile(code, f"{TUTORIAL.name}[python block {i + 1}]", "exec"), ns)
        except Exception as err:  # noqa: BLE001 - say which block failed
            pytest.fail(f"python block {i + 1} of docs/tutorial.md failed: "
                        f"{type(err).__name__}: {err}\n--- block ---\n{code}")
    elapsed = time.perf_counter() - start
    out = capsys.readouterr().out

    # 1. the geometry's names, as printed in the tutorial
    mesh = ns["mesh"]
    assert {"design", "chamber"} == set(mesh.GetMaterials())
    assert {"fixed", "inlet", "outer"} == set(mesh.GetBoundaries())
    assert "tip" in set(mesh.GetBBoundaries())
    assert "regions:    ['chamber', 'design']" in out
    assert "boundaries: ['fixed', 'inlet', 'outer']" in out

    # the case file the reader saved is a case file pacto_ng loads
    assert pacto_ng.load_case_file(CASE_FILE).name == ns["CASE"].name == "my_actuator"

    # 4. the run: a finite objective that the optimiser lowered, ten iterations, ρ̄ in [0, 1]
    result = ns["result"]
    assert isinstance(result, pacto_ng.Result)
    assert result.exit_code == 0
    assert math.isfinite(result.objective)
    assert result.objective < 0  # -Δ/SE: the tip moves down
    assert result.summary["output_displacement"] > 0
    assert len(result.history) == 10 == result.summary["iterations"]
    assert result.history[-1]["objective"] < result.history[0]["objective"]
    rho = np.asarray(result.rho_bar)
    assert rho.shape == (mesh.ne,) and np.all((rho >= -1e-12) & (rho <= 1 + 1e-12))
    assert ns["again"].objective == result.objective

    # 5. where the outputs are
    folder = in_tmp / "output" / "my_actuator"
    assert Path(result.folder).resolve() == folder.resolve()
    for name in ("summary.json", "history.csv", "design.vtu", "design.png", "convergence.png",
                 "pressure.png", "params.json", "checkpoint.npz"):
        assert (folder / name).is_file(), name

    listing = str(sorted(f.name for f in folder.iterdir() if f.name != "export"))  # before §7
    assert listing in out and listing in TUTORIAL.read_text()

    # 7. the STL (in mm): exit code 0, closed, volume = remeshed area x thickness > 0
    assert ns["code"] == 0
    stl = folder / "export" / "design.stl"
    assert stl.is_file()
    import pyvista as pv

    part = pv.read(str(stl)).clean()
    assert part.n_cells > 0
    assert part.n_open_edges == 0
    assert part.is_manifold
    thickness = result.summary["parameters"]["thickness"]
    assert np.ptp(part.points[:, 2]) == pytest.approx(1e3 * thickness, rel=1e-6)  # float32
    assert 0 < part.volume < 0.08 * 0.02 * thickness * 1e9

    # 8. other geometry sources
    assert ns["quads"].ne == 80 * 20
    assert {"design", "chamber"} == set(ns["quads"].GetMaterials())
    assert {"default", "fixed", "inlet"} == set(ns["cad"].GetBoundaries())
    assert ns["plate_mesh"].ne == 4
    assert set(ns["plate_mesh"].GetBoundaries()) == {"fixed", "load"}

    # 9. the one-line error that lists the names that exist
    message = ns["message"]
    assert "\n" not in message
    assert "'fixd'" in message and "fixed, inlet, outer" in message
    assert message in TUTORIAL.read_text()  # the tutorial shows the message as it is

    # 10. the chain as --show-chain prints it, and the own objective's gradients
    chain_text = f"my_actuator ({mesh.ne} elements, model linear):\n" + "\n".join(
        result.problem.describe())
    assert chain_text in TUTORIAL.read_text()
    assert ns["worst"] < 1e-6
    assert f"worst relative error {ns['worst']:.1e}" in out

    assert elapsed < 90, f"the tutorial took {elapsed:.0f} s"
