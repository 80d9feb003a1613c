"""The thickness of a part's walls in 2D and 3D (pacto_ng/shape/thickness.py) and the
refinement that keeps it from falling (pacto_ng/shape/refine.py, ``min_wall``).

Independent references: a unit square with a centred square hole 0.4 wide has walls 0.3
thick on all four sides, and squeezing the square to half its height halves the walls across
y (0.15) but not those across x; the plate with a pressurised hole of test_refine.py thins its
walls when refined freely, and keeps them above a floor when given one."""
import numpy as np
import pytest
from netgen.occ import MoveTo, OCCGeometry
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


def test_the_walls_of_a_hollow_cube():
    """A unit cube with a centred cubic hole 0.4 wide (tetrahedra): walls 0.3 thick on all six
    sides; the cube squeezed to half its depth has walls 0.15 thick across z."""
    from netgen.occ import Box

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
    from netgen.occ import Glue

    soft, stiff = MoveTo(0, 0).Rectangle(0.5, 1).Face(), MoveTo(0.5, 0).Rectangle(0.5, 1).Face()
    soft.faces.name, stiff.faces.name = "soft", "stiff"
    square = Glue([soft, stiff])
    square.edges.name = "interface"
    mesh = Mesh(OCCGeometry(square, dim=2).GenerateMesh(maxh=0.1))
    assert "interface" in mesh.GetBoundaries()
    walls = WallThickness(mesh)(np.array([v.point for v in mesh.vertices]))
    assert walls.min() == pytest.approx(1.0, rel=1e-12)


def test_the_refinement_keeps_its_walls_above_the_floor():
    """Five steps at 95 % of the volume: without a floor the plate's thinnest wall thins from
    0.141 to 0.094 (measured); with the floor at 0.12 no accepted shape has a thinner wall,
    and the output still grows; with the floor at the start's thinnest wall, the first step
    the descent takes thins it, so the loop stops there (``no_descent``: the floor is kept by
    refusing steps, not by steering the descent)."""
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
    _, held, result = results[0.12]
    assert min(held) >= 0.12 and result.delta > 2.0 * result.history[0]["delta"]
    _, _, stuck = results["start"]
    assert stuck.status == "no_descent" and len(stuck.history) == 1
