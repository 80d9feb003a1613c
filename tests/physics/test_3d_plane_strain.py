"""A 3D slab held in plane strain (u_z = 0 on both z faces) is the 2D plane-strain analysis of its
cross-section: structured hexahedra nx x ny x 1 against structured quadrilaterals nx x ny.

With u_z = 0 on both faces and one element through the depth, the mirror symmetry z -> T - z
makes u independent of z; a trilinear field independent of z with u_z = 0 has the strains of the
bilinear quad field, the 2 x 2 x 2 Gauss rule integrates a z-independent integrand as T times the
2 x 2 rule, and a mean over the end face is the mean over the end edge.  The discrete equations
are therefore those of the 2D block with thickness T: the two solutions agree to the solver's
round-off (linear) or Newton's tolerance (nonlinear), for point loads and for the Darcy pressure
(no flux through the z faces: p is independent of z too), fixed or follower (cof(F) of a
z-independent plane deformation is the 2D cofactor, and its z row meets ∂p/∂z = 0).

The 2D blocks are pinned by their own tests; here they are the reference.
"""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng.design import DesignField
from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import Compliance, darcy_body, darcy_follower
from pacto_ng.physics.loads import PointLoad
from pacto_ng.physics.materials import get_material, jacobian
from pacto_ng.physics.mechanics import Field, Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.wang import wang_model
from pacto_ng.responses import compliance

L, H, T = 1.0, 0.25, 0.1
NX, NY = 12, 4
E1, E0, NU = 3e9, 3e3, 0.4


def meshes():
    from ngsolve.meshes import MakeStructured2DMesh, MakeStructured3DMesh

    m2 = MakeStructured2DMesh(quads=True, nx=NX, ny=NY, mapping=lambda x, y: (L * x, H * y))
    m3 = MakeStructured3DMesh(hexes=True, nx=NX, ny=NY, nz=1,
                              mapping=lambda x, y, z: (L * x, H * y, T * z))
    return m2, m3


# the names of the same boundaries: 2D quads, 3D hexes
NAMES = {2: {"clamp": "left", "end": "right", "inlet": "bottom", "zero": "top"},
         3: {"clamp": "back", "end": "front", "inlet": "left", "zero": "right"}}


def density(mesh):
    """A smooth density of the element centroid (the same function on both meshes)."""
    c = DesignField(mesh).centroids()
    return 0.55 + 0.4 * np.sin(5 * c[:, 0]) * np.cos(7 * c[:, 1])


def energy(model):
    modulus = lambda c: simp_cf(c["rho_bar"], E0, E1, 3.0)
    if model == "wang":
        model = wang_model(modulus, NU, "strain", "rho_bar", 3.0)
        return model, model.guard, False
    mat = get_material(model)
    guard = (lambda G, c: jacobian(G)) if mat.needs_positive_J else None
    return (lambda G, c: mat.energy(G, modulus(c), NU)), guard, mat.linear


def block(mesh, model, load):
    """The mechanics block on a 2D (thickness T) or 3D (thickness 1, u_z = 0 on the z faces)
    mesh, with a force on the end or the Darcy pressure (``load``: force | fixed | follower),
    solved; and the compliance of its load (None for the follower load)."""
    d, n = mesh.dim, NAMES[mesh.dim]
    e, guard, linear = energy(model)
    sup = Supports(clamp=(n["clamp"],), fix_z=("bottom", "top") if d == 3 else ())
    kw = dict(order=1, energy=e, supports=sup, guard=guard, linear=linear,
              thickness=T if d == 2 else 1.0, newton=NewtonSettings(rtol=1e-12))
    rho = density(mesh)
    if load == "force":
        force = (0.0, -4e4) + ((0.0,) if d == 3 else ())
        mech = Mechanics(mesh, loads=(PointLoad(n["end"], force),), **kw)
        return mech, compliance(mech).forward(mech.forward(rho))
    dar = DarcyPressure(mesh, inlet=n["inlet"], zero=n["zero"], p_in=3e7, delta_s=0.05)
    p = dar.forward(rho)
    extra = ({"body": darcy_body("p")} if load == "fixed"
             else {"residual_density": darcy_follower("p")})
    mech = Mechanics(mesh, fields=("rho_bar", Field("p", dar.fes)), **extra, **kw)
    u = mech.forward(rho, p)
    return mech, (Compliance(mech, dar).forward(u, p) if load == "fixed" else None)


def difference(model, load):
    """max |u3 - u2| / max |u2| over the 2D vertices, at z = 0 and z = T, the largest |u_z|, the
    2D tip deflection (the scale of the deformation), and the two compliances."""
    m2, m3 = meshes()
    (b2, c2), (b3, c3) = block(m2, model, load), block(m3, model, load)
    pts = np.array([v.point for v in m2.vertices])
    u2 = np.array([b2.gfu(m2(x, y)) for x, y in pts])
    diff, uz = 0.0, 0.0
    for z in (0.0, T):
        u3 = np.array([b3.gfu(m3(x, y, z)) for x, y in pts])
        diff = max(diff, float(np.max(np.abs(u3[:, :2] - u2))))
        uz = max(uz, float(np.max(np.abs(u3[:, 2]))))
    return diff / float(np.max(np.abs(u2))), uz, float(np.max(np.abs(u2[:, 1]))), (c2, c3)


@pytest.mark.parametrize("model,load", [
    ("linear", "force"),  # measured relative difference 2.5e-14
    ("neohookean", "force"),  # 2.2e-15
    ("linear", "fixed"),  # 3.7e-14
    ("wang", "fixed"),  # 3.4e-16
    ("neohookean", "follower"),  # 6.3e-16
])
def test_slab_in_plane_strain_is_the_2d_analysis(model, load):
    """The same discrete equations: agreement to round-off (measured at most 3.7e-14 of the
    largest displacement, deflections 0.12 - 2.9 m of the 1 m slab), asserted at 1e-10: far below
    any discretisation error, above the round-off of Newton's stopping test (residual 1e-12 of
    the load).  The compliance of the force and of the fixed Darcy load (its 3D value over the
    volume, thickness 1; the 2D one times T) agree alike (measured at most 4.4e-14)."""
    rel, uz, tip, (c2, c3) = difference(model, load)
    print(model, load, "relative difference", rel, "largest |u_z|", uz, "2D deflection", tip,
          "compliances", c2, c3)
    assert tip > 0.1 * L  # a real deformation (measured 0.12 - 2.9 of the length)
    assert uz == 0.0
    assert rel < 1e-10
    if c2 is not None:
        assert c2 > 0 and abs(c3 / c2 - 1) < 1e-10
