"""Pictures of a case solved on a symmetric half show the whole mechanism (post.plots,
post.domain.symmetry_line, pictures.plot_deformed)."""
import numpy as np
import pytest

from conftest import centroids, half_disc_shape, name_edges
from pacto_ng.post.domain import Line, symmetry_line
from pacto_ng.post.plots import element_polygons, picture_polygons, picture_triangulation


@pytest.fixture(scope="module")
def pa_half():
    """The pa-inverter's half domain (0.2 x 0.1 m, ``symmetry`` at y = 0), Netgen triangles."""
    from pacto_ng.case import get_case, mesh_for

    case = get_case("pa-inverter")
    return mesh_for(case, case.defaults).mesh


def _design(mesh):
    """A half pa-inverter-like design: a wall along the inlet and an arm to the output."""
    c = centroids(mesh)
    return np.clip(np.exp(-((c[:, 0] - 0.03) / 0.02) ** 2) + (np.abs(c[:, 1] - 0.03) < 0.01), 0, 1)


def _assert_symmetric(polys, values, line):
    """Every polygon's mirror image is a polygon of the set with the same value."""
    from scipy.spatial import cKDTree

    cen = np.array([p.mean(axis=0) for p in polys])
    scale = float(np.ptp(cen, axis=0).max())
    dist, idx = cKDTree(cen).query(line.reflect(cen))
    assert dist.max() < 1e-12 * scale
    assert np.array_equal(values[idx], values)
    # and the image of each polygon is that polygon (same vertices)
    for k in range(0, len(polys), 97):
        img = line.reflect(polys[k])
        other = polys[idx[k]]
        assert np.abs(np.sort(img, axis=0) - np.sort(other, axis=0)).max() < 1e-12 * scale


def test_half_pa_inverter_design_is_drawn_whole(pa_half):
    rho = _design(pa_half)
    line = symmetry_line(pa_half)
    assert line is not None
    assert line.point[1] == pytest.approx(0.0, abs=1e-15)
    assert line.direction == pytest.approx((1.0, 0.0))
    polys, vals, used = picture_polygons(pa_half, rho)
    assert used == line and len(polys) == 2 * pa_half.ne
    _assert_symmetric(polys, vals, line)
    allpts = np.concatenate(polys)
    assert allpts[:, 1].min() == pytest.approx(-0.1) and allpts[:, 1].max() == pytest.approx(0.1)
    # the half is still available
    half, hv, none = picture_polygons(pa_half, rho, mirror=False)
    assert none is None and len(half) == pa_half.ne and np.array_equal(hv, rho)
    # the vertex picture (pressure.png): the mirrored triangulation, values repeated
    tri, v, _ = picture_triangulation(pa_half, np.arange(pa_half.nv, dtype=float))
    assert len(tri.x) == 2 * pa_half.nv and len(tri.triangles) == 2 * pa_half.ne
    assert np.allclose(tri.y[pa_half.nv:], -tri.y[:pa_half.nv])
    assert np.array_equal(v[pa_half.nv:], v[:pa_half.nv])


def _mesh(shape, maxh):
    import ngsolve as ng
    from netgen import occ

    return ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))


def test_a_tilted_symmetry_line():
    """The line is computed from the boundary's vertices: here y = x (a wedge whose diagonal
    edge is the symmetry)."""
    from netgen import occ

    shape = occ.WorkPlane().MoveTo(0, 0).LineTo(1, 0).LineTo(1, 0.6).LineTo(0.5, 0.5).Close() \
        .Face()
    name_edges(shape, lambda x, y: "symmetry" if abs(x - y) < 1e-9 else "free")
    mesh = _mesh(shape, 0.1)
    line = symmetry_line(mesh)
    assert line.direction == pytest.approx((np.sqrt(0.5), np.sqrt(0.5)))
    assert abs(line.point[0] - line.point[1]) < 1e-12
    rho = centroids(mesh)[:, 0]
    polys, vals, _ = picture_polygons(mesh, rho)
    _assert_symmetric(polys, vals, line)


def test_no_mirror_without_a_straight_symmetry(chamber_trigs):
    """A mesh without ``symmetry`` is drawn as it is; a curved ``symmetry`` is not mirrored."""
    rho = np.linspace(0, 1, chamber_trigs.ne)
    polys, vals, line = picture_polygons(chamber_trigs, rho)
    assert line is None and symmetry_line(chamber_trigs) is None
    ref = element_polygons(chamber_trigs)
    assert len(polys) == len(ref) and all(np.array_equal(p, q[:, :2]) for p, q in zip(polys, ref))
    assert np.array_equal(vals, rho)
    curved = half_disc_shape()
    name_edges(curved, lambda x, y: "symmetry" if abs(y) > 1e-9 else "fixed")
    assert symmetry_line(_mesh(curved, 0.2)) is None


def test_reflect_about_a_line():
    line = Line((1.0, 0.0), (0.0, 1.0))  # x = 1
    assert line.reflect(np.array([[3.0, 2.0], [1.0, 5.0]])) == pytest.approx(
        np.array([[-1.0, 2.0], [1.0, 5.0]]))


def test_pictures_are_written_mirrored(pa_half, tmp_path):
    """density_png and plot_deformed draw the whole mechanism (a smoke test: the files exist
    and the picture is twice as tall as the half alone)."""

    import matplotlib.image as mpimg
    import ngsolve as ng

    from pacto_ng.outputs import Drawn
    from pacto_ng.post.pictures import plot_deformed
    from pacto_ng.post.plots import density_png

    drawn = Drawn(pa_half, "pa", "linear", 0.3, _design(pa_half))
    for mirror in (True, False):
        density_png(tmp_path / f"design_{mirror}.png", drawn, title="t", mirror=mirror)
    whole = mpimg.imread(tmp_path / "design_True.png")
    half = mpimg.imread(tmp_path / "design_False.png")
    assert whole.shape[0] > 1.5 * half.shape[0]  # twice as tall (the figure follows the data)
    fes = ng.VectorH1(pa_half, order=1)
    u = ng.GridFunction(fes)
    u.Set(ng.CF((1e-3 * ng.x, 0.0)))
    plot_deformed(tmp_path / "deformed.png", pa_half, u, mirror=True)
    assert mpimg.imread(tmp_path / "deformed.png")[..., :3].std() > 0.05
