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
from netgen.occ import Box, Glue, MoveTo, OCCGeometry
from ngsolve import Mesh

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


def test_a_blunt_corner_is_no_wall_and_a_knife_edge_is():
    """A strip 0.2 thick with its ends cut at 60° (a parallelogram): near its acute corners
    the rays leave across the slanted end at 60° to its normal, which is no wall, so the
    thinnest wall is the strip's 0.2; cut at 30° instead, the corners are knife edges
    (rays leave at 30°, facing the end) and thinner than the strip."""
    def strip(angle):
        run = 0.2 / np.tan(np.radians(angle))
        body = MoveTo(0, 0).LineTo(1, 0).LineTo(1 + run, 0.2).LineTo(run, 0.2).Close().Face()
        mesh = Mesh(OCCGeometry(body, dim=2).GenerateMesh(maxh=0.05))
        return WallThickness(mesh)(np.array([v.point for v in mesh.vertices]))

    assert strip(60).min() == pytest.approx(0.2, rel=1e-12)
    assert strip(30).min() < 0.1


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
    """Five steps at 95 % of the volume: without a floor the plate's thinnest wall thins from
    0.141 to 0.098 (measured); with the floor at 0.12 or at the start's thinnest wall, no
    accepted shape has a thinner wall and the output still grows more than threefold (the
    shortfall constraint steers the descent off the floor: measured 0.0086 to 0.063 and
    0.031)."""
    results = {}
    for floor in (None, 0.12, "start"):
        mesh = plate()
        space = ShapeSpace(mesh, hold=("left",))
        response = plate_response(mesh)
        start = WallThickness(mesh)(np.array([v.point for v in mesh.vertices])).min()
        with compute(THREADS):
            result = refine(response, space, volume_max=0.95 * volume(mesh, response.thickness),
                            steps=5, step=0.02, q_min=Q_MIN,
                            min_wall=start if floor == "start" else floor)
        walls = [row["wall"] for row in result.history]
        assert walls[0] == pytest.approx(start, rel=1e-12)
        results[floor] = (start, walls, result)
    start, free, _ = results[None]
    assert min(free) < 0.7 * start
    for floor in (0.12, "start"):
        _, held, result = results[floor]
        assert min(held) >= (start if floor == "start" else floor)
        assert result.delta > 3.0 * result.history[0]["delta"] and len(held) == 6
