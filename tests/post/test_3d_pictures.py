"""The 3D pictures as a user reads them (pacto_ng/post/plots3d.py): every view has its axes
in metres, a cut's title gives its coordinate rounded to the part's size (no round-off shown
as a coordinate), and the pictures are drawn (off-screen pyvista)."""
import numpy as np
import pytest

from pacto_ng.post.grid import mesh_to_pyvista
from pacto_ng.post.plots3d import (WINDOW, coordinate_text, cut_title, deformed_picture,
                                   design_picture, plotter, pressure_picture, render,
                                   rounded_bounds, show_axes)


@pytest.mark.parametrize("value, size, text", [
    (5.384e-08, 0.02, "0"),      # the round-off of a mid-depth of a box around z = 0
    (-3e-12, 1.0, "0"),
    (0.01, 0.2, "0.01"),
    (0.0123456, 0.02, "0.01235"),
    (-0.005, 0.01, "-0.005"),
    (12.5, 100.0, "12.5"),
])
def test_a_coordinate_is_rounded_to_the_parts_size(value, size, text):
    assert coordinate_text(value, size) == text


def test_the_bounds_on_the_axes_have_no_round_off():
    assert rounded_bounds([-6.06e-20, 0.2, -6.67e-20, 0.1, -0.0004, 0.02]) == [
        0.0, 0.2, 0.0, 0.1, 0.0, 0.02]


@pytest.fixture(scope="module")
def box_mesh():
    """A 3D box x in [0, 0.04], y in [0, 0.02], z in [-0.005, 0.005] (mid-depth 0, reached
    through round-off) of coarse tetrahedra."""
    import ngsolve
    from netgen.occ import Box, OCCGeometry, Pnt

    shape = Box(Pnt(0, 0, -0.005), Pnt(0.04, 0.02, 0.005))
    return ngsolve.Mesh(OCCGeometry(shape).GenerateMesh(maxh=0.005))


def _centroids(mesh):
    pts = np.asarray(mesh.ngmesh.Coordinates())
    return np.array([pts[[v.nr for v in el.vertices]].mean(axis=0) for el in mesh.Elements()])


def _picture(path):
    import matplotlib.image as mpimg

    img = mpimg.imread(path)
    assert img.shape[:2] == (WINDOW[1], WINDOW[0])
    assert len(np.unique(img[..., :3].reshape(-1, 3), axis=0)) > 50  # not blank
    return img


def test_a_cut_through_a_box_around_zero_is_titled_z_0(box_mesh):
    grid = mesh_to_pyvista(box_mesh)
    grid.points[:, 2] += 5.384e-08  # the box's mid-depth: round-off
    assert cut_title(grid) == "cut at z = 0 m"


def test_the_axes_are_labelled_in_metres():
    import pyvista as pv

    bounds = (0.0, 0.2, 0.0, 0.1, 0.0, 0.02)
    inks = []
    for with_axes in (False, True):
        p = plotter(window=(600, 400))
        p.add_mesh(pv.Box(bounds=bounds).outline(), color="grey")
        if with_axes:
            show_axes(p, bounds)
            axes = p.renderer.cube_axes_actor
            assert (axes.x_title, axes.y_title, axes.z_title) == ("x (m)", "y (m)", "z (m)")
        p.view_isometric()
        img = render(p)
        inks.append(np.count_nonzero(np.any(img != img[0, 0], axis=-1)))
    assert inks[1] > inks[0] + 500  # the labels and ticks are drawn


def test_the_design_pressure_and_deformed_pictures_are_drawn(box_mesh, tmp_path):
    import ngsolve

    c = _centroids(box_mesh)
    rho = np.where((c[:, 0] < 0.02) | (c[:, 1] < 0.005), 1.0, 0.0)
    design_picture(tmp_path / "design.png", mesh_to_pyvista(box_mesh), rho, title="a box")
    x = np.asarray(box_mesh.ngmesh.Coordinates())[:, 0]
    pressure_picture(tmp_path / "pressure.png", mesh_to_pyvista(box_mesh), 1.0 - x / 0.04, rho,
                     title="a box")
    u = ngsolve.CoefficientFunction((0, 0.05 * ngsolve.x, 0))
    deformed_picture(tmp_path / "deformed.png", box_mesh, u, title="a box")
    for name in ("design.png", "pressure.png", "deformed.png"):
        _picture(tmp_path / name)
