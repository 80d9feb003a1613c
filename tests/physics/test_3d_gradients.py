"""Adjoint gradients of the whole 3D chain against central finite differences.

``x -> Helmholtz filter -> projection (β = 2) -> ρ̄ -> [Darcy pressure p] -> SIMP mechanics u ->
responses`` on a tiny Netgen tetrahedral mesh and a tiny structured hexahedral one (P1), for the
linear, Neo-Hookean and Wang models, loaded by a force on the end face, by the Darcy pressure as
a fixed body load, or by the Darcy pressure as a follower load.  The responses: the compliance
(of the force, or of the fixed Darcy load with its load term through p), the output displacement
at the end face against an output spring, and the strain energy (follower load: no compliance).

The reference is :func:`pacto_ng.core.check_gradient` with the five-point stencil at h = 1e-4
(error O(h⁴)), as ``pacto check-gradients`` does (pacto_ng/gradcheck.py), Newton to 1e-12 of the
load, and the tolerance 1e-6 of tests/gradients/test_nonlinear_gradients.py.  With the two-point
stencil at h = 1e-5 the Newton-solved responses showed their noise: hex, linear material under
the follower load (solved by Newton in 3D), 3.2e-7 at h = 1e-5, against 1.0e-8 at h = 1e-4 and
1.0e-6 at h = 1e-3 (the h² truncation).  The loads give end deflections of 5.6 - 8.9 % of the
length (printed), so that the nonlinear models are away from their linear limit.  Measured
worst relative errors: 1.0e-9 (hexahedra, Neo-Hookean, follower load, strain energy); the linear
material's element-matrix route (from the second design on) 9e-10; most others 1e-12 - 2e-11.

The energies are those a run builds (:func:`~pacto_ng.physics.energy.make_energy`), so that the
routes a run takes are the ones checked.  This file checks the tetrahedral mesh,
test_3d_gradients_hex.py the hexahedral one.
"""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng.core import Chain
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import Compliance, darcy_body, darcy_follower
from pacto_ng.physics.loads import PointLoad, Port
from pacto_ng.physics.energy import make_energy
from pacto_ng.physics.mechanics import Field, Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.responses import StrainEnergy, compliance, output_displacement
from small_cases import chain_fd

pytestmark = pytest.mark.usefixtures("one_thread")

L, W, D = 1.0, 0.4, 0.3
E1, E0, NU = 3e9, 3e3, 0.4
TOL = 1e-6
FORCE = 2e5  # N on the end face
P_IN = 2e6  # Pa at the inlet face


def mesh_of(kind):
    """``(mesh, names)``: the L x W x D box as Netgen tetrahedra (maxh 0.15) or 8 x 3 x 2
    structured hexahedra, with the names of its clamped face (x = 0), end face (x = L), Darcy
    inlet (y = 0) and zero-pressure face (y = W)."""
    if kind == "tet":
        from netgen.occ import X, Y, Box, OCCGeometry
        from ngsolve import Mesh

        box = Box((0, 0, 0), (L, W, D))
        box.faces.Min(X).name = "clamp"
        box.faces.Max(X).name = "end"
        box.faces.Min(Y).name = "inlet"
        box.faces.Max(Y).name = "zero"
        mesh = Mesh(OCCGeometry(box, dim=3).GenerateMesh(maxh=0.15))
        return mesh, {"clamp": "clamp", "end": "end", "inlet": "inlet", "zero": "zero"}
    from ngsolve.meshes import MakeStructured3DMesh

    mesh = MakeStructured3DMesh(hexes=True, nx=8, ny=3, nz=2,
                                mapping=lambda x, y, z: (L * x, W * y, D * z))
    return mesh, {"clamp": "back", "end": "front", "inlet": "left", "zero": "right"}


def energy(model):
    """``(energy, guard, linear)`` as a run builds them (pacto_ng/physics/energy.py: SIMP p = 3,
    with the declarations that choose the fast routes)."""
    from ngsolve import Parameter

    from pacto_ng.params import Parameters

    return make_energy(Parameters(model=model, E1=E1, E0=E0, nu=NU), Parameter(3.0))


def chain_of(kind, model, load, order=1):
    """The chain and the names of its checked responses (displacement and pressure of order
    ``order``, as a run builds them)."""
    mesh, n = mesh_of(kind)
    field = DesignField(mesh)
    blocks = [Embed(field), HelmholtzFilter(mesh, 0.3), HeavisideProjection(2.0),
              FixPassive(field)]
    e, guard, linear = energy(model)
    port = Port(n["end"], (0.0, 1.0, 0.0), spring=1e6)
    kw = dict(order=order, energy=e, supports=Supports(clamp=(n["clamp"],)), guard=guard,
              linear=linear, springs=port.springs(), newton=NewtonSettings(rtol=1e-12))
    if load == "force":
        mech = Mechanics(mesh, loads=(PointLoad(n["end"], (0.0, FORCE, 0.0)),), **kw)
        responses = [compliance(mech)]
    else:
        dar = DarcyPressure(mesh, inlet=n["inlet"], zero=n["zero"], p_in=P_IN, delta_s=0.1,
                            order=order)
        blocks.append(dar)
        extra = ({"body": darcy_body("p")} if load == "fixed"
                 else {"residual_density": darcy_follower("p", e.gamma if model == "wang"
                                                          else None)})
        mech = Mechanics(mesh, fields=("rho_bar", Field("p", dar.fes)), **extra, **kw)
        responses = [Compliance(mech, dar) if load == "fixed" else StrainEnergy(mech)]
    responses.append(output_displacement(mech, port))
    chain = Chain(blocks + [mech] + responses)
    return field, mech, chain, [r.output for r in responses]


def check_chain(kind, model, load, order=1):
    """The worst relative error of the chain's responses (asserted below TOL), after checking
    that the structure deforms visibly and that a linear material under the follower load is
    solved by Newton in 3D (its residual is quadratic in u there)."""
    field, mech, chain, names = chain_of(kind, model, load, order)
    assert mech.linear == (model == "linear" and load != "follower")
    x0 = np.random.default_rng(2).uniform(0.3, 0.7, field.n)
    tip = float(chain.forward(x=x0)["delta"])
    print(kind, order, mech.mesh.ne, model, load, "end deflection / L", tip / L)
    assert abs(tip) / L > 0.02
    errors = {}
    for name in names:
        errors[name] = chain_fd(chain, name, x0, h=1e-4, directions=2, stencil=4).rel_error
    print(errors)
    assert max(errors.values()) < TOL, errors
    # from the second design on, the element-matrix routes (scatter.py) were the ones checked
    if mech.linear:
        assert mech.assembly["linear_system"] == "element_matrices"
    for b in chain.blocks:
        if isinstance(b, DarcyPressure):
            assert b.route == "element_matrices"


@pytest.mark.parametrize("load", ["force", "fixed", "follower"])
@pytest.mark.parametrize("model", ["linear", "neohookean", "wang"])
def test_chain_gradients_on_tetrahedra(model, load):
    check_chain("tet", model, load)
