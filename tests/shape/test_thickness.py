"""The thickness of a part's walls in 2D and 3D (pacto_ng/shape/thickness.py) and the
refinement that keeps it from falling (pacto_ng/shape/refine.py, ``min_wall``).

Independent references: a unit square with a centred square hole 0.4 wide has walls 0.3
thick on all four sides, and squeezing the square to half its height halves the walls across
y (0.15) but not those across x; the walls' shortfall below a floor has the derivative of its
central finite differences; the plate with a pressurised hole of test_refine.py thins its
walls when refined freely, and keeps them above a floor when given one while its output
grows."""
import numpy as np
import pytest
from netgen.occ import Box, Glue, MoveTo, OCCGeometry, Rectangle
from netgen.meshing import Element2D, Element3D, FaceDescriptor, MeshPoint, Pnt
from netgen.meshing import Mesh as NgMesh
from ngsolve import BND, Mesh

from pacto_ng.shape import ShapeSpace, volume
from pacto_ng.shape.refine import refine
from pacto_ng.shape.thickness import WallThickness
from pacto_ng.threads import compute

from test_refine import Q_MIN, THREADS, plate_response
from test_shape_gradient import plate


def test_the_walls_of_a_square_frame():
    body = MoveTo(0, 0).Rectangle(1, 1).Face() - MoveTo(0.3, 0.3).Rectangle(0.4, 0.4).Face()
    mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.05))
    walls = WallThickness(mesh)
    points = np.array([v.point for v in mesh.vertices])
    t = walls(points)
    assert t.min() == pytest.approx(0.3, rel=1e-12) and np.all(np.isfinite(t))
    # the rays of the outer sides that miss the hole cross the whole square
    assert t.max() == pytest.approx(1.0, rel=1e-12)
    squeezed = points * np.array([1.0, 0.5])
    assert walls(squeezed).min() == pytest.approx(0.15, rel=1e-12)


def test_a_ray_across_the_facet_beside_its_own_measures_a_wall_only_facing_it():
    """One tetrahedron with its apex over a corner of its base: (0,0,0), (1,0,0), (0,1,0),
    (0,0,h).  Every ray leaves across a face beside its own (all four share vertices): the
    base's ray (up, from its centre) leaves through the slanted face, whose outward normal
    (1,1,1/h)/|.| is at more than 45° to it for h = 1 (cos 0.577) and at less for h = 0.2
    (cos 0.96): no wall, then a wall of the closed form's height 1 - 2/3 = 1/3 of h."""
    for h, wall in ((1.0, False), (0.2, True)):
        mesh = NgMesh(dim=3)
        v = [mesh.Add(MeshPoint(Pnt(*p))) for p in ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, h))]
        mesh.Add(FaceDescriptor(surfnr=1, domin=1, bc=1))
        mesh.Add(Element3D(1, [v[0], v[1], v[2], v[3]]))
        for face in ((v[0], v[2], v[1]), (v[0], v[1], v[3]), (v[1], v[2], v[3]),
                     (v[0], v[3], v[2])):
            mesh.Add(Element2D(1, list(face)))
        m = Mesh(mesh)
        t = WallThickness(m)(np.array([p.point for p in m.vertices]))
        base = int(np.argmin([abs(np.mean([m[u].point[2] for u in e.vertices]))
                              for e in m.Elements(BND)]))
        if wall:
            assert t[base] == pytest.approx(h / 3.0, rel=1e-12)
        else:
            assert np.isinf(t[base])


def test_a_ragged_neck_is_as_thin_as_it_is():
    """A strip 0.2 thick with a V notch 0.1 deep in its top (flanks at 63° to the strip, each
    leaving the rays from below at 63° to its normal): the notch's two flanks together face
    the rays (the surface's normal smoothed over the facets around), so the neck under it
    measures between its 0.1 and the strip's 0.2."""
    body = (MoveTo(0, 0).LineTo(1, 0).LineTo(1, 0.2).LineTo(0.55, 0.2).LineTo(0.5, 0.1)
            .LineTo(0.45, 0.2).LineTo(0, 0.2).Close().Face())
    mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.01))
    t = WallThickness(mesh)(np.array([v.point for v in mesh.vertices]))
    assert 0.1 < t.min() < 0.12


def test_necks_are_measured_across_the_solid_not_across_a_void():
    """``neck``: a unit square with a slot 0.1 wide from y = 0.3 up through its top: the
    slot's walls face each other across the void (no neck), the solid under the slot is 0.3
    thick; the V-notched strip above: its neck under the notch is the notch's 0.1 (a mesh
    vertex at the tip and one below it); none below a reach shorter than the necks."""
    slot = Rectangle(1, 1).Face() - MoveTo(0.45, 0.3).Rectangle(0.1, 0.8).Face()
    notch = (MoveTo(0, 0).LineTo(1, 0).LineTo(1, 0.2).LineTo(0.55, 0.2).LineTo(0.5, 0.1)
             .LineTo(0.45, 0.2).LineTo(0, 0.2).Close().Face())
    for body, maxh, neck in ((slot, 0.05, 0.3), (notch, 0.01, 0.1)):
        mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=maxh))
        walls, points = WallThickness(mesh), np.array([v.point for v in mesh.vertices])
        assert walls.neck(points, 0.5) == pytest.approx(neck, rel=1e-9)
        assert walls.neck(points, 0.9 * neck) == np.inf


def test_the_walls_of_a_hollow_cube():
    """A unit cube with a centred cubic hole 0.4 wide (tetrahedra): walls 0.3 thick on all six
    sides; the cube squeezed to half its depth has walls 0.15 thick across z."""
    body = Box((0, 0, 0), (1, 1, 1)) - Box((0.3, 0.3, 0.3), (0.7, 0.7, 0.7))
    mesh = Mesh(OCCGeometry(body).GenerateMesh(maxh=0.15))
    walls = WallThickness(mesh)
    points = np.array([v.point for v in mesh.vertices])
    t = walls(points)
    assert t.min() == pytest.approx(0.3, rel=1e-12) and np.all(np.isfinite(t))
    assert t.max() == pytest.approx(1.0, rel=1e-12)
    assert walls(points * np.array([1.0, 1.0, 0.5])).min() == pytest.approx(0.15, rel=1e-12)


def test_an_interface_between_two_materials_is_no_wall():
    """A unit square of two materials (soft and stiff halves glued along x = 0.5, the
    interface a named boundary inside): its walls are 1 thick, the interface does not halve
    them."""
    soft, stiff = MoveTo(0, 0).Rectangle(0.5, 1).Face(), MoveTo(0.5, 0).Rectangle(0.5, 1).Face()
    soft.faces.name, stiff.faces.name = "soft", "stiff"
    square = Glue([soft, stiff])
    square.edges.name = "interface"
    mesh = Mesh(OCCGeometry(square, dim=2).GenerateMesh(maxh=0.1))
    assert "interface" in mesh.GetBoundaries()
    walls = WallThickness(mesh)(np.array([v.point for v in mesh.vertices]))
    assert walls.min() == pytest.approx(1.0, rel=1e-12)


def _frame(dim: int):
    """The unit square (cube) with a centred hole 0.4 wide, its vertices moved at random by
    1 % of its size (no wall parallel to another: the rays hit facets at angles)."""
    if dim == 2:
        body = MoveTo(0, 0).Rectangle(1, 1).Face() - MoveTo(0.3, 0.3).Rectangle(0.4, 0.4).Face()
        mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.1))
    else:
        body = Box((0, 0, 0), (1, 1, 1)) - Box((0.3, 0.3, 0.3), (0.7, 0.7, 0.7))
        mesh = Mesh(OCCGeometry(body).GenerateMesh(maxh=0.3))
    rng = np.random.default_rng(0)
    points = np.array([v.point for v in mesh.vertices])[:, :dim]
    return mesh, points + 0.01 * rng.standard_normal(points.shape), rng


@pytest.mark.parametrize("dim", [2, 3])
def test_the_walls_shortfall_has_the_derivative_of_its_finite_differences(dim):
    """``shortfall(points, T)`` below a floor T = 0.35 above the walls' 0.3: positive, and
    its derivative along a random motion of every vertex equals the central difference with
    a step of 1e-6 to 1e-6 relative (measured 5e-9 in 2D, 3e-11 in 3D)."""
    mesh, points, rng = _frame(dim)
    walls = WallThickness(mesh)
    value, grad = walls.shortfall(points, 0.35)
    assert value > 0 and grad.shape == points.shape
    assert walls.shortfall(points, 0.25)[0] == 0.0  # every wall above 0.25
    motion, e = rng.standard_normal(points.shape), 1e-6
    fd = (walls.shortfall(points + e * motion, 0.35)[0]
          - walls.shortfall(points - e * motion, 0.35)[0]) / (2 * e)
    assert np.sum(grad * motion) == pytest.approx(fd, rel=1e-6)


def test_the_refinement_keeps_its_walls_above_the_floor():
    """Five steps at 95 % of the volume: without a floor the plate's thinnest wall (a neck,
    0.130 across a chord, 0.141 along the normals) thins to 0.087 (measured); with the floor
    at 0.12 no accepted shape has a thinner wall and the output still grows (measured 0.0086
    to 0.0107, +24 %, against 0.087 freely); with the floor at the start's thinnest wall the
    loop stops at once (``no_descent``): the steering constraint measures along the normals,
    which do not see the neck, so the floor there refuses the steps rather than steering."""
    results = {}
    for floor in (None, 0.12, "start"):
        mesh = plate()
        space = ShapeSpace(mesh, hold=("left",))
        response = plate_response(mesh)
        walls, points = WallThickness(mesh), np.array([v.point for v in mesh.vertices])
        start = min(walls(points).min(), walls.neck(points, 1.0))  # as the history has it
        with compute(THREADS):
            result = refine(response, space, volume_max=0.95 * volume(mesh, response.thickness),
                            steps=5, step=0.02, q_min=Q_MIN,
                            min_wall=start if floor == "start" else floor)
        walls = [row["wall"] for row in result.history]
        assert walls[0] == pytest.approx(start, rel=1e-12)
        results[floor] = (start, walls, result)
    start, free, _ = results[None]
    assert min(free) < 0.7 * start
    _, held, result = results[0.12]
    assert min(held) >= 0.12 and len(held) == 6
    assert result.delta > 1.2 * result.history[0]["delta"]
    _, _, stuck = results["start"]
    assert stuck.status == "no_descent" and len(stuck.history) == 1
