"""``pacto analyse`` (post.analyse): one flow for 2D and 3D.

Two small runs, their designs chosen (small_cases.run_with_design): a 2D chamber beam whose
output is the mean over its right *edge* (tests/post/cases/edge_port.py: a port on a boundary,
which the part must reach and which is read as the mean over the part's edge), and the 3D
pneunet-3d member of test_3d_post.py.  Both analyses write the same files and an
analysis.json of the same layout.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

EDGE_CASE = Path(__file__).parent / "cases" / "edge_port.py"
FILES = ("analysis.json", "analysis.csv", "analysis.png", "deformed.png", "report.md",
         "part.stl", "remeshed.vtu", "deformed.vtu")


@pytest.fixture(scope="module")
def edge_run(tmp_path_factory):
    """The chamber beam, solid in the band 5 mm < y < 40 mm (the cavity's walls, out to the
    right edge), analysed at 1e3 and 1e4 Pa."""
    from small_cases import run_with_design

    out = run_with_design(tmp_path_factory.mktemp("edge") / "run",
                          [str(EDGE_CASE), "--iterations", "1"],
                          lambda c: (c[:, 1] > 0.005) & (c[:, 1] < 0.04))
    assert main(["analyse", str(out), "--pressures", "1e3,1e4", "--quiet"]) == 0
    return out, json.loads((out / "analysis" / "analysis.json").read_text())


@pytest.fixture(scope="module")
def run3d(tmp_path_factory):
    """pneunet-3d, solid below y = 0.03 m (test_3d_post.py's), analysed with the fixed
    pressure at 1e3 and 1e4 Pa."""
    from small_cases import run_with_design

    out = run_with_design(tmp_path_factory.mktemp("an3d") / "pn",
                          ["pneunet-3d", "--maxh", "0.006", "--iterations", "1", "--set",
                           "filter_radius=0.004"], lambda c: c[:, 1] < 0.03)
    assert main(["analyse", str(out), "--pressures", "1e3,1e4", "--kinds", "fixed",
                 "--quiet"]) == 0
    return out, json.loads((out / "analysis" / "analysis.json").read_text())


def _keys(data):
    """The layout: the top-level keys, and those of the run, settings, part, a row and a
    kind's entry of a row."""
    row = data["pressures"][0]
    return {"top": set(data), "run": set(data["run"]), "settings": set(data["settings"]),
            "part": set(data["part"]), "row": set(row) - {"darcy", "follower"},
            "kind": set(row["fixed"])}


def test_2d_and_3d_write_the_same_layout(edge_run, run3d):
    (out2, d2), (out3, d3) = edge_run, run3d
    assert d2["run"]["dim"] == 2 and d3["run"]["dim"] == 3
    assert _keys(d2) == _keys(d3)
    for out in (out2, out3):
        for name in FILES:
            assert (out / "analysis" / name).stat().st_size > 0, (out, name)
        md = (out / "analysis" / "report.md").read_text()
        for section in ("## The part", "## The seal", "## The analyses", "## The gap",
                        "## Warnings", "## Pictures"):
            assert section in md, (out, section)
    # the default order and element size: the run's own part's (order 2; half the design's
    # element size in 2D, the design's in 3D); the run's own model
    assert d2["settings"]["order"] == 2 and d3["settings"]["order"] == 2
    assert d2["settings"]["maxh"] == pytest.approx(0.5 * d2["run"]["mesh_h"])
    assert d3["settings"]["maxh"] == pytest.approx(d3["run"]["mesh_h"])
    assert d2["settings"]["model"] == d3["settings"]["model"] == "linear"
    assert d2["settings"]["kinds"] == ["darcy", "fixed", "follower"]


def test_the_chamber_s_volume_change_is_reported_where_the_part_is_sealed(edge_run, run3d):
    """Each pressure's ``volume_change`` for the wall-pressure kinds of a sealed part: the
    chamber grows under pressure, ten times as much at ten times the (small) pressure of a
    linear model; None for the darcy kind and for a part whose chamber is open."""
    for _, data in (edge_run, run3d):
        rows, sealed = data["pressures"], data["seal"]["sealed"]
        for kind in set(rows[0]) & {"fixed", "follower"}:
            low, high = (row[kind]["volume_change"] for row in rows)
            if sealed:
                assert 0 < low and high == pytest.approx(10 * low, rel=1e-3)
            else:
                assert low is None and high is None
        assert all(row["darcy"]["volume_change"] is None for row in rows if "darcy" in row)
    assert run3d[1]["seal"]["sealed"]  # one of the two is checked with a chamber


def test_a_port_on_an_edge_is_analysed(edge_run):
    """The output is the mean of -u_y over the part's edge on ``tip``: the part reaches the
    edge (about 0.035 m of it: the solid band), and Δ is that mean, read back here from
    remeshed.vtu's u along the edge (the trapezoidal mean of the vertex values, to 1e-3:
    the order-2 field between them)."""
    import meshio

    out, data = edge_run
    assert data["settings"]["threshold_choice"]["boundary_ports"] == {"tip": True}
    # (the band's edges are the nodal density's iso-lines: within an element of y = 5 and 40 mm)
    assert data["part"]["boundaries"]["tip"] == pytest.approx(0.035, abs=0.004)
    assert data["part"]["port_shifts"] == {}  # no named point to move
    for row in data["pressures"]:
        for kind in ("darcy", "fixed", "follower"):
            assert row[kind]["converged"] and row[kind]["delta"] != 0
    m = meshio.read(out / "analysis" / "remeshed.vtu")
    on = np.abs(m.points[:, 0] - 0.1) < 1e-12
    y, uy = m.points[on, 1], m.point_data["u"][on, 1]
    order = np.argsort(y)
    mean = -np.trapezoid(uy[order], y[order]) / (y.max() - y.min())
    assert mean == pytest.approx(data["pressures"][-1]["follower"]["delta"], rel=1e-3)
    vec = data["pressures"][-1]["follower"]["vectors"]["tip"]
    assert -vec[1] == pytest.approx(data["pressures"][-1]["follower"]["delta"], rel=1e-12)


def test_the_gap_taken_apart_adds_up(edge_run):
    """analysis.json's ``gap_parts``: per wall-pressure kind, threshold (the part's solid
    rounded onto the design mesh) + remesh (the part under the same Darcy load) + wall
    pressure (instead of the Darcy body force) add up to the kind's gap; the rounded design's
    Δ of this linear run scales with P; report.md tabulates the steps."""
    out, d = edge_run
    top = d["pressures"][-1]
    lo = d["pressures"][0]
    assert top["rounded"] / lo["rounded"] == pytest.approx(10.0, rel=1e-9)
    e, r, dd = top["expected"], top["rounded"], top["darcy"]["delta"]
    parts = d["gap_parts"]
    assert set(parts) == {"fixed", "follower"}
    for kind, g in parts.items():
        assert g["threshold"] == pytest.approx((r - e) / abs(e), rel=1e-12)
        assert g["remesh"] == pytest.approx((dd - r) / abs(e), rel=1e-12)
        assert (g["threshold"] + g["remesh"] + g["wall_pressure"]
                == pytest.approx(g["total"], rel=1e-12, abs=1e-15))
        assert g["total"] == pytest.approx(d["gap_at_largest_pressure"][kind], rel=1e-12)
    md = (out / "analysis" / "report.md").read_text()
    assert "Where it comes from" in md and "| fixed |" in md


def test_contact_changes_nothing_where_no_walls_touch(edge_run, tmp_path):
    """``--contact``: the part's boundaries in self-contact.  The chamber beam's walls do not
    touch at 1e3 and 1e4 Pa, so each kind's Δ is the one without contact (to Newton's
    tolerance: the linear model then takes Newton's route) and the contact's area is 0;
    analysis.json records the setting."""
    import shutil

    out, plain = edge_run
    copy = tmp_path / "run"
    shutil.copytree(out, copy)
    assert main(["analyse", str(copy), "--pressures", "1e3,1e4", "--contact", "--quiet"]) == 0
    data = json.loads((copy / "analysis" / "analysis.json").read_text())
    assert data["settings"]["contact"] is True and plain["settings"]["contact"] is False
    for row, ref in zip(data["pressures"], plain["pressures"]):
        for kind in ("fixed", "follower", "darcy"):
            assert row[kind]["delta"] == pytest.approx(ref[kind]["delta"], rel=1e-8)
            assert row[kind]["contact"] == {"area": 0.0, "force": 0.0, "pressure": 0.0}
            assert ref[kind]["contact"] is None
    assert plain["first_contact"] is None
    assert data["first_contact"] == {k: {"pressure": None, "last_without": 1e4}
                                     for k in ("darcy", "fixed", "follower")}


@pytest.mark.parametrize("model", [[], ["--model", "neohookean", "--set", "nu=0.49"]],
                         ids=["linear", "mixed"])
def test_contact_is_reported_where_walls_touch(tmp_path, model):
    """``--contact`` on a part whose walls meet: tests/post/cases/slotted_block.py as built
    (a slotted block squeezed by a pressure on its top and bottom, 264 elements), at 500,
    1500 and 3000 Pa.  The slot is open at 500 Pa and shut at 1500 Pa: analysis.json records
    per pressure and kind the contact's area, force and largest pressure (0 where the walls do
    not touch, growing with the load where they do), and per kind the first swept pressure
    with contact and the one before it; report.md tabulates them; deformed.png marks the
    walls' vertices in contact in red.  Also near-incompressible (ν = 0.49), where the part is
    analysed with the mixed formulation."""
    from matplotlib.image import imread

    out = tmp_path / "slot"
    assert main(["analyse", str(Path(__file__).parent / "cases" / "slotted_block.py"),
                 "--as-built", "--pressures", "500,1500,3000", "--contact", "--out", str(out),
                 "--quiet", *model]) == 0
    data = json.loads((out / "analysis.json").read_text())
    assert model == [] or data["settings"]["formulation"] == "mixed"
    kinds = data["settings"]["kinds"]
    assert kinds == ["fixed", "follower"] and {"contact", "first_contact"} <= set(
        data["definitions"])
    for kind in kinds:
        c = [row[kind]["contact"] for row in data["pressures"]]
        assert all(set(ci) == {"area", "force", "pressure"} for ci in c)
        assert c[0] == {"area": 0.0, "force": 0.0, "pressure": 0.0}
        for ci in c[1:]:
            assert ci["area"] > 0 and ci["force"] > 0 and ci["pressure"] > 0
        assert c[2]["force"] > c[1]["force"] and c[2]["pressure"] > c[1]["pressure"]
        assert data["first_contact"][kind] == {"pressure": 1500.0, "last_without": 500.0}
    md = (out / "report.md").read_text()
    assert "### Walls in contact" in md and "first contact at 1500 Pa" in md
    rgb = imread(out / "deformed.png")[..., :3]
    red = (rgb[..., 0] > 0.9) & (rgb[..., 1] < 0.2) & (rgb[..., 2] < 0.2)
    assert red.sum() > 20


def test_a_contact_sweep_says_its_time_and_is_refused_past_the_time_limit(tmp_path, capsys):
    """With ``--contact`` each kind's sweep first says what one Newton iteration with contact
    measured on the part and the range of time it may take; where even the lower figure is
    over ``--time-limit`` the analysis stops with one line naming ``--contact`` (exit 2) and
    writes nothing: 0.06 s lets the analysis without contact through (estimated 0.042 s) and
    not the one with it (at least 12 Newton iterations, 0.025 s each, measured 2026-12-06)."""
    case = str(Path(__file__).parent / "cases" / "slotted_block.py")
    out = tmp_path / "slot"
    assert main(["analyse", case, "--as-built", "--pressures", "500", "--kinds", "fixed",
                 "--contact", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "fixed: with contact:" in said and "per Newton iteration (measured)" in said
    code = main(["analyse", case, "--as-built", "--pressures", "500", "--kinds", "fixed",
                 "--contact", "--time-limit", "0.06", "--out", str(tmp_path / "refused")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("pacto: error: --contact:")
    assert "--time-limit" in err[0] and not (tmp_path / "refused").exists()
