"""``pacto export`` of a half-domain case as a part to fabricate from: the whole mechanism
(mirrored about the symmetry line, the halves merged), in mm by default for STL, extruded by the
case's own thickness, and a VTU with the run's fields on the part.

The run is the small pa-inverter of tests/post/test_cli_post.py (15 iterations at 1e5 Pa,
maxh 0.01, the same options), made once per module (about 13 s); pa-inverter is solved on its
upper half, the symmetry line y = 0.  At threshold 0.25 its part reaches the symmetry line (at
0.3 and above it does not), so the halves must join there.  Every expected value is computed
here from what the run wrote (params.json, design.vtu) or from the half part written with
``--no-mirror``.
"""
import json

import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

THRESHOLD = "0.25"


@pytest.fixture(scope="module")
def half_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("fabricable") / "pa"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        rc = main(["run", "pa-inverter", "--load", "1e5", "--maxh", "0.01", "--iterations",
                   "15", "--set", "filter_radius=0.03", "--set", "penal_start=0", "--set",
                   "move=0.2", "--set", "robust=0", "--out", str(out), "--quiet"])
    assert rc == 0
    assert json.loads((out / "summary.json").read_text())["symmetric_half_domain"] is True
    return out


@pytest.fixture(scope="module")
def exported(half_run):
    """The default STL and VTU (whole, mm / m) and the half as solved (VTU, m)."""
    files = {"stl": half_run / "export" / "design.stl", "vtu": half_run / "export" / "design.vtu",
             "half": half_run / "export" / "half.vtu"}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        for fmt in ("stl", "vtu"):
            assert main(["export", str(half_run), "--format", fmt, "--threshold", THRESHOLD,
                         "--quiet"]) == 0
        assert main(["export", str(half_run), "--format", "vtu", "--threshold", THRESHOLD,
                     "--no-mirror", "--units", "m", "--out", str(files["half"]), "--quiet"]) == 0
    return files


def _areas(points, tris):
    p = np.asarray(points)[:, :2]
    a, b = p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]]
    return 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def test_the_stl_is_the_whole_closed_part_in_mm(half_run, exported):
    import meshio
    import pyvista as pv

    t = json.loads((half_run / "params.json").read_text())["params"]["thickness"]  # m
    half = meshio.read(exported["half"])
    tri = half.cells_dict["triangle"]
    area_half = float(_areas(half.points, tri).sum())  # m², the thresholded, remeshed half
    on_line = np.abs(half.points[:, 1]) < 1e-12
    assert on_line.sum() >= 2  # the half reaches the symmetry line: the halves join there

    raw = exported["stl"].read_bytes()
    assert b"units mm" in raw[:80] and not raw[:5].lower().startswith(b"solid")
    stl = pv.read(exported["stl"]).clean()
    assert stl.n_open_edges == 0 and stl.is_manifold
    # one solid: the two halves merged along the line (no inner faces, no double vertices)
    assert stl.connectivity().point_data["RegionId"].max() == 0
    assert stl.n_points == 2 * (2 * len(half.points) - on_line.sum())
    # mm: volume (mm³) = 2 × half area × thickness, converted
    assert stl.volume == pytest.approx(2.0 * area_half * t * 1e9, rel=1e-6)
    assert np.ptp(stl.points[:, 2]) == pytest.approx(t * 1e3, rel=1e-6)
    # mirrored about y = 0: the y range is symmetric, and that of the half in mm
    ymax = half.points[:, 1].max() * 1e3
    assert stl.points[:, 1].max() == pytest.approx(ymax, rel=1e-6)
    assert stl.points[:, 1].min() == pytest.approx(-ymax, rel=1e-6)


def test_the_vtu_carries_the_run_fields_on_the_whole_part(half_run, exported):
    """ρ̄, strain and stress per cell equal design.vtu's (the run's own file) in the optimisation
    element that holds the cell's centroid (reflected for the mirror image, its xy components
    changing sign); u and p at the vertices, finite, u's y component reflected."""
    import meshio

    whole, half = meshio.read(exported["vtu"]), meshio.read(exported["half"])
    n, ne = len(whole.points), sum(len(b.data) for b in whole.cells)
    on_line = np.abs(half.points[:, 1]) < 1e-12
    assert n == 2 * len(half.points) - on_line.sum()  # no duplicate vertices on the line
    tri = whole.cells_dict["triangle"]
    assert ne == len(tri) == 2 * len(half.cells_dict["triangle"])
    assert _areas(whole.points, tri).sum() == pytest.approx(
        2.0 * _areas(half.points, half.cells_dict["triangle"]).sum(), rel=1e-12)
    # the fields: a linear run's design.vtu names (strain, stress), plus rho_bar, u and p
    cell = {k: v[0] for k, v in whole.cell_data.items()}
    expected = {"rho_bar"} | {f"{m}_{c}" for m in ("strain", "stress") for c in ("xx", "yy", "xy")}
    assert set(cell) == expected
    assert set(whole.point_data) == {"u", "p"}
    assert whole.point_data["u"].shape == (n, 3) and whole.point_data["p"].shape == (n,)
    for key, val in {**cell, **whole.point_data}.items():
        assert len(val) == (ne if key in cell else n) and np.all(np.isfinite(val)), key
    assert np.ptp(cell["stress_xx"]) > 0 and np.abs(whole.point_data["u"]).max() > 0

    # against the run's design.vtu (VTKOutput: three points per element, P0 values on them)
    design = meshio.read(half_run / "design.vtu")
    dp = design.points[:, :2]
    dtri = design.cells_dict["triangle"]
    A, B, C = dp[dtri[:, 0]], dp[dtri[:, 1]], dp[dtri[:, 2]]
    cen = whole.points[tri, :2].mean(axis=1)
    mirrored = cen[:, 1] < 0
    cen[mirrored, 1] *= -1
    v0, v1 = B - A, C - A
    det = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
    for k, q in enumerate(cen):
        w = q - A
        l1 = (w[:, 0] * v1[:, 1] - w[:, 1] * v1[:, 0]) / det
        l2 = (v0[:, 0] * w[:, 1] - v0[:, 1] * w[:, 0]) / det
        holds = np.flatnonzero(np.minimum(np.minimum(l1, l2), 1 - l1 - l2) > -1e-9)
        assert len(holds), k  # on an element, or on the edge of two (either value)
        for key, val in cell.items():
            sign = -1.0 if mirrored[k] and key.endswith("_xy") else 1.0
            ref = sign * design.point_data[key][dtri[holds, 0]]
            scale = np.abs(design.point_data[key]).max()
            assert np.min(np.abs(ref - val[k])) <= 1e-9 * scale, (key, k)
    # u and p of the mirror image: the original's, u_y reflected
    pts = whole.points[:, :2]
    lower = np.flatnonzero(pts[:, 1] < -1e-12)
    upper = {tuple(np.round(p, 12)): i for i, p in enumerate(pts) if p[1] > 1e-12}
    pair = np.array([upper[(round(pts[i, 0], 12), round(-pts[i, 1], 12))] for i in lower])
    u = whole.point_data["u"]
    np.testing.assert_allclose(u[lower, 0], u[pair, 0], rtol=0, atol=1e-12 * np.abs(u).max())
    np.testing.assert_allclose(u[lower, 1], -u[pair, 1], rtol=0, atol=1e-12 * np.abs(u).max())
    np.testing.assert_array_equal(whole.point_data["p"][lower], whole.point_data["p"][pair])
    # the run's Darcy pressure at the part: the inlet pressure (the run's load) where the part
    # meets the inlet, not above it
    assert whole.point_data["p"].max() == pytest.approx(1e5, rel=1e-3)


def test_the_thickness_is_the_runs(half_run, exported, tmp_path):
    """The STL's thickness is params.json's: the same run with thickness 4 mm in its
    params.json (the design, and so the part, do not depend on it) exports 4 mm thick, with
    four times the volume, here in m (--units m)."""
    import shutil

    import pyvista as pv

    run = tmp_path / "thick"
    shutil.copytree(half_run, run, ignore=shutil.ignore_patterns("export"))
    info = json.loads((run / "params.json").read_text())
    t1 = info["params"]["thickness"]
    info["params"]["thickness"] = 4e-3
    (run / "params.json").write_text(json.dumps(info))
    out = tmp_path / "thick.stl"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        assert main(["export", str(run), "--format", "stl", "--threshold", THRESHOLD, "--units",
                     "m", "--out", str(out), "--quiet"]) == 0
    thick, ref = pv.read(out).clean(), pv.read(exported["stl"]).clean()
    assert out.read_bytes()[:80].rstrip().endswith(b"units m")
    assert thick.n_open_edges == 0
    assert np.ptp(thick.points[:, 2]) == pytest.approx(4e-3, rel=1e-6)
    # ref is in mm and t1 thick
    assert thick.volume == pytest.approx(ref.volume * 1e-9 * 4e-3 / t1, rel=1e-6)


def test_units_inch_is_refused_in_one_line(half_run, capsys):
    capsys.readouterr()
    assert main(["export", str(half_run), "--format", "stl", "--units", "inch"]) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert len(err) == 1 and err[0].startswith("pacto: error:") and "--units" in err[0]


def test_the_line_says_what_the_part_was_mirrored_about(half_run, exported, tmp_path, capsys):
    """The printed line says it as a 3D run's does: the whole part mirrored about the symmetry
    line, or the part as solved with ``--no-mirror``."""
    capsys.readouterr()
    for extra, words in (([], "; units m; whole: mirrored about 1 line (symmetry: y = 0 m)"),
                         (["--no-mirror"], "; units m; the part as solved (--no-mirror)")):
        assert main(["export", str(half_run), "--format", "msh", "--threshold", THRESHOLD,
                     "--out", str(tmp_path / "p.msh"), *extra]) == 0
        line = capsys.readouterr().out
        assert words in line and "(whole:" not in line, line
