"""A case's geometry from any source: netgen.occ shapes (curved), CAD files, Gmsh and Netgen
mesh files, rectangles; several output ports with weights."""
import numpy as np
import pytest

import pacto_ng as pn
from pacto_ng.geometry_kinds import extent
from pacto_ng.meshing import mesh_geometry
from pacto_ng.params import InputError


def half_disc():
    from netgen import occ

    face = (occ.WorkPlane().MoveTo(-1, 0).LineTo(1, 0, name="base")
            .Rotate(90).Arc(1.0, 180, name="arc").Face())
    face.faces.name = "design"
    return face


def test_a_curved_occ_shape_is_meshed_with_its_names():
    meshed = mesh_geometry(half_disc(), maxh=0.2)
    m = meshed.mesh
    assert set(m.GetMaterials()) == {"design"} and set(m.GetBoundaries()) == {"base", "arc"}
    assert meshed.h == 0.2 and meshed.shape is not None and meshed.dim == 2
    # the curved boundary's vertices lie on the unit circle
    from ngsolve import BND

    arc = {v.nr for el in m.Elements(BND) if el.mat == "arc" for v in el.vertices}
    r = [np.hypot(*m.vertices[i].point) for i in arc]
    assert max(abs(np.array(r) - 1.0)) < 1e-12
    assert extent(half_disc()) == pytest.approx(1.0, abs=1e-6)


def test_a_cad_file_keeps_its_names(tmp_path):
    path = tmp_path / "disc.step"
    half_disc().WriteStep(str(path))
    shape = pn.load_cad(path)
    names = {e.name for e in shape.edges}
    assert {"base", "arc"} <= names and {f.name for f in shape.faces} == {"design"}
    m = mesh_geometry(str(path), maxh=0.2).mesh
    assert set(m.GetBoundaries()) == {"base", "arc"}


def test_a_gmsh_file_with_physical_groups(tmp_path):
    import meshio

    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    lines = np.array([[3, 0], [1, 2], [0, 1], [2, 3]])
    phys = [np.array([1, 1]), np.array([2, 3, 4, 4])]
    meshio.write(tmp_path / "sq.msh",
                 meshio.Mesh(pts, [("triangle", np.array([[0, 1, 2], [0, 2, 3]])), ("line", lines)],
                             cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                             field_data={"design": np.array([1, 2]), "fixed": np.array([2, 1]),
                                         "load": np.array([3, 1]), "free": np.array([4, 1])}),
                 file_format="gmsh22", binary=False)
    meshed = mesh_geometry(str(tmp_path / "sq.msh"), maxh=1.0)
    m = meshed.mesh
    assert m.ne == 2 and m.GetMaterials() == ("design",)
    assert set(m.GetBoundaries()) == {"fixed", "load", "free"}
    assert meshed.shape is None and meshed.h == pytest.approx(1.0)  # sqrt(2 area / ne)


def test_a_netgen_vol_file(tmp_path):
    meshed = mesh_geometry(half_disc(), maxh=0.3)
    meshed.mesh.ngmesh.Save(str(tmp_path / "disc.vol"))
    m = pn.load_mesh(tmp_path / "disc.vol")
    assert m.ne == meshed.mesh.ne and set(m.GetBoundaries()) == {"base", "arc"}


@pytest.mark.parametrize("geometry, kwargs, message", [
    ("nothing.step", {}, "CAD file 'nothing.step' does not exist"),
    ("part.dxf", {}, "neither a CAD file"),
    (42, {}, "got a int"),
    (None, {"nelx": 4, "nely": 2}, "structured quads need a rectangular domain"),
    (None, {"maxh": 5.0}, "maxh: 5 is too coarse"),
    ("solid", {"nelx": 4, "nely": 2, "nelz": 2}, "structured hexahedra need a box domain"),
])
def test_bad_geometries_are_one_line_errors(geometry, kwargs, message):
    from netgen import occ

    if geometry is None:
        geometry = half_disc()
    elif geometry == "solid":
        geometry = occ.Box((0, 0, 0), (1, 1, 1))
    with pytest.raises(InputError, match=message):
        mesh_geometry(geometry, **{"maxh": 0.2, **kwargs})


def test_several_ports_with_weights_add_up(one_thread):
    """Outputs: Δ = Σ w d·u, here 2 u_x(a) - mean(-u_y)(b) = 2 u_x(a) + mean u_y(b) for a
    linear u (exact in P1)."""
    from netgen import occ
    from ngsolve import CF, GridFunction, LinearForm, VectorH1, x, y

    face = occ.WorkPlane().Rectangle(1, 1).Face()
    face.faces.name = "design"
    face.vertices.Nearest((1, 0, 0)).name = "a"
    face.edges.Max(occ.Y).name = "b"
    m = mesh_geometry(face, maxh=0.25).mesh
    gf = GridFunction(VectorH1(m, order=1))
    gf.Set(CF((1 + x + 2 * y, 3 * x + y)))  # u_x(1, 0) = 2; on y = 1: u_y = 3x + 1, mean 2.5
    ports = pn.Outputs((pn.Port("a", (1.0, 0.0), weight=2.0), pn.Port("b", (0.0, -1.0), weight=-1.0)))
    fes = gf.space
    lf = LinearForm(fes)
    lf += ports.functional(m, fes.TestFunction())
    lf.Assemble()
    delta = lf.vec.InnerProduct(gf.vec)
    assert delta == pytest.approx(2 * 2.0 + 2.5, rel=1e-12)
    with pytest.raises(ValueError, match="weight"):
        pn.Port("a", (1.0, 0.0), weight=0.0)
    with pytest.raises(ValueError, match="spring"):
        pn.Port("a", (1.0, 0.0), spring=-1.0)
    assert pn.Port("a", (1.0, 0.0), spring=5.0).springs()[0].stiffness == 5.0
