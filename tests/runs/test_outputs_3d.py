"""A 3D design's output files (pacto_ng/outputs.py, pacto_ng/post/plots.py, plots3d.py):
design.vtu holds x, ρ̄, u, p and the 3x3 strain and stress components; design.png and
pressure.png are rendered off-screen at their size; member_width says a 3D design is not
measured.  The problem is a stand-in holding what the writers read (a linear solid on a
chambered box, tetrahedra and hexahedra), so that the test needs no 3D physics."""
from types import SimpleNamespace

import numpy as np
import pytest

from pacto_ng.box import Block, Box, netgen_box_mesh, structured_box
from pacto_ng.member_width import member_width_of_run
from pacto_ng.outputs import drawn as outputs_drawn
from pacto_ng.outputs import one_mesh, write_vtu
from pacto_ng.post.plots import density_png, pressure_png
from pacto_ng.post.plots3d import WINDOW

pytestmark = pytest.mark.usefixtures("pacto_one_thread")

BOX = Box(0.04, 0.02, 0.01, blocks=(Block("chamber", "void", (0.01, 0.005, 0.0025),
                                          (0.03, 0.015, 0.0075), boundary="inlet"),))


def stand_in(mesh):
    """What write_vtu and the pictures' :func:`pacto_ng.outputs.drawn` read of a Problem, for
    ``mesh``."""
    from ngsolve import CF, H1, L2, GridFunction, InnerProduct, Sym, Trace, VectorH1, x, y, z

    l2 = L2(mesh, order=0)
    gfu = GridFunction(VectorH1(mesh, order=1))
    gfu.Set(CF((1e-3 * y, 3e-3 * x, 2e-3 * z)))  # linear: exact in P1
    gfp = GridFunction(H1(mesh, order=1))
    gfp.Set(1e5 * (1 - (x - 0.02) ** 2 / 4e-4))
    centres = np.array([np.mean([mesh.vertices[v.nr].point for v in el.vertices], axis=0)
                        for el in mesh.Elements()])
    shell = np.linalg.norm((centres - [0.02, 0.01, 0.005]) / [0.018, 0.009, 0.01], axis=1)
    rho = np.where(shell < 1.0, 1.0, 1e-3)
    rho[[el.mat == "chamber" for el in mesh.Elements()]] = 1e-3

    def energy(G, c):
        eps = Sym(G)
        return 0.5 * Trace(eps) ** 2 + InnerProduct(eps, eps)

    return SimpleNamespace(
        mesh=mesh, params=SimpleNamespace(order=1, model="linear"),
        case=SimpleNamespace(name="box3d"), values={"rho_bar": rho, "p": gfp},
        n_design_fields=1, field=SimpleNamespace(full=lambda xs: xs, design=rho > 0,
                                                 areas=np.ones(mesh.ne)),
        mech=SimpleNamespace(l2=l2, u=gfu, energy=energy, coeffs=None),
        pressure_block=SimpleNamespace(pressure=gfp, p_in=1e5, inputs=("rho_bar",)),
        design_density=lambda: rho, volume_fraction=lambda: float(np.mean(rho)))


@pytest.fixture(scope="module", params=["tets", "hexes"])
def problem(request):
    if request.param == "tets":
        return stand_in(netgen_box_mesh(BOX, 0.004))
    return stand_in(structured_box(BOX, 16, 8, 4))


def test_design_vtu_holds_the_3d_fields(problem, tmp_path):
    import meshio

    write_vtu(tmp_path / "design", problem, problem.values["rho_bar"])
    m = meshio.read(tmp_path / "design.vtu")
    assert sum(len(c.data) for c in m.cells) == problem.mesh.ne
    assert {c.type for c in m.cells} <= {"tetra", "hexahedron"}
    for name in ("rho_bar", "x", "p"):
        assert np.asarray(m.point_data[name]).size == len(m.points)
    assert np.asarray(m.point_data["u"]).shape == (len(m.points), 3)
    for part in ("strain", "stress"):
        for comp in ("xx", "yy", "zz", "xy", "yz", "xz"):
            assert f"{part}_{comp}" in m.point_data
    # u = (1e-3 y, 3e-3 x, 2e-3 z): ε_zz = 2e-3, ε_xy = 2e-3, ε_yz = 0, and the stand-in's
    # σ = tr(ε) I + 2 ε: σ_xx = 2e-3, σ_zz = 6e-3, σ_xy = 4e-3
    for name, value in (("strain_zz", 2e-3), ("strain_xy", 2e-3), ("strain_yz", 0.0),
                        ("stress_xx", 2e-3), ("stress_zz", 6e-3), ("stress_xy", 4e-3)):
        assert np.allclose(m.point_data[name].ravel(), value, rtol=1e-9, atol=1e-15), name
    assert member_width_of_run(tmp_path)["reason"].startswith("a 3D design")


def test_design_and_pressure_pictures_are_rendered_off_screen(problem, tmp_path):
    import matplotlib.image as mpimg

    drawn = outputs_drawn(problem, one_mesh(problem), {"volume_fraction": 0.5})
    density_png(tmp_path / "design.png", drawn)
    pressure_png(tmp_path / "pressure.png", drawn)
    for name in ("design.png", "pressure.png"):
        img = mpimg.imread(tmp_path / name)
        assert img.shape[:2] == (WINDOW[1], WINDOW[0])
        # not blank: the pictures hold many colours
        assert len(np.unique(img[..., :3].reshape(-1, 3), axis=0)) > 50, name
