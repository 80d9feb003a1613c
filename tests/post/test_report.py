"""The one-call post-analysis (post.report)."""
import csv
import json

import numpy as np
import pytest

from conftest import chamber_density, chamber_pressure
from pacto_ng.physics.loads import Port
from pacto_ng.post.report import post_analyse


@pytest.fixture(autouse=True)
def _off_screen(monkeypatch):
    import pyvista as pv

    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    monkeypatch.setenv("MPLBACKEND", "Agg")


def test_post_analyse_writes_a_consistent_folder(chamber_quads, tmp_path):
    import meshio
    import pyvista as pv

    res = post_analyse(chamber_quads, chamber_density(chamber_quads), tmp_path / "post",
                       pressures=[3e4, 1e5], E=1e8, nu=0.4, thickness=1e-3,
                       output=Port("output", (0.0, -1.0), 1e4), maxh=0.003,
                       pressure=chamber_pressure, expected=([1e5], [4e-5]))
    for path in res.files.values():
        assert path.exists() and path.stat().st_size > 0
    summary = json.loads(res.files["json"].read_text())
    assert summary["thresholded_area"] == res.thresholded.area
    assert summary["remeshed_area"] == pytest.approx(res.remeshed.area, rel=1e-15)
    assert summary["deformed_state"] == "follower"
    rows = list(csv.DictReader(open(res.files["csv"])))
    assert [(r["kind"], float(r["pressure"])) for r in rows] == [
        ("fixed", 3e4), ("fixed", 1e5), ("follower", 3e4), ("follower", 1e5)]
    for r, sw in zip(rows, [res.sweeps["fixed"]] * 2 + [res.sweeps["follower"]] * 2):
        assert float(r["delta"]) in sw.delta
    stl = pv.read(res.files["stl"]).clean()
    assert stl.n_open_edges == 0
    assert stl.volume == pytest.approx(res.remeshed.area * 1e-3, rel=1e-6)
    dfm = meshio.read(res.files["deformed"])
    ref = meshio.read(res.files["remeshed"])
    np.testing.assert_allclose(dfm.points - ref.points, ref.point_data["u"], atol=1e-15)
    # the deformed state is the follower's at the last pressure: Δ read back from the VTU
    out = np.array(res.remeshed.ports["output"][1])
    k = int(np.argmin(np.linalg.norm(ref.points[:, :2] - out, axis=1)))
    assert -ref.point_data["u"][k, 1] == pytest.approx(res.sweeps["follower"].delta[-1],
                                                       rel=1e-10)
