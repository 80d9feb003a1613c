"""``pacto export`` of a 3D run: the whole part, mirrored about the case's symmetry planes, and
the run's fields on the clipped solid.

The run: pa-inverter-3d (a quarter: ``symmetry`` at y = 0, ``symmetry_z`` at z = D/2 = 0.02 m)
on tetrahedra of 0.01 m, one iteration (the run folder), its design then replaced by a hand-made
one: solid for x < 0.05 m and for x < 0.15 m, y < 0.03 m (an L reaching the clamp, the inlet and
both symmetry planes).  Every expected value is computed here from the files ``export`` writes
(the triangles' volumes by the divergence theorem, the reflections by 3 x 3 matrices, the
strain from the exported u) or from the run's own settings; the mirrored files are checked
against the half written with ``--no-mirror``.
"""
import numpy as np
import pytest

from pacto_ng.cli import main

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

DH = 0.02  # symmetry_z: z = D/2 (m)
LOAD = 1e6  # pa-inverter-3d's inlet pressure (Pa)
NU = 0.4  # its Poisson's ratio


@pytest.fixture(scope="module")
def run3d(tmp_path_factory):
    from small_cases import run_with_design

    out = tmp_path_factory.mktemp("parts3d") / "inv"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PACTO_THREADS", "1")
        return run_with_design(out, ["pa-inverter-3d", "--maxh", "0.01", "--iterations", "1"],
                               lambda c: (c[:, 0] < 0.05) | ((c[:, 0] < 0.15) & (c[:, 1] < 0.03)))


def _triangles(surface):
    return np.asarray(surface.points, dtype=float)[np.asarray(surface.faces).reshape(-1, 4)[:, 1:]]


def _signed_volume(surface):
    """Σ v0·(v1 × v2) / 6 over the triangles: the enclosed volume, > 0 when they face out."""
    v = _triangles(surface)
    return float(np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6.0)


def _fold(points):
    """Every point of the whole part taken back into the quarter (y >= 0, z <= D/2), and the
    reflection (a diagonal of ±1) that maps the quarter's vectors onto it."""
    p = np.array(points, dtype=float)
    s = np.ones_like(p)
    s[p[:, 1] < 0, 1] = -1.0
    s[p[:, 2] > DH, 2] = -1.0
    p[:, 1] = np.abs(p[:, 1])
    p[:, 2] = np.where(p[:, 2] > DH, 2 * DH - p[:, 2], p[:, 2])
    return p, s


def _tensors(six):
    """(n, 6) in the order xx, yy, zz, xy, yz, xz -> (n, 3, 3)."""
    a = np.asarray(six, dtype=float)
    t = np.empty((len(a), 3, 3))
    for k, (i, j) in enumerate([(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]):
        t[:, i, j] = t[:, j, i] = a[:, k]
    return t


def test_mirrored_stl_is_the_closed_whole(run3d, tmp_path, capsys):
    import pyvista as pv

    assert main(["export", str(run3d), "--format", "stl"]) == 0
    line = capsys.readouterr().out
    assert "mirrored about 2 planes" in line and "0 open edges" in line
    half_stl = tmp_path / "half.stl"
    assert main(["export", str(run3d), "--format", "stl", "--no-mirror", "--out",
                 str(half_stl)]) == 0
    assert "the part as solved (--no-mirror)" in capsys.readouterr().out
    whole, half = pv.read(str(run3d / "export" / "design.stl")), pv.read(str(half_stl))
    assert (run3d / "export" / "design.stl").read_bytes()[:80].rstrip().endswith(
        b"whole (mirrored about 2 planes); units mm")
    # closed, manifold, one piece, no point twice
    for s in (whole, half):
        assert s.n_open_edges == 0 and s.is_manifold
    assert whole.connectivity().point_data["RegionId"].max() == 0
    assert whole.clean(tolerance=1e-6).n_points == whole.n_points
    # the whole's volume (divergence theorem over its triangles, mm³): 4 times the half's,
    # both positive (the facets face outward); the half's is the part's, 1e-9 m³ = 1 mm³
    v_whole, v_half = _signed_volume(whole), _signed_volume(half)
    assert v_half > 0 and v_whole == pytest.approx(4.0 * v_half, rel=1e-6)
    # the L: 0.05 x 0.1 x 0.02 + 0.1 x 0.03 x 0.02 m³ = 1.6e-4 m³ (measured 1.590e-4)
    assert v_half * 1e-9 == pytest.approx(1.6e-4, rel=0.05)
    # the bounding box: the half's reflected about y = 0 and z = 20 mm (to the STL's single
    # precision, 6e-8 relative), x the same
    hb, wb = np.reshape(half.bounds, (3, 2)), np.reshape(whole.bounds, (3, 2))
    eps = 1e-7 * np.abs(wb).max()
    assert hb[1, 0] == pytest.approx(0.0, abs=eps) and hb[2, 1] == pytest.approx(20.0, abs=eps)
    assert np.allclose(wb[0], hb[0], atol=eps)
    assert np.allclose(wb[1], [-hb[1, 1], hb[1, 1]], atol=eps)
    assert np.allclose(wb[2], [hb[2, 0], 40.0 - hb[2, 0]], atol=eps)
    # no face left on a symmetry plane (inside the whole part); the half has them on both

    def on_planes(s):
        v = _triangles(s)
        return [int(np.sum(np.abs(v[:, :, 1]).max(axis=1) < eps)),
                int(np.sum(np.abs(v[:, :, 2] - 20.0).max(axis=1) < eps))]

    assert on_planes(whole) == [0, 0] and min(on_planes(half)) > 0


def test_vtu_fields_and_their_mirror_image(run3d, tmp_path, capsys):
    import pyvista as pv
    from scipy.spatial import cKDTree

    assert main(["export", str(run3d), "--format", "vtu"]) == 0
    line = capsys.readouterr().out
    assert "mirrored about 2 planes" in line and "fields rho, p, u, rho_bar, strain, stress" \
        in line
    half_vtu = tmp_path / "half.vtu"
    assert main(["export", str(run3d), "--format", "vtu", "--no-mirror", "--units", "mm",
                 "--out", str(half_vtu)]) == 0
    whole, half = pv.read(str(run3d / "export" / "design.vtu")), pv.read(str(half_vtu))
    half.points = np.asarray(half.points) * 1e-3  # mm -> m
    half.point_data["u"] = np.asarray(half.point_data["u"]) * 1e-3
    for g in (whole, half):
        assert set(g.point_data) >= {"rho", "u", "p"}
        assert set(g.cell_data) >= {"rho_bar", "strain", "stress"}
        assert g.point_data["u"].shape == (g.n_points, 3)
        assert g.cell_data["stress"].shape == (g.n_cells, 6)
        for arr in [*g.point_data.values(), *g.cell_data.values()]:
            assert np.all(np.isfinite(arr))
    hp, u = np.asarray(half.points), np.asarray(half.point_data["u"])
    umax = np.abs(u).max()
    assert 1e-6 < umax < 1e-2  # m: the run's displacement in m (measured 2.5e-4)
    # the supports: no normal displacement on the symmetry planes
    on_y, on_z = np.abs(hp[:, 1]) < 1e-12, np.abs(hp[:, 2] - DH) < 1e-12
    assert on_y.sum() > 10 and on_z.sum() > 10
    assert np.abs(u[on_y, 1]).max() < 1e-12 * umax and np.abs(u[on_z, 2]).max() < 1e-12 * umax
    # the inlet x = 0 (below the clamp, behind the front face z = 0): p = P_in
    inlet = (hp[:, 0] < 1e-12) & (hp[:, 1] < 0.09) & (hp[:, 2] > 1e-6)
    assert inlet.sum() > 5 and np.allclose(half.point_data["p"][inlet], LOAD, rtol=1e-9)
    # the whole solid: 4 times the half's volume; every point and cell the image of one of
    # the half's (single-precision points: 6e-9 m), u reflected, tensors R T Rᵀ
    assert abs(whole.volume) == pytest.approx(4.0 * abs(half.volume), rel=1e-6)
    folded, s = _fold(whole.points)
    dist, idx = cKDTree(hp).query(folded)
    assert dist.max() < 1e-8
    wu = np.asarray(whole.point_data["u"])
    assert np.allclose(wu, s * u[idx], rtol=0, atol=1e-12 * umax)
    assert np.allclose(whole.point_data["p"], half.point_data["p"][idx], rtol=1e-12, atol=1e-6)
    # across the plane y = 0 the normal component flips sign: some point pairs move apart
    below = np.asarray(whole.points)[:, 1] < -1e-3
    assert np.abs(wu[below, 1]).max() > 0.1 * umax
    assert np.allclose(wu[below, 1], -u[idx[below], 1], rtol=0, atol=1e-12 * umax)
    fc, sc = _fold(whole.cell_centers().points)
    dist, ic = cKDTree(np.asarray(half.cell_centers().points)).query(fc)
    assert dist.max() < 1e-8
    for name in ("strain", "stress"):
        T = _tensors(half.cell_data[name])[ic]
        R = np.einsum("ni,ij->nij", sc, np.eye(3))
        expect = np.einsum("nij,njk,nlk->nil", R, T, R)
        got = _tensors(whole.cell_data[name])
        assert np.allclose(got, expect, rtol=0, atol=1e-12 * np.abs(T).max())
    assert np.array_equal(whole.cell_data["rho_bar"], half.cell_data["rho_bar"][ic])


def test_strain_and_stress_of_the_exported_u(run3d, tmp_path):
    """On linear tetrahedra the run's u is linear in every source element, so the strain of
    a clipped tetrahedron is sym ∇u of u at its four points; the linear model's stress is
    isotropic: tr σ = 3K tr ε, dev σ = 2μ dev ε with K / μ = 2(1 + ν) / (3(1 − 2ν))."""
    import pyvista as pv

    dst = tmp_path / "half.vtk"
    assert main(["export", str(run3d), "--format", "vtk", "--no-mirror", "--out", str(dst),
                 "--quiet"]) == 0
    g = pv.read(str(dst))
    tets = g.cells_dict[pv.CellType.TETRA]
    x = np.asarray(g.points)[tets]
    u = np.asarray(g.point_data["u"])[tets]
    dx = x[:, 1:] - x[:, :1]
    keep = np.abs(np.linalg.det(dx)) > 1e-3 * np.abs(np.linalg.det(dx)).max()
    grad = np.linalg.solve(dx[keep], u[:, 1:][keep] - u[:, :1][keep])  # rows: ∂u/∂x_i
    eps = 0.5 * (grad + np.transpose(grad, (0, 2, 1)))
    cells = np.flatnonzero(g.celltypes == pv.CellType.TETRA)[keep]
    strain = _tensors(g.cell_data["strain"])[cells]
    assert len(cells) > 100
    assert np.allclose(strain, eps, rtol=0, atol=1e-6 * np.abs(eps).max())
    sigma = _tensors(g.cell_data["stress"])[cells]
    tr_e, tr_s = np.trace(strain, axis1=1, axis2=2), np.trace(sigma, axis1=1, axis2=2)
    dev_e = strain - tr_e[:, None, None] * np.eye(3) / 3
    dev_s = sigma - tr_s[:, None, None] * np.eye(3) / 3
    two_mu = np.einsum("nij,nij->n", dev_s, dev_e) / np.einsum("nij,nij->n", dev_e, dev_e)
    assert np.allclose(dev_s, two_mu[:, None, None] * dev_e, rtol=0,
                       atol=1e-6 * np.abs(dev_s).max())
    big = np.abs(tr_e) > 1e-2 * np.abs(tr_e).max()
    ratio = (tr_s[big] / (3 * tr_e[big])) / (0.5 * two_mu[big])
    assert np.allclose(ratio, 2 * (1 + NU) / (3 * (1 - 2 * NU)), rtol=1e-6)


def test_symmetry_planes_and_refusals():
    """pneunet-3d: one plane, symmetry_z; on a unit cube (NGSolve's structured tetrahedra,
    faces renamed): two planes; faces named ``symmetry`` on two planes, two parallel symmetry
    planes, an oblique one: one line naming --mirror each."""
    import ngsolve as ng
    from netgen import occ
    from ngsolve.meshes import MakeStructured3DMesh

    from pacto_ng.geometries import solids
    from pacto_ng.params import InputError
    from pacto_ng.post.mirror3d import symmetry_planes

    pn = symmetry_planes(ng.Mesh(occ.OCCGeometry(solids.pneunet()).GenerateMesh(maxh=0.05)))
    assert [(p.name, p.axis) for p in pn] == [("symmetry_z", 2)]
    assert pn[0].offset == pytest.approx(0.015, abs=1e-12)

    def cube(names, mapping=None):
        """Faces: back x = 0, front x = 1, left y = 0, right y = 1, bottom z = 0, top z = 1."""
        m = MakeStructured3DMesh(hexes=False, nx=2, ny=2, nz=2, mapping=mapping)
        for i in range(6):
            m.ngmesh.SetBCName(i, names.get(m.ngmesh.GetBCName(i), "side"))
        return ng.Mesh(m.ngmesh)

    two = symmetry_planes(cube({"left": "symmetry", "top": "symmetry_z"}))
    assert [(p.name, p.axis, p.offset) for p in two] == [("symmetry", 1, 0.0),
                                                         ("symmetry_z", 2, 1.0)]
    with pytest.raises(InputError, match=r"^--mirror: the symmetry face 'symmetry' is not "
                                         r"planar"):
        symmetry_planes(cube({"left": "symmetry", "bottom": "symmetry"}))
    with pytest.raises(InputError, match="^--mirror: two symmetry faces are planes "
                                         "perpendicular to the same axis"):
        symmetry_planes(cube({"left": "symmetry", "right": "symmetry_y"}))
    with pytest.raises(InputError, match="^--mirror: the symmetry face 'symmetry' is a plane "
                                         "not perpendicular to x, y or z"):
        symmetry_planes(cube({"left": "symmetry"}, lambda x, y, z: (x, y + 0.5 * x, z)))
