"""A chamber beam whose output is a boundary: Δ = the mean of -u_y over its right edge ``tip``
(a port on an edge, as docs/tutorial.md allows: "a named point, or the mean over a named
boundary").  0.1 x 0.05 m, clamped on the left edge (``fixed``), a passive void cavity
[0.03, 0.07] x [0.015, 0.03] whose walls are the ``inlet``, zero pressure on the top, the
bottom and the right edge.  For tests/post/test_analyse.py."""
import pacto_ng as pn

W, H = 0.1, 0.05
CAVITY = (0.03, 0.015, 0.07, 0.03)


def geometry(p):
    return pn.Layout(W, H, segments=(pn.Segment("fixed", (0.0, H), (0.0, 0.0)),
                                     pn.Segment("tip", (W, 0.0), (W, H)),
                                     pn.Segment("outer", (0.0, 0.0), (W, 0.0)),
                                     pn.Segment("outer", (W, H), (0.0, H))),
                     regions=(pn.Region("cavity", "void", *CAVITY, boundary="inlet"),))


def setup(p):
    return pn.Setup(supports=pn.Supports(clamp=("fixed",)),
                    pressure=pn.Pressure(inlet=("inlet",), zero=("outer", "tip")),
                    port=pn.Port("tip", (0.0, -1.0), spring=p.k_out), void=("cavity",),
                    objective="mechanism", objective_ref=0.1 / (p.load * W * p.thickness))


CASE = pn.Case(
    name="edge_port", summary="chamber beam read on its right edge (a port on a boundary)",
    source="tests/post/cases/edge_port.py",
    defaults=pn.Parameters(model="linear", maxh=0.004, plane="strain", thickness=1e-3,
                           E1=1e8, E0=1e2, nu=0.4, volfrac=0.5, filter_radius=0.008,
                           load=1e5, k_out=1e3, iterations=2, move=0.2),
    geometry=geometry, setup=setup, load_unit="Pa")
