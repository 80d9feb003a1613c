"""Frictionless contact of two curved walls (pacto_ng/physics/contact.py) against Hertz's
closed form: two equal cylinders pressed together, in plane strain.

Two cylinders of radius R = 1 m (E = 1 Pa, ν = 0.3, linear) touch along a line; a force F'
per unit length presses them together.  Hertz (Johnson 1985, *Contact mechanics*, §4.3):
the contact strip has the half-width a = sqrt(4 F' R* / (π E*)), with R* = R/2 and
E* = E / (2 (1 - ν²)) for two equal bodies, and the pressure across it is elliptic,
p(s) = p0 sqrt(1 - s²/a²), so that its second moment gives the half-width,
a = 2 sqrt(∫ p s² ds / ∫ p ds) over one half of the strip.

Computed on a quarter of each cylinder (symmetric about x = 0, held there in x): the lower
one's flat face y = -R clamped, the upper one's flat face y = R loaded by a pressure q and
held by a soft spring (1e-2 N/m on its mean motion: without contact the upper body would
float); a gap of 1e-4 R between them at rest.  The elements within 3 a of the contact are
halved ``levels`` times (Netgen's refinement, on the circles), order 2.  The contact force per
unit length is F' = 2 F (F the quarter's), read with the package's measure; the strip's
half-width from the second moment of the contact pressure k max(g, 0) over the strip (a
probe written here with NGSolve's ContactBoundary).  Measured (2026-12-06, a ≈ 0.096 R):
relative difference from Hertz -1.34e-2, -4.41e-3 and -2.55e-3 at 1, 2 and 3 levels (orders
1.6 and 0.8: the last level meets the finite bodies' own difference from the half-spaces of
Hertz's theory, a/R ≈ 0.1).  The strip's width counted where the walls overlap
(``contact_area``) is coarser: -2.5e-2, -2.9e-3 and -4.5e-2 at the same levels (its end,
where the pressure falls to zero, is found at the quadrature points only).

The largest contact pressure (``contact_pressure``: the largest over the walls' vertices of
the contact pressure's mean around the vertex, its hat function the weight) against Hertz's
peak p0 = 2 F' / (π a), a the closed form's half-width: measured (2026-12-06) -2.60e-2,
-4.68e-3 and +5.4e-4 at 1, 2 and 3 levels (order 2.5 from the first to the second: the mean
over the peak's vertex's half-hat, of width h, falls short of the peak by about h²/(12 a²);
the third meets the finite bodies' own difference, as the half-width does).
"""
import numpy as np
import pytest
from netgen import occ
from netgen.occ import MoveTo, OCCGeometry, X, Y
from ngsolve import (BilinearForm, CoefficientFunction, ContactBoundary, GridFunction, IfPos,
                     Mesh, x, y)

from pacto_ng import Parameters, Port
from pacto_ng.physics.mechanics import Supports
from pacto_ng.post.part_analysis import PartAnalysis

R, E, NU, GAP, SPRING = 1.0, 1.0, 0.3, 1e-4, 1e-2
E_STAR, R_STAR = E / (2 * (1 - NU ** 2)), R / 2


def cylinders(levels: int, a: float):
    """The two quarter cylinders (module docstring), refined ``levels`` times near the
    contact."""
    top = (occ.Circle((0, R + GAP), R).Face() * MoveTo(0, GAP).Rectangle(R, R).Face())
    bottom = occ.Circle((0, -R), R).Face() * MoveTo(0, -R).Rectangle(R, R).Face()
    for face, tag in ((top, "top"), (bottom, "bottom")):
        face.edges.name = f"arc_{tag}"
        face.edges.Min(X).name = f"axis_{tag}"
    top.edges.Max(Y).name = "pressure"
    bottom.edges.Min(Y).name = "base"
    mesh = Mesh(OCCGeometry(occ.Compound([top, bottom]), dim=2).GenerateMesh(maxh=0.1))
    for _ in range(levels):
        for el in mesh.Elements():
            c = np.mean([mesh[v].point for v in el.vertices], axis=0)
            mesh.SetRefinementFlag(el, bool(np.hypot(*c) < 3 * a))
        mesh.Refine()
    mesh.Curve(2)
    return mesh


def pressed(levels: int, a: float = 0.1):
    """``(half-width by the moment, by the overlap, Hertz's, contact force, applied force)``
    of the cylinders pressed so that Hertz's half-width is about ``a``."""
    q = a ** 2 * np.pi * E_STAR / (4 * R_STAR) / (2 * R)
    mesh = cylinders(levels, a)
    params = Parameters(model="linear", E1=E, E0=1e-6, nu=NU, plane="strain", thickness=1.0,
                        order=2)
    an = PartAnalysis(mesh, "fixed", params=params,
                      supports=Supports(clamp=("base",), fix_x=("axis_top", "axis_bottom")),
                      ports=Port("pressure", (0.0, -1.0), spring=SPRING),
                      contact=("arc_top", "arc_bottom"))
    point = an.solve(q)
    assert point.converged
    moments = []
    state = GridFunction(an.mech.space)
    state.vec.data = an.mech.gfx.vec
    k = an.mech.contact.stiffness
    for weight in (1.0, x * x):  # both walls carry k g: the sum is the force 2 k ∫ g
        cb = ContactBoundary(mesh.Boundaries("arc_top|arc_bottom"),
                             mesh.Boundaries("arc_top|arc_bottom"))
        u = an.mech.space.TrialFunction()
        g = (CoefficientFunction((x, y)) + u - CoefficientFunction((x, y)).Other()
             - u.Other()) * cb.normal
        cb.AddEnergy(IfPos(g, k * g * weight, 0))
        form = BilinearForm(an.mech.space)
        cb.Update(state, form, intorder=10, maxdist=an.mech.contact.maxdist)
        moments.append(form.Energy(state.vec))
    force = point.contact_force
    hertz = np.sqrt(4 * (2 * force) * R_STAR / (np.pi * E_STAR))
    return (2 * np.sqrt(moments[1] / moments[0]), point.contact_area, hertz, force,
            q * R - SPRING * point.delta, moments[0], point.contact_pressure)


def test_two_cylinders_touch_over_hertzs_strip():
    coarse, fine = pressed(1), pressed(2)
    for width, area, hertz, force, applied, probe, _ in (coarse, fine):
        # the force through the contact: the load less the spring's (to Newton's residual,
        # 1e-10 of the load vector's norm: measured 1.5e-8 of the force), and the probe's sum
        assert force == pytest.approx(applied, rel=1e-7)
        assert probe == pytest.approx(force, rel=1e-10)
    errors = [abs(width / hertz - 1) for width, _, hertz, *_ in (coarse, fine)]
    assert errors[1] < 0.006 and errors[1] < 0.5 * errors[0]
    # the largest contact pressure against Hertz's peak p0 = 2 F' / (π a) (a Hertz's
    # half-width for the force F' = 2 F): measured -2.60e-2 and -4.68e-3
    peaks = [peak / (2 * (2 * force) / (np.pi * hertz)) - 1
             for _, _, hertz, force, _, _, peak in (coarse, fine)]
    assert peaks[0] < 0 and peaks[1] < 0  # a mean around the peak's vertex, below the peak
    assert abs(peaks[1]) < 0.006 and abs(peaks[1]) < 0.25 * abs(peaks[0])
    assert abs(fine[1] / fine[2] - 1) < 0.01  # the overlap's width
