"""The Newton forms' two speed-ups (pacto_ng/physics/quadrature.py ``mechanics_rules``,
pacto_ng/physics/compiled.py): one quadrature point on order-1 triangles and tetrahedra, and
in 3D the tangent from symbolic derivatives.  References independent of both: the same forms
integrated with the degree-2 rule (3 points on a triangle, 4 on a tetrahedron), and central
differences of the residual.
"""
from __future__ import annotations

import numpy as np
import pytest
from ngsolve import H1, CF, GridFunction, IntegrationRule, TET, TRIG, x, y, z

from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy_load import darcy_follower
from pacto_ng.physics.materials import jacobian, neohookean_energy
from pacto_ng.physics.mechanics import Field, Mechanics, Supports
from small_cases import PA_L, small_pa_mesh

pytestmark = pytest.mark.usefixtures("one_thread")


def _mesh(dim):
    """``(mesh, size)``: the small pa-inverter's triangles, or tetrahedra of a 1 x 0.4 x 0.3 m
    box clamped at x = 0, and the domain's length."""
    if dim == 2:
        return small_pa_mesh("trig"), PA_L
    from netgen.occ import X, Box, OCCGeometry
    from ngsolve import Mesh

    box = Box((0, 0, 0), (1.0, 0.4, 0.3))
    box.faces.Min(X).name = "fixed"
    return Mesh(OCCGeometry(box, dim=3).GenerateMesh(maxh=0.15)), 1.0


def _block(mesh, size, intorder=None):
    """A Neo-Hookean SIMP block under a follower pressure ``p`` (an order-1 field, varying by
    its mean over the domain), with a random density and a random state (1e-4 of the domain's
    size); ``intorder`` replaces the block's own rule."""
    modulus = lambda c: simp_cf(c["rho_bar"], 3e3, 3e8, 3.0)  # noqa: E731
    mech = Mechanics(mesh, energy=lambda G, c: neohookean_energy(G, modulus(c), 0.4),
                     guard=lambda G, c: jacobian(G), residual_density=darcy_follower("p"),
                     fields=("rho_bar", Field("p", H1(mesh, order=1))),
                     supports=Supports(clamp=("fixed",)), intorder=intorder)
    p = GridFunction(H1(mesh, order=1))
    p.Set(CF(1e5 * (1 + (x + y + (z if mesh.dim == 3 else 0)) / size)))
    mech.set_fields(np.random.default_rng(1).uniform(0.1, 1.0, mesh.ne), p.vec)
    u = mech.state_vector
    u.FV().NumPy()[:] = 1e-4 * size * np.random.default_rng(2).standard_normal(len(u))
    u.FV().NumPy()[~mech.free] = 0.0
    return mech


def _residual(mech, vec):
    out = vec.CreateVector()
    mech.residual(vec, out, 1.0)
    return out.FV().NumPy().copy()


def _tangent_times(mech, vec, d):
    mech.assemble_tangent(vec, 1.0)
    out = vec.CreateVector()
    out.data = mech.matrix * d
    return out.FV().NumPy().copy()


@pytest.mark.parametrize("dim", [2, 3])
def test_one_point_integrates_the_order_one_simplex_forms_exactly(dim):
    """∇u and ρ̄ are constant on an order-1 simplex and p is linear: the residual and the
    tangent of the one-point rule equal the degree-2 rule's to round-off."""
    mesh, size = _mesh(dim)
    fast, ref = _block(mesh, size), _block(mesh, size, intorder=2)
    et = TRIG if dim == 2 else TET
    assert len(fast.rules[et].points) == 1 < len(ref.rules[et].points) == len(
        IntegrationRule(et, 2).points)
    u = fast.state_vector
    r_fast, r_ref = _residual(fast, u), _residual(ref, u)
    assert np.linalg.norm(r_fast - r_ref) <= 1e-12 * np.linalg.norm(r_ref)
    d = u.CreateVector()
    d.FV().NumPy()[:] = np.random.default_rng(3).standard_normal(len(d))
    k_fast, k_ref = _tangent_times(fast, u, d), _tangent_times(ref, u, d)
    assert np.linalg.norm(k_fast - k_ref) <= 1e-12 * np.linalg.norm(k_ref)


def test_the_symbolic_tangent_in_3d_is_the_residual_s_derivative():
    """K(u) d against (R(u + h d) - R(u - h d)) / 2h on the free dofs (error O(h²))."""
    mech = _block(*_mesh(3))
    u = mech.state_vector
    d = u.CreateVector()
    d.FV().NumPy()[:] = np.random.default_rng(4).standard_normal(len(d)) * mech.free
    h = 1e-6
    plus, minus = u.CreateVector(), u.CreateVector()
    plus.data = u + h * d
    minus.data = u - h * d
    fd = (_residual(mech, plus) - _residual(mech, minus)) / (2 * h)
    kd = _tangent_times(mech, u, d)
    free = mech.free
    err = np.linalg.norm(kd[free] - fd[free]) / np.linalg.norm(fd[free])
    assert err < 1e-7, err
