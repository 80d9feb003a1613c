"""``pacto compare`` of 3D runs (pacto_ng/post/compare.py, compare3d.py): what the 2D compare
gives, for 3D runs — the designs side by side (the ρ̄ = 0.5 iso-surfaces with one camera, the
mid-depth cuts with axes in metres), the outlines over each other, the analysis curves — and
the table a user reads, one row per run."""
import json
import shutil

import numpy as np
import pytest

from pacto_ng.cli import main
from pacto_ng.post.compare3d import common_box, cropped, read_design

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


@pytest.fixture(scope="module")
def runs3d(tmp_path_factory):
    """A short pa-gripper-3d run on a coarse mesh ("thin") and a copy of it whose design has
    more material ("thick": ρ̄ raised to the power 0.5 in design.vtu, its volume fraction in
    summary.json; compare reads these files)."""
    import pyvista as pv

    base = tmp_path_factory.mktemp("cmp3d")
    thin, thick = base / "thin", base / "thick"
    assert main(["run", "pa-gripper-3d", "--maxh", "0.01", "--iterations", "2", "--no-part",
                 "--quiet", "--out", str(thin)]) == 0
    shutil.copytree(thin, thick)
    g = pv.read(str(thick / "design.vtu"))
    g.point_data["rho_bar"] = np.sqrt(np.clip(g.point_data["rho_bar"], 0.0, 1.0))
    g.save(str(thick / "design.vtu"))
    summary = json.loads((thick / "summary.json").read_text())
    summary["volume_fraction"] = 0.321
    (thick / "summary.json").write_text(json.dumps(summary))
    return [thin, thick]


def _table(capsys):
    lines = capsys.readouterr().out.splitlines()
    assert lines[-1].startswith("picture: ")
    return lines[:-1]


def test_compare_of_two_3d_runs(runs3d, tmp_path, capsys):
    import matplotlib.image as mpimg

    pic = tmp_path / "cmp.png"
    assert main(["compare", *map(str, runs3d), "--out", str(pic)]) == 0
    img = mpimg.imread(pic)
    assert img.shape[0] > 1000 and img.shape[1] > 1000
    assert len(np.unique(img[..., :3].reshape(-1, 3), axis=0)) > 200  # views, not blank
    head, *rows = _table(capsys)
    assert head.split()[:5] == ["run", "case", "model", "load", "mesh"]
    assert "gap" not in head  # neither run was analysed
    assert [r.split()[0] for r in rows] == ["thin", "thick"]
    for folder, row in zip(runs3d, rows):
        summary = json.loads((folder / "summary.json").read_text())
        assert "pa-gripper-3d" in row and "1e+06 Pa" in row
        assert f"3D, {summary['mesh']['elements']} el." in row
        assert f"{summary['volume_fraction']:.3f}" in row
        assert format(summary["output_displacement"], ".4g") in row


def test_an_analysed_3d_run_adds_its_curves_and_gaps(runs3d, tmp_path, capsys):
    """An analysis.json (the fields compare reads) beside one run: its gap in the table and
    its curves in the picture."""
    analysed = tmp_path / "analysed"
    shutil.copytree(runs3d[1], analysed)
    (analysed / "analysis").mkdir()
    rows = [{"pressure": P, "expected": 1e-9 * P, "follower": {"delta": 0.9e-9 * P}}
            for P in (1e4, 1e5, 1e6)]
    (analysed / "analysis" / "analysis.json").write_text(json.dumps(
        {"settings": {"kinds": ["follower"], "model": "linear"}, "pressures": rows,
         "gap_at_largest_pressure": {"follower": -0.1}}))
    pic = tmp_path / "cmp.png"
    assert main(["compare", str(runs3d[0]), str(analysed), "--out", str(pic)]) == 0
    assert pic.stat().st_size > 50_000
    head, thin, thick = _table(capsys)
    assert head.split()[-2:] == ["gap", "follower"]
    assert thin.endswith("—") and thick.endswith("-10.0 %")


def test_a_design_is_read_whole_with_its_density_on_the_vertices(runs3d):
    import pyvista as pv

    raw = pv.read(str(runs3d[1] / "design.vtu"))
    d = read_design(runs3d[1] / "design.vtu")
    assert d.grid.n_cells == raw.n_cells
    assert d.grid.n_points < raw.n_points / 3  # NGSolve's copies of every vertex merged
    rho = np.asarray(d.grid.point_data["rho_bar"])
    assert 0.0 <= rho.min() < 0.5 < rho.max() <= 1.0  # the iso-surface exists
    assert d.z == pytest.approx(0.01) and d.cut_title == "cut at z = 0.01 m"
    assert d.cut.n_cells > 0
    assert common_box([d, read_design(runs3d[0] / "design.vtu")]) == pytest.approx(
        [0.0, 0.2, 0.0, 0.1, 0.0, 0.02], abs=1e-6)


def test_a_rendered_view_is_cropped_to_its_picture():
    img = np.full((50, 80, 3), 255, dtype=np.uint8)
    img[10:20, 30:60] = 0
    assert cropped(img, pad=2).shape == (14, 34, 3)
    assert cropped(np.zeros((5, 5, 3), dtype=np.uint8)).shape == (5, 5, 3)  # blank: kept


def test_a_2d_and_a_3d_run_are_not_compared(runs3d, tmp_path, capsys):
    run2d = tmp_path / "inv"
    assert main(["run", "pa-inverter", "--maxh", "0.01", "--iterations", "1", "--no-part",
                 "--quiet", "--out", str(run2d)]) == 0
    assert main(["compare", str(run2d), str(runs3d[0]), "--out", str(tmp_path / "c.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("pacto: error:") and "2D and 3D" in err
    assert not (tmp_path / "c.png").exists()


def test_a_design_without_its_density_is_named(runs3d, tmp_path, capsys):
    import pyvista as pv

    broken = tmp_path / "broken"
    shutil.copytree(runs3d[0], broken)
    g = pv.read(str(broken / "design.vtu"))
    g.point_data.remove("rho_bar")
    g.save(str(broken / "design.vtu"))
    assert main(["compare", str(runs3d[0]), str(broken), "--out", str(tmp_path / "c.png")]) == 2
    err = capsys.readouterr().err
    assert "broken/design.vtu' has no rho_bar field" in err
