"""Hertz's contact of two cylinders in 3D: the plane-strain set-up of test_hertz.py extruded
into a slab 0.05 R thick, its two faces held in z (plane strain), meshed with tetrahedra
(Netgen, maxh 0.1 R, order 2, curved), the elements within 3 a of the contact halved
``levels`` times; the contact surfaces are the two cylinders' curved faces (quadrature order
6 on them, the 3D default).  The force per unit length F' = 2 F / t, the strip's half-width
from the second moment of the contact pressure over the faces, the largest contact pressure
against Hertz's peak p0 = 2 F' / (π a).

Measured (2026-12-06, one thread): at 0 and 1 levels the half-width within -1.04e-2 and
-7.2e-3 of Hertz's, the largest pressure within -1.59e-2 and -8.8e-3 of p0; 35 s and 134 s
(265 and 436 Newton iterations: the contact pairs made anew until they hold).  The 2D
set-up converges faster with refinement (tests/physics/test_hertz.py); here one element
spans the slab's thickness, and the faces' quadrature is order 6 against 10 in 2D.
"""
import numpy as np
import pytest
from netgen import occ
from netgen.occ import MoveTo, OCCGeometry, X, Y, Z
from ngsolve import (BilinearForm, CoefficientFunction, ContactBoundary, GridFunction, IfPos,
                     Mesh, x, y, z)

from pacto_ng import Parameters, Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.post.part_analysis import PartAnalysis
from test_hertz import E, E_STAR, GAP, NU, R, R_STAR, SPRING

pytestmark = pytest.mark.slow

T = 0.05  # the slab's thickness


def slab(levels: int, a: float):
    """The two quarter cylinders of test_hertz.py extruded by T (module docstring)."""
    top = occ.Circle((0, R + GAP), R).Face() * MoveTo(0, GAP).Rectangle(R, R).Face()
    bottom = occ.Circle((0, -R), R).Face() * MoveTo(0, -R).Rectangle(R, R).Face()
    solids = []
    for face, tag in ((top, "top"), (bottom, "bottom")):
        solid = face.Extrude((0, 0, T))
        solid.faces.name = f"arc_{tag}"
        solid.faces.Min(X).name = f"axis_{tag}"
        solid.faces.Min(Z).name = solid.faces.Max(Z).name = "sides"
        solids.append(solid)
    solids[0].faces.Max(Y).name = "pressure"
    solids[1].faces.Min(Y).name = "base"
    mesh = Mesh(OCCGeometry(occ.Compound(solids)).GenerateMesh(maxh=0.1))
    for _ in range(levels):
        for el in mesh.Elements():
            c = np.mean([mesh[v].point for v in el.vertices], axis=0)
            mesh.SetRefinementFlag(el, bool(np.hypot(c[0], c[1]) < 3 * a))
        mesh.Refine()
    mesh.Curve(2)
    return mesh


def pressed(levels: int, a: float = 0.1):
    """``(half-width / Hertz's - 1, largest pressure / p0 - 1, contact force per length,
    applied force per length)``."""
    q = a ** 2 * np.pi * E_STAR / (4 * R_STAR) / (2 * R)
    mesh = slab(levels, a)
    params = Parameters(model="linear", E1=E, E0=1e-6, nu=NU, thickness=1.0, order=2)
    an = PartAnalysis(mesh, "fixed", params=params,
                      supports=Supports(clamp=("base",), fix_x=("axis_top", "axis_bottom"),
                                        fix_z=("sides",)),
                      ports=Port("pressure", (0.0, -1.0, 0.0), spring=SPRING * T),
                      contact=("arc_top", "arc_bottom"))
    point = an.solve(q)
    assert point.converged
    state = GridFunction(an.mech.space)
    state.vec.data = an.mech.gfx.vec
    k, moments = an.mech.contact.stiffness, []
    for weight in (1.0, x * x):
        walls = mesh.Boundaries("arc_top|arc_bottom")
        cb = ContactBoundary(walls, walls)
        u, X3 = an.mech.space.TrialFunction(), CoefficientFunction((x, y, z))
        g = (X3 + u - X3.Other() - u.Other()) * cb.normal
        cb.AddEnergy(IfPos(g, k * g * weight, 0))
        form = BilinearForm(an.mech.space)
        cb.Update(state, form, intorder=6, maxdist=an.mech.contact.maxdist)
        moments.append(form.Energy(state.vec))
    force = point.contact_force / T
    hertz = np.sqrt(4 * (2 * force) * R_STAR / (np.pi * E_STAR))
    p0 = 2 * (2 * force) / (np.pi * hertz)
    return (2 * np.sqrt(moments[1] / moments[0]) / hertz - 1, point.contact_pressure / p0 - 1,
            force, q * R - SPRING * point.delta)


def test_two_cylinders_touch_over_hertzs_strip_in_3d():
    coarse, fine = pressed(0), pressed(1)
    for _, _, force, applied in (coarse, fine):
        assert force == pytest.approx(applied, rel=1e-4)  # measured 1.8e-5 and 5.7e-7
    for i in (0, 1):  # the half-width, the largest pressure: below Hertz's, approaching it
        assert coarse[i] < 0 and fine[i] < 0 and abs(fine[i]) < 0.8 * abs(coarse[i])
        assert abs(fine[i]) < 0.01
