"""STL, VTU, format conversion and pictures (post.export)."""
import numpy as np
import pytest

from pacto_ng.physics.materials import neohookean_energy
from pacto_ng.post.export import convert, write_stl, write_vtu
from pacto_ng.post.pictures import plot_deformed, plot_sweeps

T = 1e-3  # thickness (m)


@pytest.fixture(autouse=True)
def _off_screen(monkeypatch):
    import pyvista as pv

    monkeypatch.setattr(pv, "OFF_SCREEN", True)
    monkeypatch.setenv("MPLBACKEND", "Agg")


@pytest.mark.parametrize("source", ["remeshed", "clipped"])
def test_stl_is_watertight_and_has_the_right_volume(chamber_remeshed, tmp_path, source):
    import pyvista as pv

    th, rm = chamber_remeshed
    src, area = (rm.mesh, rm.area) if source == "remeshed" else (th.solid, th.area)
    path = tmp_path / "design.stl"
    write_stl(path, src, T)
    back = pv.read(path).clean()
    assert back.n_open_edges == 0
    assert back.is_manifold
    assert back.volume == pytest.approx(area * T, rel=1e-6)
    assert np.ptp(back.points[:, 2]) == pytest.approx(T, rel=1e-12)


def _square(n=4):
    from pacto_ng.mesh import Layout, netgen_mesh

    return netgen_mesh(Layout(1.0, 1.0), 1.0 / n)


def test_vtu_fields_of_a_homogeneous_stretch(tmp_path):
    """u = (a x, b y): F = diag(1+a, 1+b, 1), J = (1+a)(1+b), and the Neo-Hookean Cauchy stress
    σ = μ/J (F Fᵀ - I) + λ ln J / J I, the closed form for
    φ = μ/2 (I1-3) - μ ln J + λ/2 ln² J: the stress by automatic differentiation of the
    energy the VTU is given, σ_zz from the plane-strain embedding F33 = 1."""
    import meshio
    import ngsolve as ng

    mesh = _square()
    a, b, E, nu = 0.1, -0.05, 2e6, 0.3
    u = ng.GridFunction(ng.VectorH1(mesh, order=1))
    u.Set(ng.CF((a * ng.x, b * ng.y)))
    phi = lambda G: neohookean_energy(G, E, nu)  # noqa: E731 - the part's energy density
    write_vtu(tmp_path / "remeshed.vtu", mesh, u, phi=phi)
    write_vtu(tmp_path / "deformed.vtu", mesh, u, phi=phi, deformed=True)
    ref, dfm = meshio.read(tmp_path / "remeshed.vtu"), meshio.read(tmp_path / "deformed.vtu")
    X = ref.points
    np.testing.assert_allclose(ref.point_data["u"][:, :2], np.c_[a * X[:, 0], b * X[:, 1]],
                               atol=1e-14)
    np.testing.assert_allclose(dfm.points, X + ref.point_data["u"], atol=1e-14)
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    J = (1 + a) * (1 + b)
    sig = mu / J * (np.diag([(1 + a) ** 2, (1 + b) ** 2, 1.0]) - np.eye(3)) \
        + lam * np.log(J) / J * np.eye(3)
    dev = sig - np.trace(sig) / 3 * np.eye(3)
    vm = np.sqrt(1.5 * np.sum(dev * dev))
    np.testing.assert_allclose(ref.cell_data["J"][0], J, rtol=1e-13)
    np.testing.assert_allclose(ref.cell_data["stress"][0], np.tile(sig.ravel(), (mesh.ne, 1)),
                               rtol=1e-12, atol=1e-9 * mu)
    np.testing.assert_allclose(ref.cell_data["von_mises"][0], vm, rtol=1e-12)


def test_vtu_fields_of_a_homogeneous_stretch_3d(tmp_path):
    """The same in 3D: u = (a x, b y, c z) on tetrahedra, F = diag(1+a, 1+b, 1+c), and a
    two-region part (material, material_<name> and E per cell)."""
    import meshio
    import ngsolve as ng
    from netgen import occ

    lower, upper = occ.Box((0, 0, 0), (1, 1, 0.5)), occ.Box((0, 0, 0.5), (1, 1, 1))
    lower.mat("design")
    upper.mat("stiff")
    mesh = ng.Mesh(occ.OCCGeometry(occ.Glue([lower, upper])).GenerateMesh(maxh=0.5))
    a, b, c, E, nu = 0.1, -0.05, 0.02, 2e6, 0.3
    u = ng.GridFunction(ng.VectorH1(mesh, order=1))
    u.Set(ng.CF((a * ng.x, b * ng.y, c * ng.z)))
    write_vtu(tmp_path / "r.vtu", mesh, u, phi=lambda G: neohookean_energy(G, E, nu),
              E={"design": E, "stiff": 10 * E})
    write_vtu(tmp_path / "d.vtu", mesh, u, deformed=True)
    ref, dfm = meshio.read(tmp_path / "r.vtu"), meshio.read(tmp_path / "d.vtu")
    X = ref.points
    np.testing.assert_allclose(ref.point_data["u"], X * [a, b, c], atol=1e-14)
    np.testing.assert_allclose(dfm.points, X + ref.point_data["u"], atol=1e-14)
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    F = np.diag([1 + a, 1 + b, 1 + c])
    J = np.linalg.det(F)
    sig = mu / J * (F @ F.T - np.eye(3)) + lam * np.log(J) / J * np.eye(3)
    np.testing.assert_allclose(ref.cell_data["J"][0], J, rtol=1e-13)
    np.testing.assert_allclose(ref.cell_data["stress"][0], np.tile(sig.ravel(), (mesh.ne, 1)),
                               rtol=1e-12, atol=1e-9 * mu)
    mat = ref.cell_data["material"][0]
    assert set(mat) == {1, 2}
    np.testing.assert_array_equal(ref.cell_data["E"][0], np.where(mat == 2, 10 * E, E))
    np.testing.assert_array_equal(ref.cell_data["material_stiff"][0], mat == 2)


def test_convert_round_trip(tmp_path):
    import meshio

    mesh = _square()
    write_vtu(tmp_path / "a.vtu", mesh)
    convert(tmp_path / "a.vtu", tmp_path / "b.msh")
    convert(tmp_path / "b.msh", tmp_path / "c.vtk")
    convert(tmp_path / "c.vtk", tmp_path / "d.stl")
    a = meshio.read(tmp_path / "a.vtu")
    c = meshio.read(tmp_path / "c.vtk")
    np.testing.assert_allclose(c.points, a.points, atol=1e-12)
    np.testing.assert_array_equal(c.cells_dict["triangle"], a.cells_dict["triangle"])
    d = meshio.read(tmp_path / "d.stl")
    assert len(d.cells_dict["triangle"]) == mesh.ne
    with pytest.raises(ValueError, match="unsupported format"):
        convert(tmp_path / "a.vtu", tmp_path / "a.obj")


def test_pictures(chamber_remeshed, chamber_sweeps, tmp_path):
    """deformed.png and analysis.png are written and are not blank."""
    import matplotlib.image as mpimg

    th, rm = chamber_remeshed
    res = chamber_sweeps
    plot_deformed(tmp_path / "deformed.png", rm.mesh, res["follower"].displacement(),
                  title="chamber at 1e5 Pa (follower)")
    plot_sweeps(tmp_path / "analysis.png", res,
                expected=([1e4, 1e5], [0.9 * res["fixed"].delta[1], 0.9 * res["fixed"].delta[2]]))
    for name in ("deformed.png", "analysis.png"):
        img = mpimg.imread(tmp_path / name)
        assert img.shape[0] > 300 and img.shape[1] > 400
        assert img[..., :3].std() > 0.05
