"""The moved part meshed anew (pacto_ng/shape/remesh.py): the same polygon (2D) or surface
(3D), names, materials and named points, on fresh elements.

The checks are exact properties of the construction: the new mesh's geometry is the moved
mesh's boundary polygon, so its area, the length of each named boundary and each material's
area equal the moved mesh's (integrated by NGSolve on the moved mesh, an independent route)
to round-off, and a named point sits at its moved position.
"""
import numpy as np
import ngsolve
import pytest
from netgen.occ import X, Y, Z, Box, Circle, Glue, MoveTo, OCCGeometry, Rectangle
from ngsolve import BBBND, BBND, BND, CF, Integrate, ds, dx, x, y, z

from pacto_ng.shape import ShapeSpace, remesh_moved
from pacto_ng.shape.remesh import crossing_walls


def _plate():
    """A 2 × 1 plate with a hole of radius 0.25: ``fixed`` on the left, ``pressure`` on the
    hole, the corner point ``tip`` named."""
    face = Rectangle(2, 1).Face()
    face.edges.Min(X).name = "fixed"
    face.edges.Max(X).name = "load"
    hole = Circle((1, 0.5), 0.25).Face()
    hole.edges.name = "pressure"
    part = face - hole
    part.vertices.Max(X + Y).name = "tip"
    return ngsolve.Mesh(OCCGeometry(part, dim=2).GenerateMesh(maxh=0.1))


def _moved(mesh, field):
    """The ShapeSpace of ``mesh`` (``fixed`` held) moved by the CoefficientFunction ``field``."""
    space = ShapeSpace(mesh, hold=("fixed",))
    gf = ngsolve.GridFunction(space.space)
    gf.Set(field)
    space.set(gf.vec.FV().NumPy())
    return space


def test_the_new_mesh_keeps_the_moved_polygon_its_names_and_points():
    mesh = _plate()
    space = _moved(mesh, CF((0.1 * x * y, 0.05 * x * x)))
    points = space.moved_points()
    new = remesh_moved(mesh, points, 0.05)
    assert new.ne > mesh.ne  # finer: fresh triangles, not the old ones
    assert Integrate(CF(1.0) * dx, new) == pytest.approx(Integrate(CF(1.0) * dx, mesh),
                                                         rel=1e-12)
    for name in ("fixed", "load", "pressure", "default"):
        assert Integrate(CF(1.0) * ds(name), new) == pytest.approx(
            Integrate(CF(1.0) * ds(name), mesh), rel=1e-12), name
    assert set(new.GetMaterials()) == set(mesh.GetMaterials())
    tip = [el for el in new.Elements(BBND) if el.mat == "tip"]
    assert len(tip) == 1
    old = [el.vertices[0].nr for el in mesh.Elements(BBND) if el.mat == "tip"][0]
    np.testing.assert_allclose(new.vertices[tip[0].vertices[0].nr].point, points[old],
                               atol=1e-14)


def test_two_materials_keep_their_areas_and_interface():
    """Two faces (``soft`` and ``stiff``) glued along an ``interface``: each material's area
    and the interface's length are the moved mesh's."""
    soft = Rectangle(1, 1).Face()
    soft.faces.name = "soft"
    stiff = Rectangle(1, 1).Face().Move((1, 0, 0))
    stiff.faces.name = "stiff"
    stiff.edges.Min(X).name = "interface"
    soft.edges.Min(X).name = "fixed"
    mesh = ngsolve.Mesh(OCCGeometry(Glue([soft, stiff]), dim=2).GenerateMesh(maxh=0.2))
    space = _moved(mesh, CF((0.05 * x * y, 0.1 * x * x * (1 - y))))
    new = remesh_moved(mesh, space.moved_points(), 0.1)
    for name in ("soft", "stiff"):
        assert Integrate(CF(1.0) * dx(name), new) == pytest.approx(
            Integrate(CF(1.0) * dx(name), mesh), rel=1e-12), name
    assert "interface" in new.GetBoundaries()
    assert Integrate(CF(1.0) * ds("interface"), new) == pytest.approx(
        Integrate(CF(1.0) * ds("interface"), mesh), rel=1e-12)


def test_refusals():
    mesh = _plate()
    with pytest.raises(ValueError, match="points for a mesh"):
        remesh_moved(mesh, np.zeros((3, 2)), 0.1)


def test_a_3d_part_gets_a_new_interior_for_its_moved_surface():
    """A box with a box cavity (``pressure``), moved by a smooth field: the new mesh has the
    moved surface's names and areas and the moved volume (NGSolve's integrals on the moved
    mesh, an independent route) to round-off, new tetrahedra, and the named point."""
    outer = Box((0, 0, 0), (1, 0.5, 0.5))
    outer.faces.Min(X).name = "fixed"
    cavity = Box((0.3, 0.15, 0.15), (0.6, 0.35, 0.35))
    cavity.faces.name = "pressure"
    part = outer - cavity
    part.vertices.Max(X + Y + Z).name = "tip"
    mesh = ngsolve.Mesh(OCCGeometry(part).GenerateMesh(maxh=0.2))
    space = _moved(mesh, CF((0.1 * x * y, 0.05 * x * x, 0.05 * x * z)))
    points = space.moved_points()
    new = remesh_moved(mesh, points, 0.1)
    assert new.dim == 3 and new.ne != mesh.ne
    assert Integrate(CF(1.0) * dx, new) == pytest.approx(Integrate(CF(1.0) * dx, mesh),
                                                         rel=1e-12)
    for name in ("fixed", "pressure", "default"):
        assert Integrate(CF(1.0) * ds(name), new) == pytest.approx(
            Integrate(CF(1.0) * ds(name), mesh), rel=1e-12), name
    tip = [el for el in new.Elements(BBBND) if el.mat == "tip"]
    old = [el.vertices[0].nr for el in mesh.Elements(BBBND) if el.mat == "tip"][0]
    assert len(tip) == 1
    np.testing.assert_allclose(new.vertices[tip[0].vertices[0].nr].point, points[old],
                               atol=1e-14)


def test_crossing_walls_counts_walls_that_pass_through_each_other():
    """A square with a slot 0.1 wide: no crossing as made; the slot's left wall above
    y = 0.5 moved 0.15 to the right (past the right wall, 0.1 away) crosses it: the upper
    left wall and the segment joining it to the rest cross the right wall (2 pairs, counted
    by hand); moved 0.05 (half the slot) it crosses nothing."""
    face = Rectangle(1, 1).Face() - MoveTo(0.45, 0.3).Rectangle(0.1, 0.8).Face()
    mesh = ngsolve.Mesh(OCCGeometry(face, dim=2).GenerateMesh(maxh=0.05))
    points = np.array([v.point for v in mesh.vertices])
    assert crossing_walls(mesh, points) == 0
    left = (np.abs(points[:, 0] - 0.45) < 1e-9) & (points[:, 1] > 0.5)
    for shift, expected in ((0.05, 0), (0.15, 2)):
        moved = points.copy()
        moved[left, 0] += shift
        assert crossing_walls(mesh, moved) == expected


def test_crossing_walls_in_3d():
    """A unit cube with a centred cubic hole 0.4 wide (walls 0.3 thick): no crossing as made;
    the hole's face at x = 0.7 moved to x = 0.9 (inside the wall) crosses nothing, moved to
    x = 1.2 (through the outer face at x = 1) the hole's side walls cross the outer face."""
    body = Box((0, 0, 0), (1, 1, 1)) - Box((0.3, 0.3, 0.3), (0.7, 0.7, 0.7))
    mesh = ngsolve.Mesh(OCCGeometry(body).GenerateMesh(maxh=0.15))
    points = np.array([v.point for v in mesh.vertices])
    assert crossing_walls(mesh, points) == 0
    face = (np.isclose(points[:, 0], 0.7)
            & np.all((points[:, 1:] > 0.29) & (points[:, 1:] < 0.71), axis=1))
    moved = points.copy()
    moved[face, 0] = 0.9
    assert crossing_walls(mesh, moved) == 0
    moved[face, 0] = 1.2
    assert crossing_walls(mesh, moved) > 0


def test_a_field_moves_with_the_part_onto_its_new_mesh():
    """A linear field u(x0) = (x0 + y0, 2 x0 - y0) of the reference points, on the plate
    moved by a linear deformation x = A x0: set on the remeshed moved plate through
    ``moved_field`` it is u(A⁻¹ x) at every new point (exact: P1 reproduces a linear field);
    set from the field directly, NGSolve would locate x on the reference mesh and give
    u(x) instead (checked: it differs)."""
    from pacto_ng.shape import moved_field

    mesh = _plate()
    A = np.array([[1.0, 0.1], [0.05, 1.0]])
    space = _moved(mesh, CF((0.1 * y, 0.05 * x)))
    points = space.moved_points()
    mesh.UnsetDeformation()
    u = ngsolve.GridFunction(ngsolve.VectorH1(mesh, order=2))
    u.Set(CF((x + y, 2 * x - y)))
    mesh.SetDeformation(space.deformation)
    new = remesh_moved(mesh, points, 0.07)
    moved, naive = (ngsolve.GridFunction(ngsolve.VectorH1(new, order=2)) for _ in range(2))
    moved.Set(moved_field(mesh, points, u))
    naive.Set(u)
    X = np.array([[1.3, 0.4], [0.5, 0.9], [0.2, 0.1]])
    for p in X:
        x0 = np.linalg.solve(A, p)
        np.testing.assert_allclose(moved(new(*p)), (x0[0] + x0[1], 2 * x0[0] - x0[1]),
                                   atol=1e-12)
    assert abs(naive(new(*X[0]))[0] - (X[0][0] + X[0][1])) < 1e-9  # u(x), not u(A⁻¹x)


def test_short_segments_on_a_straight_wall_are_joined():
    """The plate's top wall (straight, 2 long) with its vertices near x = 1 pulled together
    (segments of ~0.1 squeezed to ~0.01): remeshed at maxh 0.1, no top segment is shorter
    than 0.02 (the squeezed ones were joined; kept, they would be 0.01), the top wall keeps
    its length 2 (straight: joining moves nothing), the area is kept, and the curved hole,
    whose segments are not short, keeps every vertex."""
    mesh = _plate()
    points = np.array([v.point for v in mesh.vertices], dtype=float)
    top = np.abs(points[:, 1] - 1.0) < 1e-9
    squeeze = top & (np.abs(points[:, 0] - 1.0) < 0.35)
    moved = points.copy()
    moved[squeeze, 0] = 1.0 + 0.1 * (points[squeeze, 0] - 1.0)
    new = remesh_moved(mesh, moved, 0.1)
    coords = np.array([v.point for v in new.vertices])
    lengths = [float(np.linalg.norm(coords[a] - coords[b])) for a, b in
               ([v.nr for v in el.vertices] for el in new.Elements(BND))
               if abs(coords[a][1] - 1.0) < 1e-9 and abs(coords[b][1] - 1.0) < 1e-9]
    assert min(lengths) > 0.02 and sum(lengths) == pytest.approx(2.0, rel=1e-12)
    assert Integrate(CF(1.0) * dx, new) == pytest.approx(Integrate(CF(1.0) * dx, mesh),
                                                         rel=1e-12)
    hole = lambda m: sum(1 for el in m.Elements(BND) if el.mat == "pressure")  # noqa: E731
    assert hole(new) >= hole(mesh)
