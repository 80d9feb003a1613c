"""3D geometry (pacto_ng/geometry.py, pacto_ng/box.py): a named netgen.occ solid, a STEP file
and a .vol mesh file are meshed in 3D with their names; a Box meshes as tetrahedra and as
structured hexahedra with the same names and volume."""
import numpy as np
import pytest

import pacto_ng as pn
from pacto_ng.box import Block, Box, Patch, structured_box
from pacto_ng.meshing import mesh_geometry
from pacto_ng.params import InputError
from pacto_ng.setup import Pressure, Setup
from pacto_ng.setup_names import check_setup_names
from pacto_ng.physics.loads import Port
from pacto_ng.physics.mechanics import Supports


def chambered_block():
    """A 0.1 x 0.02 x 0.03 m block with a cylindrical chamber along x: solids ``design`` and
    ``chamber``, faces ``fixed`` (x = 0), ``inlet`` (the chamber's wall), ``free``, a named
    vertex ``tip``."""
    from netgen import occ

    body = occ.Box((0, 0, 0), (0.1, 0.02, 0.03))
    chamber = occ.Cylinder((0.02, 0.01, 0.015), occ.X, r=0.006, h=0.06)
    design = body - chamber
    design.solids.name = "design"
    chamber.solids.name = "chamber"
    shape = occ.Glue([design, chamber])
    shape.faces.name = "free"
    shape.faces.Min(occ.X).name = "fixed"
    for f in shape.faces:
        if chamber.bounding_box[0][0] - 1e-6 < f.center.x < chamber.bounding_box[1][0] + 1e-6 \
                and abs(f.center.y - 0.01) < 1e-6 and abs(f.center.z - 0.015) < 1e-6:
            f.name = "inlet"
    shape.vertices.Max(occ.X + occ.Y + occ.Z).name = "tip"
    return shape


def setup(**kw):
    base = dict(supports=Supports(clamp=("fixed",)), void=("chamber",),
                port=Port("tip", (0.0, 1.0, 0.0)),
                pressure=Pressure(inlet=("inlet",), zero=("free",)))
    return Setup(**{**base, **kw})


def test_a_named_solid_meshes_with_its_names():
    meshed = mesh_geometry(chambered_block(), maxh=0.005)
    m = meshed.mesh
    assert m.dim == 3 and meshed.dim == 3 and meshed.h == 0.005
    assert set(m.GetMaterials()) == {"design", "chamber"}
    assert {"fixed", "inlet", "free"} <= set(m.GetBoundaries())
    assert "tip" in m.GetBBBoundaries()
    check_setup_names(m, setup())


@pytest.mark.parametrize("change, message", [
    ({"void": ("cavity",)}, "passive void 'cavity' is not a region"),
    ({"supports": Supports(clamp=("base",))}, "clamp 'base' is not a boundary or point"),
    ({"port": Port("corner", (0.0, 1.0, 0.0))}, "output port 'corner'"),
])
def test_a_missing_name_is_named(change, message):
    m = mesh_geometry(chambered_block(), maxh=0.006).mesh
    with pytest.raises(InputError, match=message):
        check_setup_names(m, setup(**change))


def test_no_design_solid_is_said_in_3d_words():
    from netgen import occ

    box = occ.Box((0, 0, 0), (1, 1, 1))
    m = mesh_geometry(box, maxh=0.4).mesh
    with pytest.raises(InputError, match="no solid is named 'design'.*solid.name = 'design'"):
        check_setup_names(m, setup(void=(), pressure=None))


def test_maxh_checks_all_three_axes():
    from netgen import occ

    thin = occ.Box((0, 0, 0), (1, 1, 0.1))
    with pytest.raises(InputError, match="maxh: 0.2 is too coarse for a domain 0.1 across"):
        mesh_geometry(thin, maxh=0.2)
    assert pn.geometry_kinds.extent(thin) == pytest.approx(0.1, rel=1e-5)  # OCC pads its boxes


def test_a_step_file_and_a_vol_file_load_in_3d(tmp_path):
    from netgen import occ

    box = occ.Box((0, 0, 0), (0.1, 0.05, 0.04))
    box.solids.name = "design"
    box.faces.Min(occ.X).name = "fixed"
    step = tmp_path / "block.step"
    box.WriteStep(str(step))
    meshed = mesh_geometry(str(step), maxh=0.02)
    assert meshed.mesh.dim == 3 and "design" in meshed.mesh.GetMaterials()
    assert "fixed" in meshed.mesh.GetBoundaries()
    vol = tmp_path / "block.vol"
    meshed.mesh.ngmesh.Save(str(vol))
    again = mesh_geometry(str(vol), maxh=1.0)
    assert again.mesh.dim == 3 and again.mesh.ne == meshed.mesh.ne
    assert again.shape is None and again.h > 0
    assert set(again.mesh.GetBoundaries()) == set(meshed.mesh.GetBoundaries())


def chamber_box():
    return Box(0.04, 0.02, 0.01,
               patches=(Patch("fixed", "xmin"), Patch("load", "xmax", (0.005, 0.0025),
                                                        (0.015, 0.0075))),
               blocks=(Block("chamber", "void", (0.01, 0.005, 0.0025), (0.03, 0.015, 0.0075),
                             boundary="inlet"),),
               points=(("tip", (0.04, 0.01, 0.005)), ("corner", (0.04, 0.02, 0.01))))


def test_a_box_meshes_as_tets_and_hexes_with_the_same_names_and_volume():
    from ngsolve import BND, Integrate

    box = chamber_box()
    tets = mesh_geometry(box, maxh=0.004).mesh
    hexes = mesh_geometry(box, maxh=0.004, nelx=8, nely=4, nelz=4).mesh
    for m in (tets, hexes):
        assert set(m.GetMaterials()) == {"design", "chamber"}
        assert set(m.GetBoundaries()) == {"fixed", "load", "free", "inlet"}
        assert {"tip", "corner"} <= set(m.GetBBBoundaries())
        check_setup_names(m, setup())
    assert Integrate(1, tets) == pytest.approx(Integrate(1, hexes), rel=0, abs=1e-12)
    assert Integrate(1, hexes) == pytest.approx(0.04 * 0.02 * 0.01, rel=1e-12)
    for name, area in (("fixed", 2e-4), ("load", 5e-5), ("inlet", 2 * (2e-4 + 1e-4 + 5e-5))):
        for m in (tets, hexes):
            got = Integrate(1, m, BND, definedon=m.Boundaries(name))
            assert got == pytest.approx(area, rel=1e-9), (name, m.ne)
    assert tets.ngmesh.Elements3D().NumPy()["type"][0] == 20
    assert set(hexes.ngmesh.Elements3D().NumPy()["type"]) == {25}


def test_hexes_are_in_grid_order_with_outward_normals():
    from ngsolve import BND, Integrate, specialcf

    box = chamber_box()
    m = structured_box(box, 8, 4, 4)
    assert m.ne == 128
    centres = np.array([np.mean([m.vertices[v.nr].point for v in el.vertices], axis=0)
                        for el in m.Elements()])
    i, j, k = 3, 2, 3
    e = (k * 4 + j) * 8 + i
    assert centres[e] == pytest.approx([(i + 0.5) * 0.005, (j + 0.5) * 0.005,
                                        (k + 0.5) * 0.0025])
    n = specialcf.normal(3)
    assert Integrate(n, m, BND, definedon=m.Boundaries("fixed")) == pytest.approx(
        [-2e-4, 0, 0], abs=1e-15)
    assert Integrate(n, m, BND, definedon=m.Boundaries("inlet")) == pytest.approx(
        [0, 0, 0], abs=1e-15)


def test_nelz_needs_a_box_and_a_box_needs_nelz():
    with pytest.raises(InputError, match="nelz: a box domain"):
        mesh_geometry(chamber_box(), maxh=0.004, nelx=8, nely=4)
    with pytest.raises(InputError, match="structured quads need a rectangular domain"):
        mesh_geometry(chambered_block(), maxh=0.005, nelx=8, nely=4)


def test_a_gmsh_file_with_volume_groups(tmp_path):
    """A 3D .msh: volume physical groups name the regions, surface groups the boundaries."""
    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
    tris = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 4, 3], [1, 2, 4], [2, 3, 4]])
    phys = [np.array([1, 2]), np.array([3, 4, 4, 4, 4, 4])]
    meshio.write(tmp_path / "two.msh",
                 meshio.Mesh(pts, [("tetra", tets), ("triangle", tris)],
                             cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                             field_data={"design": np.array([1, 3]), "chamber": np.array([2, 3]),
                                         "fixed": np.array([3, 2]), "free": np.array([4, 2])}),
                 file_format="gmsh22", binary=False)
    meshed = mesh_geometry(str(tmp_path / "two.msh"), maxh=1.0)
    m = meshed.mesh
    assert m.dim == 3 and m.ne == 2 and set(m.GetMaterials()) == {"design", "chamber"}
    assert set(m.GetBoundaries()) == {"fixed", "free"}
    assert meshed.shape is None and meshed.h > 0
