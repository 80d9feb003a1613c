"""``pacto analyse CASE --as-built`` (post.as_built): a case's own geometry as the part.

* 2D, tests/post/cases/ring.py: a thick ring around its chamber, linear model, plane strain:
  the inner wall's displacement against Lamé's thick-walled cylinder at two mesh sizes (the
  part keeps the case's curved geometry: the error is the analysis's, falling with h); the
  chamber check (sealed; opened by a zero-pressure boundary on its own wall: a warning).
* 3D, examples/five_chamber/five_chamber.py, coarse: the Ecoflex finger on its stiff layer
  (E2 on the region ``stiff``) curls down under the follower pressure; its measures are the
  case's solids' exactly; the files and the progress lines.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

CASES = Path(__file__).parent / "cases"
EXAMPLE = Path(__file__).parents[2] / "examples" / "five_chamber" / "five_chamber.py"
E, NU, A, B = 1e6, 0.3, 0.01, 0.02


def lame(P):
    return (1 + NU) * A * A * P / (E * (B * B - A * A)) * ((1 - 2 * NU) * A + B * B / A)


def _one_line_error(capsys):
    lines = [ln for ln in capsys.readouterr().err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("pacto: error:"), lines
    return lines[0]


def test_a_thick_ring_as_built_against_lame(tmp_path):
    """Order 2 on the curved ring (its area π(b² - a²)/4 to 2e-5: the case's geometry kept):
    u_r(a) against Lamé, measured 2.2e-4 at maxh 3 mm and 8.4e-5 at 1.5 mm (a/7), the same at
    10 and 1000 Pa (linear); the follower pressure too at 10 Pa (5.5e-5: its general route
    integrates with the full rule, the linear route's fixed pressure with the rule exact on
    affine elements, 3e-5 apart on curved ones), and above it by the follower effect at
    1000 Pa (measured 1.9e-3 at P/E = 1e-3)."""
    errs = []
    for maxh in (0.003, 0.0015):
        out = tmp_path / f"ring{maxh:g}"
        assert main(["analyse", str(CASES / "ring.py"), "--as-built", "--pressures", "1e1,1e3",
                     "--kinds", "fixed,follower", "--maxh", str(maxh), "--out", str(out),
                     "--quiet"]) == 0
        data = json.loads((out / "analysis.json").read_text())
        fixed = [r["fixed"]["delta"] / lame(r["pressure"]) - 1.0 for r in data["pressures"]]
        errs.append(fixed[-1])
        assert fixed[0] == pytest.approx(fixed[1], abs=1e-9)  # a linear model: linear in P
        follower = [r["follower"]["delta"] / lame(r["pressure"]) - 1.0
                    for r in data["pressures"]]
        assert abs(follower[0]) < 5e-4 and abs(follower[0] - fixed[0]) < 1e-4
        assert 1e-3 < follower[1] - fixed[1] < 3e-3
        # the case's curved geometry (a polygon of these chords: 1e-3 off)
        assert data["part"]["measure"] == pytest.approx(np.pi * (B * B - A * A) / 4, rel=1e-4)
        assert data["part"]["wetted"] == pytest.approx(np.pi * A / 2, rel=1e-4)  # the inlet arc
    print("ring as built against Lamé:", errs)
    assert abs(errs[1]) < 2e-4 and abs(errs[1]) < abs(errs[0]) / 2
    assert data["run"]["as_built"] and data["settings"]["model"] == "linear"
    assert data["settings"]["order"] == 2 and data["settings"]["threshold"] is None
    assert data["gap_at_largest_pressure"] is None and data["pressures"][0]["expected"] is None
    assert data["seal"]["sealed"] and [c["name"] for c in data["seal"]["chambers"]] == ["chamber"]
    assert data["warnings"] == []
    for name in ("analysis.csv", "analysis.png", "deformed.png", "report.md", "part.stl",
                 "remeshed.vtu", "deformed.vtu"):
        assert (out / name).stat().st_size > 0, name
    assert "# Analysis of ring as built" in (out / "report.md").read_text()


def test_an_open_chamber_is_a_warning(tmp_path, capsys):
    """The chamber's own symmetry edge made a zero-pressure boundary: the inlet walls no
    longer bound a closed chamber; the analysis runs and says so."""
    case = tmp_path / "open_ring.py"
    case.write_text((CASES / "ring.py").read_text().replace(
        'ZERO = ("outer",)', 'ZERO = ("outer", "chamber_left")'))
    out = tmp_path / "open"
    assert main(["analyse", str(case), "--as-built", "--pressures", "1e3", "--kinds", "fixed",
                 "--maxh", "0.004", "--out", str(out), "--quiet"]) == 0
    data = json.loads((out / "analysis.json").read_text())
    assert not data["seal"]["sealed"] and data["seal"]["chambers"][0]["boundary"] == "chamber_left"
    assert any("do not bound a closed chamber" in w for w in data["warnings"])
    assert "do not bound a closed chamber" in capsys.readouterr().err
    assert "**open**" in (out / "report.md").read_text()


@pytest.mark.parametrize("argv, words", [
    (["analyse", str(CASES / "ring.py"), "--as-built", "--kinds", "darcy"], "--kinds: darcy"),
    (["analyse", "mbb", "--as-built"], "no pressure load"),
    (["analyse", str(CASES / "ring.py"), "--as-built", "--set", "material=nothing"],
     "material"),
    (["analyse", str(CASES / "ring.py"), "--as-built", "--model", "auto"], "--model"),
])
def test_bad_as_built_input_is_one_line(argv, words, capsys):
    assert main(argv) == 2
    assert words in _one_line_error(capsys)


def test_the_five_chamber_example_curls_down(tmp_path, capsys):
    """The example of examples/five_chamber (coarse: maxh 5 mm, two pressures), Ecoflex 00-30
    (the preset's Yeoh law) on its 1 MPa layer, the follower pressure: the finger curls down
    (Δ > 0, growing faster than P: it softens), the part is the case's solids less the
    chambers exactly, the layer takes E2; one progress line per pressure."""
    out = tmp_path / "fc"
    assert main(["analyse", str(EXAMPLE), "--as-built", "--set", "material=ecoflex-00-30",
                 "--model", "yeoh", "--kinds", "follower", "--maxh", "0.005", "--pressures",
                 "1e3,1e4", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert len([ln for ln in printed.splitlines() if ln.startswith("  follower yeoh P = ")]) == 2
    data = json.loads((out / "analysis.json").read_text())
    s = data["settings"]
    assert s["model"] == "yeoh" and s["material"] == "ecoflex-00-30" and s["order"] == 1
    E1 = 2 * 2 * 17.0e3 * (1 + 0.45)  # 2 μ0 (1 + ν), μ0 = 2 C10 of the preset's Yeoh fit
    assert s["E"] == {"design": pytest.approx(E1, rel=1e-12), "stiff": 1e6}
    assert data["materials"]["remeshed"]["stiff"] == pytest.approx(0.1 * 0.002 * 0.01,
                                                                   rel=1e-9)
    # the body and the layer (half width 10 mm) less the chambers and the channel
    void = 5 * 0.012 * 0.011 * 0.007 + 0.092 * 0.002 * 0.002
    assert data["part"]["measure"] == pytest.approx(0.1 * 0.02 * 0.01 - void, rel=1e-9)
    assert data["seal"]["sealed"]
    rows = data["pressures"]
    assert all(r["follower"]["converged"] for r in rows)
    assert 0 < rows[0]["follower"]["delta"] and rows[1]["follower"]["delta"] > 10 * rows[0][
        "follower"]["delta"]
    import pyvista as pv

    stl = pv.read(str(out / "part.stl"))  # whole: mirrored about symmetry_z, in mm
    assert stl.n_open_edges == 0
    assert abs(stl.volume) * 1e-9 == pytest.approx(2 * data["part"]["measure"], rel=1e-9)
    vtu = pv.read(str(out / "remeshed.vtu"))
    assert sorted(np.unique(vtu.cell_data["E"])) == pytest.approx([E1, 1e6], rel=1e-12)
