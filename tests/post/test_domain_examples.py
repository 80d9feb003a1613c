"""The part on the domain's geometry for the shapes of the example cases soft-finger (tapered
finger, round tip, round passive void chamber) and jaw-gripper (trapezoid with a mouth, passive
solid pads, passive void object): regressions of two failures of the real runs.

* soft-finger: the cut at the tip started on the arc 9 µm past its junction with the flat
  underside (the iso-line ends at the domain's vertex); the spline ending on the boundary there
  made OCC's Common of the part with the domain empty ("the part and the domain do not
  overlap") and the run fell back to the traced outline.  The cut below is that run's.
* jaw-gripper: splines through every other point of the zig-zag iso-lines of a coarse mesh
  (h 5 mm) could not be triangulated ("OCC-Triangulation could not be built for face 1"), the
  domain route and the traced fallback alike; on the real run they also lost 2.2 % of the area.
"""
import numpy as np
import pytest

from pacto_ng.post.domain import material_domain
from pacto_ng.post.domain_part import build_domain_geometry
from pacto_ng.post.grid import mesh_to_pyvista
from pacto_ng.post.remesh import _generate, remesh
from pacto_ng.post.threshold import Component, Loop, threshold

L, B, T = 0.10, 0.026, 0.012            # the finger: length, base and tip height
CH = (0.032, 0.011, 0.006)              # its chamber: centre and radius
# the tip cut of the default soft-finger run (mm): from the arc just past (L - T/2, 0) to the
# tapered back
TIP_CUT = np.array([
    [94.0091, 0.0012], [94.0047, 0.0097], [93.7381, 1.5599], [93.4836, 2.046], [92.7734, 2.9519],
    [92.5664, 3.2611], [91.9822, 4.2527], [91.6913, 4.5369], [90.8659, 5.5147],
    [90.8237, 5.6388], [90.6555, 5.7011], [89.7498, 6.4054], [89.0835, 7.0269],
    [88.7959, 7.4436], [88.1517, 7.9433], [87.5931, 8.1589], [87.4814, 8.6084],
    [86.7413, 9.3909], [85.7525, 10.2718], [85.7025, 10.3723], [85.5972, 10.393],
    [84.1665, 10.6877], [83.8778, 12.0209], [83.7008, 12.4396], [83.5442, 13.5572]]) * 1e-3


def _top(x):
    return B - (B - T) * x / (L - T / 2)


def finger_shape():
    from netgen import occ

    r = T / 2
    body = (occ.WorkPlane().MoveTo(0, 0).LineTo(L - r, 0, name="skin").Arc(r, 180, name="skin")
            .LineTo(0, B, name="skin").LineTo(0, 0, name="base").Face())
    chamber = occ.WorkPlane().Circle(*CH).Face()
    chamber.edges.name = "inlet"
    chamber.faces.name = "chamber"
    design = body - chamber
    design.faces.name = "design"
    return occ.Glue([design, chamber])


def jaw_shape():
    from netgen import occ

    Lx, Bk, F, M, G, PAD, MT = 0.16, 0.12, 0.08, 0.04, 0.012, 0.004, 0.015
    x0 = Lx - M
    body = (occ.WorkPlane().MoveTo(0, -Bk / 2).LineTo(Lx, -F / 2, name="skin")
            .LineTo(Lx, -G, name="skin").LineTo(x0, -G, name="skin").LineTo(x0, G, name="skin")
            .LineTo(Lx, G, name="skin").LineTo(Lx, F / 2, name="skin")
            .LineTo(0, Bk / 2, name="skin").LineTo(0, Bk / 2 - MT, name="mount")
            .LineTo(0, -Bk / 2 + MT, name="inlet").LineTo(0, -Bk / 2, name="mount").Face())
    obj = occ.WorkPlane().MoveTo(x0, -G).Rectangle(M, 2 * G).Face()
    obj.faces.name = "object"
    obj.edges.name = "skin"
    pads = (occ.WorkPlane().MoveTo(x0, G).Rectangle(M, PAD).Face()
            + occ.WorkPlane().MoveTo(x0, -G - PAD).Rectangle(M, PAD).Face())
    pads.faces.name = "pads"
    design = body - pads
    design.faces.name = "design"
    return occ.Glue([design, pads, obj])


def _mesh(shape, maxh):
    import ngsolve as ng
    from netgen import occ

    return ng.Mesh(occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh))


def _centroids(mesh):
    return np.asarray(mesh_to_pyvista(mesh).cell_centers().points)[:, :2]


def _segment_distance(p, a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    t = np.clip(((p - a) @ d) / (d @ d), 0.0, 1.0)
    return np.hypot(*(p - a - t[:, None] * d).T)


def _boundary_points(mesh, names):
    import ngsolve as ng

    return np.array([mesh[v].point for el in mesh.Elements(ng.BND) if el.mat in names
                     for v in el.vertices])


def _on_finger_skin(p):
    """Distance of points from the finger's outline (underside, tip arc, tapered back)."""
    r = T / 2
    d_arc = np.abs(np.hypot(p[:, 0] - (L - r), p[:, 1] - r) - r)
    d_arc[p[:, 0] < L - r - 1e-12] = np.inf
    return np.minimum.reduce([_segment_distance(p, (0, 0), (L - r, 0)), d_arc,
                              _segment_distance(p, (L - r, T), (0, B))])


def _on_chamber(p):
    return np.abs(np.hypot(p[:, 0] - CH[0], p[:, 1] - CH[1]) - CH[2])


def test_finger_cut_from_the_tip_junction_lies_on_the_domain():
    """The solid of the real run's outer loop (underside, tip cut, tapered back, base), around
    the chamber: the part is built on the domain (before: no face at all), its area is the
    loop's within 1 %, the underside and back are the domain's lines, the chamber's wall its
    circle."""
    import ngsolve as ng

    h = 0.0016
    bottom = np.c_[np.arange(0.0, L - T / 2, h / 2), np.zeros(len(np.arange(0.0, L - T / 2, h / 2)))]
    cut = TIP_CUT.copy()
    cut[-1, 1] = _top(cut[-1, 0])
    xs = np.arange(cut[-1, 0], 0.0, -h / 2)[1:]
    back = np.c_[xs, _top(xs)]
    base = np.c_[np.zeros(8), np.linspace(B, 0.0, 9)[:-1]]
    pts = np.vstack([bottom, cut, back, base])
    labels = (["skin"] * len(bottom) + [None] * (len(cut) - 1) + ["skin"] * (len(back) + 1)
              + ["base"] * len(base))
    comp = Component(Loop(pts, tuple(labels), 0), ())
    dom = material_domain(finger_shape(), ("chamber",))
    shape = build_domain_geometry([comp], h, dom)
    expected = comp.area - np.pi * CH[2] ** 2
    assert sum(f.mass for f in shape.faces) == pytest.approx(expected, rel=0.01)
    mesh = ng.Mesh(_generate(shape, h / 2, 0.5))
    assert ng.Integrate(1.0, mesh) == pytest.approx(expected, rel=0.01)
    assert set(mesh.GetBoundaries()) >= {"skin", "base", "inlet", "free"}
    assert _on_finger_skin(_boundary_points(mesh, ("skin",))).max() < 1e-9
    wall = _boundary_points(mesh, ("inlet",))
    assert _on_chamber(wall).max() < 1e-9
    assert np.ptp(np.arctan2(wall[:, 1] - CH[1], wall[:, 0] - CH[0])) > 6.0  # all round


def test_finger_density_remeshed_on_the_domain():
    """A box-like finger design (underside and back skins, base, a ring round the chamber, a
    diagonal strut from the tip's junction to the back; nothing beyond it), coarse (maxh 2 mm):
    the domain route, area within 1 % of the thresholded area, the underside and back on the
    domain's lines, the chamber's wall (wetted: ``pressure``) on its circle."""
    shape = finger_shape()
    mesh = _mesh(shape, 0.002)
    c = _centroids(mesh)
    x, y = c[:, 0], c[:, 1]
    w = 0.003
    p0, p1 = np.array([L - T / 2, 0.0]), np.array([0.0835, _top(0.0835)])
    d = (p1 - p0) / np.linalg.norm(p1 - p0)
    sd = (c - p0) @ np.array([d[1], -d[0]])
    dtop = (_top(x) - y) / np.hypot(1.0, (B - T) / (L - T / 2))
    solid = (sd < 0) & ((y < w) | (dtop < w) | (x < 0.004) | (sd > -w)
                        | (np.hypot(x - CH[0], y - CH[1]) < CH[2] + w))
    th = threshold(mesh, solid.astype(float), 0.5, exclude=("chamber",))
    rm = remesh(th, 0.001, clamp=("base",), domain=shape)
    assert rm.geometry == "domain"
    assert rm.area == pytest.approx(th.area, rel=0.01)
    assert _on_finger_skin(_boundary_points(rm.mesh, ("skin",))).max() < 1e-9
    wall = _boundary_points(rm.mesh, ("pressure",))
    assert len(wall) and _on_chamber(wall).max() < 1e-9


def test_jaw_struts_on_a_coarse_mesh_remeshed_on_the_domain():
    """Diagonal struts of the jaw's body on a coarse mesh (maxh 5 mm, struts 1 cm wide): the
    zig-zag iso-lines meshed (before: OCC-Triangulation could not be built, on the domain and
    traced), on the domain, area within 1 %; the skin (the outline and the mouth's wall, the void
    object's edge) and the back edge are the domain's lines."""
    shape = jaw_shape()
    mesh = _mesh(shape, 0.005)
    c = _centroids(mesh)
    struts = [((0.0, 0.05), (0.06, 0.0)), ((0.0, -0.05), (0.06, 0.0)),
              ((0.06, 0.0), (0.125, 0.014)), ((0.06, 0.0), (0.125, -0.014)),
              ((0.0, 0.045), (0.1, 0.045)), ((0.0, -0.045), (0.1, -0.045)),
              ((0.1, 0.045), (0.15, 0.016)), ((0.1, -0.045), (0.15, -0.016)),
              ((0.0, -0.045), (0.0, 0.045))]
    solid = np.zeros(len(c), bool)
    for a, b in struts:
        solid |= _segment_distance(c, a, b) < 0.005
    th = threshold(mesh, solid.astype(float), 0.5, exclude=("object",))
    rm = remesh(th, 0.0025, clamp=("mount",), domain=shape)
    assert rm.geometry == "domain"
    assert rm.area == pytest.approx(th.area, rel=0.01)
    skin = _boundary_points(rm.mesh, ("skin",))
    outline = [(0.0, -0.06), (0.16, -0.04), (0.16, -0.012), (0.12, -0.012), (0.12, 0.012),
               (0.16, 0.012), (0.16, 0.04), (0.0, 0.06)]
    off = np.minimum.reduce([_segment_distance(skin, a, b) for a, b in zip(outline[:-1],
                                                                           outline[1:])])
    assert off.max() < 1e-9
    assert (np.abs(skin[:, 0] - 0.12) < 1e-9).sum() >= 3  # the mouth's bottom is solid
    back = _boundary_points(rm.mesh, ("mount", "pressure"))
    assert np.abs(back[:, 0]).max() < 1e-9
