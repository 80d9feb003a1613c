"""Body-fitted remeshing of a thresholded design and the names it carries (post.remesh)."""
import numpy as np
import pytest

from conftest import (CAVITY, FRAME, H, OUTPUT, W, box_density, chamber_density,
                      chamber_pressure)
from pacto_ng.post.remesh import remesh
from pacto_ng.post.threshold import threshold


def _length(mesh, name):
    import ngsolve as ng

    if name not in mesh.GetBoundaries():
        return 0.0
    return ng.Integrate(1.0, mesh, ng.BND, definedon=mesh.Boundaries(name))


def _segments(mesh, name):
    import ngsolve as ng

    return np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(ng.BND)
                     if el.mat == name])


@pytest.mark.parametrize("which", ["chamber_quads", "chamber_trigs"])
def test_remeshed_area_within_2_percent(request, which):
    mesh = request.getfixturevalue(which)
    th = threshold(mesh, chamber_density(mesh))
    rm = remesh(th, 0.002, pressure=chamber_pressure)
    assert abs(rm.area / th.area - 1.0) < 0.02
    assert rm.thresholded_area == th.area
    assert set(rm.mesh.GetMaterials()) == {"solid"}


def test_clamp_is_straight_and_port_is_nearest_vertex(chamber_remeshed):
    """The clamp run is one straight OCC segment: its meshed length is the solid's extent along
    x = 0 (0.035 m) and every clamp segment lies on x = 0.  The port is a vertex of the new
    mesh at most one element size from the original port."""
    th, rm = chamber_remeshed
    assert _length(rm.mesh, "fixed") == pytest.approx(0.035, rel=1e-9)
    assert np.all(np.abs(_segments(rm.mesh, "fixed")[:, :, 0]) < 1e-12)
    src, new = rm.ports["output"]
    assert src == pytest.approx(OUTPUT)
    assert np.hypot(new[0] - src[0], new[1] - src[1]) <= 0.003
    verts = np.array([rm.mesh[v].point for v in rm.mesh.vertices])
    assert np.min(np.hypot(*(verts - np.array(new)).T)) == 0.0
    assert "output" in rm.mesh.GetBBoundaries()


def test_pressure_boundary_is_the_cavity_wall(chamber_remeshed):
    """The wetted boundary is the cavity wall and only it.  The thresholded cavity is the
    rectangle with its four corners cut by diagonals of one element (h = 1 mm), so its
    perimeter is 0.11 - 4 (2 - sqrt 2) h.  The splines follow that polygon within their
    tolerance (0.1 h) and the mesh chords them (measured: 5e-5 relative at maxh = 3 h)."""
    th, rm = chamber_remeshed
    h = 0.001
    assert rm.wetted_length == pytest.approx(_length(rm.mesh, "pressure"), rel=1e-12)
    assert rm.wetted_length == pytest.approx(0.11 - 4 * (2 - np.sqrt(2)) * h, rel=1e-3)
    mid = _segments(rm.mesh, "pressure").mean(axis=1)
    x0, y0, x1, y1 = CAVITY
    assert np.all((mid[:, 0] > x0 - 2 * h) & (mid[:, 0] < x1 + 2 * h)
                  & (mid[:, 1] > y0 - 2 * h) & (mid[:, 1] < y1 + 2 * h))
    # no wetted segment on the outer walls, and every boundary is named
    assert set(rm.mesh.GetBoundaries()) == {"fixed", "free", "pressure"}
    assert rm.p_in == pytest.approx(1e5)


def test_no_solid_at_the_clamp_raises(chamber_quads):
    shifted = (0.01, FRAME[1], FRAME[2], FRAME[3])
    th = threshold(chamber_quads, box_density(chamber_quads, [shifted], [CAVITY]))
    with pytest.raises(ValueError, match="no solid touches the clamp") as err:
        remesh(th, 0.003)
    assert "\n" not in str(err.value)
    th = threshold(chamber_quads, chamber_density(chamber_quads))
    with pytest.raises(ValueError, match="no solid touches the clamp"):
        remesh(th, 0.003, clamp=("clamped",))


def test_floating_piece_is_dropped(chamber_quads):
    island = (0.05, 0.045, 0.08, 0.05)  # on the top edge, away from the frame and the clamp
    th = threshold(chamber_quads, box_density(chamber_quads, [FRAME, island], [CAVITY]))
    assert len(th.components) == 2
    rm = remesh(th, 0.003, pressure=chamber_pressure)
    small = min(c.area for c in th.components)
    assert rm.dropped_area == pytest.approx(small, rel=1e-12)
    assert abs(rm.area / (th.area - small) - 1.0) < 0.02


def test_wetted_by_boundary_name():
    """A block on the left edge named 'inlet' (the fluid beyond it) and clamped on the top:
    without a pressure field the wetted boundary is exactly its part of the inlet edge."""
    from pacto_ng.mesh import Layout, Segment, structured_mesh

    lay = Layout(W, H, segments=(Segment("inlet", (0.0, 0.0), (0.0, H)),
                                 Segment("fixed", (0.0, H), (0.02, H))))
    mesh = structured_mesh(lay, 50, 25)
    th = threshold(mesh, box_density(mesh, [(0.0, 0.02, 0.03, H)]))
    rm = remesh(th, 0.004)
    assert _length(rm.mesh, "pressure") == pytest.approx(0.03, rel=1e-9)
    assert _length(rm.mesh, "inlet") == 0.0
    assert _length(rm.mesh, "fixed") == pytest.approx(0.02, rel=1e-9)
    assert rm.p_in is None


def test_a_netgen_failure_is_one_line(chamber_quads, monkeypatch):
    """Netgen's own exception (e.g. "OCC-Triangulation could not be built for face 1", met on a
    PneuNet part) and a face left without triangles both become one-line ValueErrors."""
    from netgen import occ

    th = threshold(chamber_quads, chamber_density(chamber_quads))

    class Failing:
        def __init__(self, *a, **k):
            pass

        def GenerateMesh(self, **k):
            raise RuntimeError("OCC-Triangulation could not be built for face 1\nmore")

    monkeypatch.setattr(occ, "OCCGeometry", Failing)
    with pytest.raises(ValueError, match="^Netgen could not mesh the part: OCC-Triangulation") as err:
        remesh(th, 0.003)
    assert "\n" not in str(err.value) and "maxh 0.003" in str(err.value)


def test_netgen_s_own_exception_is_one_line():
    """Not mocked: a face OCC cannot triangulate (1 x 1e-12) makes Netgen raise its
    NgException, which becomes the one-line ValueError."""
    from netgen import occ

    from pacto_ng.post.remesh import _generate

    with pytest.raises(ValueError, match="^Netgen could not mesh the part: OCC-Triangulation "
                                         "could not be built") as err:
        _generate(occ.Rectangle(1.0, 1e-12).Face(), 0.1, 0.5)
    assert "\n" not in str(err.value) and "maxh 0.1" in str(err.value)


def test_only_the_mesher_s_errors_fall_back_to_element_wise_materials(monkeypatch):
    """A body-fitted cut that fails as OCC and Netgen fail (Netgen's NgException, OCC's
    Standard_Failure raised as a RuntimeError, split_part's own ValueError) falls back to the
    element-wise materials, its first line recorded; any other exception (a bug) is raised."""
    import importlib

    from netgen import occ
    from netgen.libngpy._meshing import NgException

    remesh_module = importlib.import_module("pacto_ng.post.remesh")
    part = occ.Rectangle(1.0, 0.5).Face()
    assigned = []
    monkeypatch.setattr(remesh_module, "assign_elementwise",
                        lambda ngm, stiff, source: assigned.append(stiff))
    for err in (NgException("error in wire builder"),
                RuntimeError("Standard_ConstructionError: Bnd_Box is void\nmore"),
                ValueError("the part and its material regions do not overlap")):
        def fail(*args, _err=err, **kwargs):
            raise _err

        monkeypatch.setattr(remesh_module, "split_part", fail)
        ngm, materials = remesh_module._generate_part(part, 0.25, 0.5, "stiff", None, None)
        assert len(ngm.Elements2D()) > 0
        first = str(err).splitlines()[0]
        assert materials == f"element-wise (the interface as a boundary failed: {first})"
    assert assigned == ["stiff"] * 3

    def bug(*args, **kwargs):
        raise TypeError("a bug in the cut")

    monkeypatch.setattr(remesh_module, "split_part", bug)
    with pytest.raises(TypeError, match="a bug in the cut"):
        remesh_module._generate_part(part, 0.25, 0.5, "stiff", None, None)


def test_unmeshed_edges_counts_segments_without_a_triangle():
    from netgen.meshing import Element1D, Element2D, FaceDescriptor, Mesh, MeshPoint, Pnt

    from pacto_ng.post.remesh import _unmeshed_edges

    m = Mesh(dim=2)
    p = [m.Add(MeshPoint(Pnt(x, y, 0))) for x, y in ((0, 0), (1, 0), (0, 1), (1, 1))]
    m.Add(FaceDescriptor(surfnr=1, domin=1, bc=1))
    m.Add(Element2D(1, [p[0], p[1], p[2]]))
    for a, b in ((0, 1), (1, 2), (2, 0)):
        m.Add(Element1D([p[a], p[b]], index=1))
    assert _unmeshed_edges(m) == 0
    m.Add(Element1D([p[1], p[3]], index=1))  # an edge of a face with no triangle
    m.Add(Element1D([p[3], p[2]], index=1))
    assert _unmeshed_edges(m) == 2


def test_a_3d_mesher_crash_is_retried_finer_then_with_the_surface_kept(monkeypatch):
    """Netgen's STL mesher crashes on some part surfaces (a thin wall); the part is meshed
    again with the next size and options of MESH_RETRY (the same size with other options
    first), and the size that worked is returned.  When
    every size fails, the surface's own triangles are kept and the volume filled: the mesh
    then encloses exactly the surface's volume (a sphere's, whose flat triangles the STL
    mesher would have replaced) and its boundary is those triangles; when that fails too, the
    unsmoothed surface's triangles.  An STL try stopped at its time limit goes to the fill
    at once."""
    import pyvista as pv
    from ngsolve import Integrate, Mesh

    from pacto_ng.post import remesh3d

    real = remesh3d._mesh_child
    tries = []

    def crash(first):
        def crashing(kind, source, maxh, vol, timeout, options=None):
            tries.append((kind, maxh, options))
            if len(tries) <= first:
                return "its mesher stopped with exit code -6"
            return real(kind, source, maxh, vol, timeout, options)
        return crashing

    cube = pv.Cube(center=(0.5, 0.5, 0.5)).triangulate()
    for first in (1, 3):  # the same size with other options; then a finer size
        tries.clear()
        monkeypatch.setattr(remesh3d, "_mesh_child", crash(first))
        gen, used, how = remesh3d._netgen_mesh(cube, 0.5, 60.0)
        assert tries == [("stl", 0.5 * f, options)
                         for f, options in remesh3d.MESH_RETRY[:first + 1]]
        assert used == tries[-1][1] and gen.ne > 0 and how == "remeshed"
    assert tries[-1][1] < 0.5 and tries[1] == ("stl", 0.5, {"grading": 0.2})

    def stl_fails(kind, *args):
        return "its mesher stopped with exit code -6" if kind == "stl" else real(kind, *args)

    monkeypatch.setattr(remesh3d, "_mesh_child", stl_fails)
    sphere = pv.Sphere(radius=1.0, theta_resolution=24, phi_resolution=12).triangulate()
    gen, used, how = remesh3d._netgen_mesh(sphere, 0.4, 60.0)
    assert how == "kept" and used == 0.4
    assert Integrate(1.0, Mesh(gen)) == pytest.approx(sphere.volume, rel=1e-12)
    assert len(gen.Elements2D()) == sphere.n_cells

    fills = []

    def first_fill_fails(kind, *args):
        if kind == "fill":
            fills.append(kind)
            if len(fills) == 1:
                return "no tetrahedra"
        return stl_fails(kind, *args)

    monkeypatch.setattr(remesh3d, "_mesh_child", first_fill_fails)
    gen, used, how = remesh3d._netgen_mesh(cube, 0.5, 60.0, unsmoothed=sphere)
    assert how == "unsmoothed" and len(gen.Elements2D()) == sphere.n_cells

    monkeypatch.setattr(remesh3d, "_mesh_child", lambda *a: "no tetrahedra")
    with pytest.raises(ValueError, match=r"^Netgen could not mesh the part \(maxh 0\.5: no "
                       r".*the kept surface filled, 0\.5: no tetrahedra"):
        remesh3d._netgen_mesh(cube, 0.5, 60.0)

    # an STL try stopped at its time limit: no finer size (it would take longer), the fill
    tries.clear()

    def stl_hangs(kind, *args):
        tries.append(kind)
        return f"{remesh3d.TOOK_LONGER} 60 s" if kind == "stl" else real(kind, *args)

    monkeypatch.setattr(remesh3d, "_mesh_child", stl_hangs)
    gen, used, how = remesh3d._netgen_mesh(sphere, 0.4, 60.0)
    assert tries == ["stl", "fill"] and how == "kept"


def test_a_piece_pinned_at_a_clamped_point_is_kept():
    """topress is supported at its two bottom corners (named points, no clamped boundary): the
    piece holding them is the part, a piece clear of them floats and is dropped, and a design
    without solid at either corner has no part."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.parallel import element_centroids

    case = get_case("topress")
    problem = build_problem(case, case.resolve(case.defaults.replace(nelx=30, nely=20)))
    c = element_centroids(problem.mesh)
    clamp = problem.setup.supports.clamp
    floor = (c[:, 1] < 4).astype(float)
    island = ((c[:, 1] > 12) & (c[:, 1] < 16) & (np.abs(c[:, 0] - 15) < 4)).astype(float)
    th = threshold(problem.mesh, floor + island)
    assert len(th.components) == 2
    rm = remesh(th, 1.0, clamp=clamp)
    assert rm.dropped_area == pytest.approx(min(p.area for p in th.components), rel=1e-12)
    assert set(rm.ports) >= {"support_left", "support_right"}
    inner = ((c[:, 1] < 4) & (np.abs(c[:, 0] - 15) < 10)).astype(float)
    with pytest.raises(ValueError, match="no solid touches the clamp support_left"):
        remesh(threshold(problem.mesh, inner), 1.0, clamp=clamp)


def test_a_3d_piece_pinned_at_clamped_points_is_kept():
    """topress-3d is held at the nodes of its top face's rim (points all named "rim", no
    clamped face): a plate in the top layer reaches them and is the part, pinned at the rim
    nodes it holds (each once); a block at the bottom floats and is dropped; a design
    without solid near the rim has no part."""
    from ngsolve import BBBND

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.parallel import element_centroids
    from pacto_ng.post.part3d import part3d
    from pacto_ng.post.remesh3d import remesh_part

    case = get_case("topress-3d")
    problem = build_problem(case, case.resolve(case.defaults.replace(nelx=6, nely=6, nelz=4)))
    mesh, clamp = problem.mesh, problem.setup.supports.clamp
    c = element_centroids(mesh)
    plate = c[:, 2] > 3
    block = (c[:, 2] < 1) & (np.abs(c[:, 0] - 3) < 1) & (np.abs(c[:, 1] - 3) < 1)
    solid = part3d(mesh, (plate | block).astype(float), 0.5, clamp=clamp)
    assert (solid.pieces, solid.dropped) == (2, 1)
    assert solid.volume_kept == pytest.approx(36.0, rel=0.02)  # the plate, 6 x 6 x 1
    rm = remesh_part(solid.surface, mesh, 1.0, problem.h, clamp=clamp)
    assert rm.volume == pytest.approx(36.0, rel=0.02)
    assert rm.dropped == 0  # part3d dropped the block already
    pins = np.array([rm.mesh[el.vertices[0]].point for el in rm.mesh.Elements(BBBND)
                     if el.mat == "rim"])
    assert len(pins) == len({tuple(p) for p in pins}) > 4
    on_rim = (np.isclose(pins[:, 0] % 6, 0, atol=0.5) | np.isclose(pins[:, 1] % 6, 0, atol=0.5))
    assert on_rim.all() and np.all(pins[:, 2] > 3.5)
    with pytest.raises(ValueError, match="no solid touches the clamp"):
        part3d(mesh, block.astype(float), 0.5, clamp=clamp)
