"""Thresholding element densities into polygons (pacto_ng.post.threshold).

Exact figures used below (structured meshes, element size h, densities 0/1 aligned with the
elements): a vertex on a straight solid/void interface gets the nodal density 1/2 (counted as
solid, the documented tie rule), a convex corner of a solid box 1/4 and a concave one 3/4.
The 0.5 cut therefore runs along the interfaces and cuts a convex corner element by the
diagonal between its two interface vertices (the solid loses h²/2 there) and a concave corner
likewise (the solid gains h²/2).
"""
import numpy as np
import pytest

from conftest import CAVITY, FRAME, box_density, chamber_density
from pacto_ng.post.grid import nodal_density
from pacto_ng.post.threshold import threshold

h = 0.001  # element size of the 100 x 50 structured chamber mesh


@pytest.mark.parametrize("bad", [0.0, 1.0, -0.2, 1.5, float("nan")])
def test_threshold_outside_unit_interval_raises(chamber_quads, bad):
    with pytest.raises(ValueError, match="threshold"):
        threshold(chamber_quads, chamber_density(chamber_quads), bad)


def test_nodal_density_two_quads():
    from pacto_ng.mesh import Layout, structured_mesh

    mesh = structured_mesh(Layout(2.0, 1.0), 2, 1)
    nod = nodal_density(mesh, np.array([0.0, 1.0]))
    x = np.asarray(mesh.ngmesh.Coordinates())[:, 0]
    np.testing.assert_allclose(nod, np.select([x < 0.5, x < 1.5], [0.0, 0.5], 1.0), atol=1e-15)


def test_nodal_density_is_area_weighted():
    """Two triangles of areas 1/2 and 1 sharing an edge, densities 1 and 0: the shared
    vertices get (1/2 * 1 + 1 * 0) / (3/2) = 1/3."""
    import ngsolve
    from netgen.meshing import Element2D, FaceDescriptor, MeshPoint, Pnt
    from netgen.meshing import Mesh as NGMesh

    m = NGMesh(dim=2)
    pids = [m.Add(MeshPoint(Pnt(x, y, 0))) for x, y in [(0, 0), (1, 0), (0, 1), (3, 0)]]
    m.Add(FaceDescriptor(surfnr=1, domin=1, bc=1))
    m.Add(Element2D(1, [pids[0], pids[1], pids[2]]))
    m.Add(Element2D(1, [pids[1], pids[3], pids[2]]))
    nod = nodal_density(ngsolve.Mesh(m), np.array([1.0, 0.0]))
    np.testing.assert_allclose(nod, [1.0, 1.0 / 3.0, 1.0 / 3.0, 0.0], rtol=1e-14)


def test_chamber_area_is_exact_on_quads(chamber_quads):
    """Frame minus cavity, with two convex corners cut (-h²/2 each; the left ones lie on the
    domain edge, where the vertex value is 1/2) and four concave cavity corners filled
    (+h²/2 each): area = 0.09*0.035 - 0.04*0.015 + h²."""
    th = threshold(chamber_quads, chamber_density(chamber_quads))
    expected = (FRAME[2] - FRAME[0]) * (FRAME[3] - FRAME[1]) \
        - (CAVITY[2] - CAVITY[0]) * (CAVITY[3] - CAVITY[1]) + h * h
    assert th.area == pytest.approx(expected, rel=1e-8)
    assert th.polygon_area == pytest.approx(th.area, rel=1e-12)


@pytest.mark.parametrize("which", ["chamber_quads", "chamber_trigs"])
def test_chamber_topology_and_orientation(request, which):
    mesh = request.getfixturevalue(which)
    th = threshold(mesh, chamber_density(mesh))
    assert len(th.components) == 1
    comp = th.components[0]
    assert len(comp.holes) == 1 and comp.outer.depth == 0 and comp.holes[0].depth == 1
    for loop in comp.loops:  # counter-clockwise: positive shoelace area
        p = loop.points
        signed = 0.5 * np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1])
        assert signed > 0
    # the hole is the cavity: its points lie around the cavity rectangle (within 1.5 h)
    x0, y0, x1, y1 = CAVITY
    q = comp.holes[0].points
    dist = np.maximum.reduce([x0 - q[:, 0], q[:, 0] - x1, y0 - q[:, 1], q[:, 1] - y1])
    assert np.all(np.abs(dist) < 1.5 * 0.0012)
    assert th.polygon_area == pytest.approx(th.area, rel=1e-12)


def test_clamp_label_runs_along_the_clamp(chamber_quads):
    """The solid touches the clamp (x = 0) over y in [0.005, 0.04]: the edges labelled
    'fixed' add up to exactly that length and lie on x = 0; the hole has no labels."""
    th = threshold(chamber_quads, chamber_density(chamber_quads))
    outer = th.components[0].outer
    p, q = outer.points, np.roll(outer.points, -1, axis=0)
    fixed = np.array([lab == "fixed" for lab in outer.labels])
    assert np.sum(np.linalg.norm(q - p, axis=1)[fixed]) == pytest.approx(0.035, rel=1e-8)
    assert np.all(np.abs(p[fixed, 0]) < 1e-12) and np.all(np.abs(q[fixed, 0]) < 1e-12)
    assert set(outer.labels) == {"fixed", None}
    assert th.components[0].holes[0].names == set()


def test_specks_are_removed(chamber_quads):
    """A 2x2-element island and a 2x2-element pinhole each enclose 2 h² (< the default
    4 h²): the island is dropped, the pinhole filled; with min_area=0 both stay.  (The tie
    rule leaves slivers of width ~1e-9 h, hence the relative tolerance 1e-7.)"""
    island = (0.094, 0.045, 0.096, 0.047)
    pin = (0.010, 0.020, 0.012, 0.022)
    th = threshold(chamber_quads, box_density(chamber_quads, [FRAME, island], [CAVITY]))
    assert len(th.components) == 1
    assert th.removed_area == pytest.approx(2 * h * h, rel=1e-7)
    th = threshold(chamber_quads, box_density(chamber_quads, [FRAME], [CAVITY, pin]))
    assert len(th.components[0].holes) == 1
    assert th.removed_area == pytest.approx(-2 * h * h, rel=1e-7)
    assert th.polygon_area == pytest.approx(th.area + 2 * h * h, rel=1e-9)
    keep = threshold(chamber_quads, box_density(chamber_quads, [FRAME, island], [CAVITY, pin]),
                     min_area=0.0)
    assert len(keep.components) == 2 and len(keep.components[0].holes) == 2
    assert keep.removed_area == 0.0
    assert keep.components[1].area == pytest.approx(2 * h * h, rel=1e-7)
    assert min(hl.area for hl in keep.components[0].holes) == pytest.approx(2 * h * h, rel=1e-7)


def test_nothing_solid_raises(chamber_quads):
    with pytest.raises(ValueError, match="threshold"):
        threshold(chamber_quads, np.full(chamber_quads.ne, 0.2))
