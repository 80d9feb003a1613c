"""Synthetic designs for the post-analysis tests (no optimisation needed).

* the *chamber*: a 0.1 x 0.05 m domain (a pneunet-like layout) whose solid is a thick
  rectangular frame ``[0, 0.09] x [0.005, 0.04]`` around a passive void cavity
  ``[0.03, 0.07] x [0.015, 0.03]`` (boundary ``inlet``), clamped on the left edge (``fixed``),
  output port in the middle of the bottom wall's outer face (it bulges out under pressure);
  the pressure is ``P_in`` inside the cavity and 0 elsewhere;
* the *ring quarter*: the exact (curved, OCC) quarter of a thick-walled cylinder
  ``a = 1 <= r <= b = 2`` with symmetry edges ``left`` (x = 0) and ``bottom`` (y = 0), inner
  arc ``pressure``, outer arc ``outer`` and the point ``output`` at (a, 0).
"""
import numpy as np
import pytest

W, H = 0.1, 0.05
CAVITY = (0.03, 0.015, 0.07, 0.03)
FRAME = (0.0, 0.005, 0.09, 0.04)
OUTPUT = (0.05, 0.005)  # middle of the frame's bottom wall
P_IN = 1e5


def chamber_layout():
    from pacto_ng.mesh import Layout, Region, Segment

    return Layout(W, H, segments=(Segment("fixed", (0.0, H), (0.0, 0.0)),),
                  regions=(Region("cavity", "void", *CAVITY, boundary="inlet"),),
                  points=(("output", OUTPUT),))


def box_density(mesh, boxes_in, boxes_out=()):
    """Element densities: 1 where the centroid is in a box of ``boxes_in`` and in none of
    ``boxes_out``, else 0."""
    from pacto_ng.post.grid import mesh_to_pyvista

    c = np.asarray(mesh_to_pyvista(mesh).cell_centers().points)[:, :2]

    def inside(box):
        x0, y0, x1, y1 = box
        return (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)

    rho = np.zeros(len(c), dtype=bool)
    for b in boxes_in:
        rho |= inside(b)
    for b in boxes_out:
        rho &= ~inside(b)
    return rho.astype(float)


def chamber_density(mesh):
    return box_density(mesh, [FRAME], [CAVITY])


def chamber_pressure(x, y):
    x0, y0, x1, y1 = CAVITY
    return np.where((x > x0) & (x < x1) & (y > y0) & (y < y1), P_IN, 0.0)


@pytest.fixture(scope="session")
def chamber_quads():
    from pacto_ng.mesh import structured_mesh

    return structured_mesh(chamber_layout(), 100, 50)


@pytest.fixture(scope="session")
def chamber_trigs():
    from pacto_ng.mesh import netgen_mesh

    return netgen_mesh(chamber_layout(), 0.0012)


@pytest.fixture(scope="session")
def chamber_remeshed(chamber_quads):
    from pacto_ng.post.remesh import remesh
    from pacto_ng.post.threshold import threshold

    th = threshold(chamber_quads, chamber_density(chamber_quads))
    return th, remesh(th, 0.003, pressure=chamber_pressure)


#: the chamber's solid: Neo-Hookean, E = 1e8 Pa, ν = 0.4, plane strain, t = 1 mm
CHAMBER_PARAMS = dict(model="neohookean", E1=1e8, E0=1e2, E2=1e8, nu=0.4, thickness=1e-3,
                      plane="strain")


@pytest.fixture(scope="session")
def chamber_sweeps(chamber_remeshed):
    """Fixed and follower sweeps of the remeshed chamber at 1e3, 1e4 and 1e5 Pa
    (:class:`~pacto_ng.post.part_analysis.PartAnalysis`, :data:`CHAMBER_PARAMS`, output spring
    1e4 N/m, order 2): ``{kind: Sweep}``."""
    from pacto_ng.params import Parameters
    from pacto_ng.physics.loads import Port
    from pacto_ng.physics.mechanics import Supports
    from pacto_ng.post.part_analysis import PartAnalysis

    th, rm = chamber_remeshed
    params = Parameters(**CHAMBER_PARAMS)
    return {kind: PartAnalysis(rm.mesh, kind, params=params, order=2,
                               supports=Supports(clamp=("fixed",)),
                               ports=Port("output", (0.0, -1.0), 1e4)).sweep([1e3, 1e4, 1e5])
            for kind in ("fixed", "follower")}


def ring_quarter_mesh(maxh, a=1.0, b=2.0, curve=3):
    import ngsolve as ng
    from netgen import occ

    shape = (occ.Circle((0, 0), b).Face() - occ.Circle((0, 0), a).Face()) \
        * occ.MoveTo(0, 0).Rectangle(b, b).Face()
    for e in shape.edges:
        c = e.center
        if abs(c.x) < 1e-9:
            e.name = "left"
        elif abs(c.y) < 1e-9:
            e.name = "bottom"
        else:
            e.name = "pressure" if np.hypot(c.x, c.y) < 0.5 * (a + b) else "outer"
    shape.vertices.Nearest((a, 0, 0)).name = "output"
    mesh = ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))
    if curve > 1:
        mesh.Curve(curve)
    return mesh


@pytest.fixture(scope="session")
def ring_quarter():
    return ring_quarter_mesh(0.1)


@pytest.fixture(scope="session")
def ring_quarter_straight():
    """Straight-sided elements: for checks that do not need the exact circle."""
    return ring_quarter_mesh(0.1, curve=1)


def name_edges(shape, namer):
    """Name every edge of ``shape`` by ``namer(x, y)`` of its centre."""
    for e in shape.edges:
        c = e.center
        e.name = namer(c.x, c.y)
    return shape


def half_disc_shape(R=1.0):
    """The upper half of the disc of radius R: arc ``outer``, the diameter's right half
    ``symmetry`` and its left half ``fixed``."""
    from netgen import occ

    shape = occ.WorkPlane().MoveTo(-R, 0).LineTo(0, 0).LineTo(R, 0).Rotate(90).Arc(R, 180) \
        .Close().Face()
    return name_edges(shape, lambda x, y: "outer" if abs(y) > 1e-9 else
                      ("fixed" if x < 0 else "symmetry"))


def ring_quarter_shape(a=1.0, b=2.0):
    """The quarter ring ``a <= r <= b`` of :func:`ring_quarter_mesh` (same names)."""
    from netgen import occ

    shape = (occ.Circle((0, 0), b).Face() - occ.Circle((0, 0), a).Face()) \
        * occ.MoveTo(0, 0).Rectangle(b, b).Face()
    return name_edges(shape, lambda x, y: "left" if abs(x) < 1e-9 else "bottom"
                      if abs(y) < 1e-9 else ("pressure" if np.hypot(x, y) < 0.5 * (a + b)
                                             else "outer"))


def centroids(mesh):
    from pacto_ng.post.grid import mesh_to_pyvista

    return np.asarray(mesh_to_pyvista(mesh).cell_centers().points)[:, :2]
