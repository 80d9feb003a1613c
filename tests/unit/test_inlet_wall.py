"""The passive wall kept around a pressure inlet (``inlet_wall``): which elements it holds.

On a square and on a cube meshed by Netgen, the elements within a distance d of one flat face
are those whose centroid has x < d (the face is x = 0).  The boundary is sampled at a quarter
of its elements' size, so the mask must hold every element with x < d - h/4 and no element with
x >= d."""
import numpy as np
import pytest
from netgen.geom2d import unit_square
from netgen.occ import X, Box, OCCGeometry
from ngsolve import Mesh

from pacto_ng.design import DesignField, near_boundary
from pacto_ng.parallel import element_centroids

H = 0.1


def _square():
    return Mesh(unit_square.GenerateMesh(maxh=H))   # left edge: "left"


def _cube():
    box = Box((0, 0, 0), (1, 1, 1))
    box.faces.Min(X).name = "left"
    return Mesh(OCCGeometry(box).GenerateMesh(maxh=2 * H))


@pytest.mark.parametrize("make, h", [(_square, H), (_cube, 2 * H)])
def test_the_wall_holds_the_elements_within_its_thickness(make, h):
    mesh = make()
    d = 0.25
    x = element_centroids(mesh)[:, 0]
    mask = near_boundary(mesh, ("left",), d)
    assert mask[x < d - h / 4].all()
    assert not mask[x >= d].any()
    assert 0 < mask.sum() < mesh.ne


def test_the_wall_becomes_passive_solid_but_never_fills_a_void():
    mesh = _square()
    mask = near_boundary(mesh, ("left",), 0.25)
    field = DesignField(mesh, wall=mask)
    assert (field.solid == mask).all() and field.n == mesh.ne - mask.sum()
    assert (field.full(np.zeros(field.n))[mask] == 1.0).all()
    everything = mesh.GetMaterials()[0]
    assert not DesignField(mesh, void=(everything,), wall=mask).solid.any()


def test_a_wall_around_a_boundary_that_does_not_exist_is_refused():
    with pytest.raises(ValueError, match="no boundary named inlet"):
        near_boundary(_square(), ("inlet",), 0.1)
