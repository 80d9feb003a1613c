"""Finite-difference checks of the Darcy pressure block and of the coupled Darcy–mechanics chain.

x -> Embed -> HelmholtzFilter -> HeavisideProjection -> FixPassive -> DarcyPressure -> Mechanics
(linear, fields rho_bar and p) -> responses, on small triangle and quad meshes at orders 1 and 2.
Central differences along random directions (:func:`pacto_ng.core.check_gradient`).
"""
from __future__ import annotations

import numpy as np
import pytest

from small_cases import PA_H, PA_L, small_pa_mesh
from pacto_ng.core import Chain, check_gradient
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import HeavisideProjection, HelmholtzFilter
from pacto_ng.interpolation import simp2_cf, simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import Compliance, darcy_body
from pacto_ng.physics.loads import Port, Spring
from pacto_ng.physics.materials import linear_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.responses import MechanismRatio, StrainEnergy, output_displacement

pytestmark = pytest.mark.usefixtures("one_thread")

L, H = PA_L, PA_H  # the small pa-inverter of tests/small_cases.py


def _fd(chain, name, x0, wrt="x", **fixed):
    def fun(x):
        return chain.forward(**{wrt: x}, **fixed)[name]

    def grad(x):
        chain.forward(**{wrt: x}, **fixed)
        return chain.gradient(name, wrt=wrt)

    return check_gradient(fun, grad, x0, h=1e-5, directions=3)


@pytest.mark.parametrize("kind", ["netgen", "quads"])
@pytest.mark.parametrize("order", [1, 2])
def test_pressure_block_gradient(kind, order):
    """ρ̄ -> p -> J(p) = c·p + ½·1e-4 pᵀMp, with p_out ≠ 0 (the drainage source depends on ρ̄ too)
    and the inlet Dirichlet values fixed; dJ/dp by hand in the test (c + 1e-4 M p)."""
    from ngsolve import BilinearForm, dx

    mesh = small_pa_mesh(kind)
    block = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e4, p_out=300.0, order=order)
    rng = np.random.default_rng(0)
    c = rng.normal(size=block.fes.ndof)
    u, v = block.fes.TnT()
    m = BilinearForm(u * v * dx).Assemble()

    def parts(rho):
        p = block.forward(rho)
        mp = p.CreateVector()
        mp.data = m.mat * p
        return p, mp

    def fun(rho):
        p, mp = parts(rho)
        return float(c @ p.FV().NumPy() + 0.5e-4 * p.InnerProduct(mp))

    def grad(rho):
        p, mp = parts(rho)
        return block.backward(c + 1e-4 * mp.FV().NumPy())[0]

    res = check_gradient(fun, grad, rng.uniform(0.1, 0.9, mesh.ne), h=1e-5, directions=4)
    assert res.rel_error < 1e-6, res  # measured 0.9e-8 .. 2.7e-8


def _chain(kind, order, sensitivity=True):
    mesh = small_pa_mesh(kind)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=order,
                        sensitivity=sensitivity)
    energy = lambda G, c: linear_energy(G, simp_cf(c["rho_bar"], 3e3, 3e9, 3.0), 0.4)
    mech = Mechanics(mesh, order=order, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), body=darcy_body("p"),
                     thickness=1e-3, linear=True)
    field = DesignField(mesh, solid=("block",))
    blocks = [Embed(field), HelmholtzFilter(mesh, 0.002), HeavisideProjection(2.0),
              FixPassive(field), dar, mech, Compliance(mech, dar),
              output_displacement(mech, Port("output", (-1.0, 0.0))), StrainEnergy(mech),
              MechanismRatio(scale=1.0)]
    x0 = np.random.default_rng(1).uniform(0.2, 0.8, field.n)
    return Chain(blocks), dar, x0


@pytest.mark.parametrize("kind", ["netgen", "quads"])
@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("response", ["compliance", "objective"])
def test_full_chain_gradient(kind, order, response):
    """Compliance f(p)·u and the mechanism ratio -Δ/SE (output spring) through the whole chain;
    then the same check with the load sensitivity switched off must fail: the p-path matters."""
    chain, dar, x0 = _chain(kind, order)
    vals = chain.forward(x=x0)
    assert vals["compliance"] > 0 and vals["se"] > 0 and vals["delta"] != 0
    assert _fd(chain, response, x0).rel_error < 1e-6  # measured 1e-10 .. 4e-9
    dar.sensitivity = False
    assert _fd(chain, response, x0).rel_error > 0.05  # measured 0.11 .. 0.76


def test_two_material_chain_gradient():
    """Two design fields with the two-material SIMP law (thesis eq. 6.1), the pressure driven by
    the first (solid/void) field, as in mm-gripper: FD check with respect to each field."""
    mesh = small_pa_mesh("quads")
    field = DesignField(mesh, solid=("block",))
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=1e5, order=1, inputs=("rho1",))
    energy = lambda G, c: linear_energy(G, simp2_cf(c["rho1"], c["rho2"], 3e2, 3e8, 3e9, 3.0), 0.4)
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho1", "rho2", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), body=darcy_body("p"),
                     thickness=1e-3, linear=True)
    blocks = []
    for i in ("1", "2"):
        blocks += [Embed(field, inputs=("x" + i,), output="r" + i),
                   HelmholtzFilter(mesh, 0.002, inputs=("r" + i,), output="rt" + i),
                   HeavisideProjection(2.0, inputs=("rt" + i,), output="rp" + i),
                   FixPassive(field, inputs=("rp" + i,), output="rho" + i)]
    blocks += [dar, mech, output_displacement(mech, Port("output", (-1.0, 0.0))),
               StrainEnergy(mech), MechanismRatio(scale=1.0), Compliance(mech, dar)]
    chain = Chain(blocks, inputs=("x1", "x2"))
    rng = np.random.default_rng(2)
    x1, x2 = rng.uniform(0.2, 0.8, field.n), rng.uniform(0.2, 0.8, field.n)
    for name in ("objective", "compliance"):
        assert _fd(chain, name, x1, wrt="x1", x2=x2).rel_error < 1e-6
        assert _fd(chain, name, x2, wrt="x2", x1=x1).rel_error < 1e-6


def test_neohookean_chain_gradient():
    """The deformation-independent Darcy load with a Neo-Hookean model (Newton rtol 1e-12)."""
    from pacto_ng.physics.materials import jacobian, neohookean_energy
    from pacto_ng.physics.newton import NewtonSettings

    mesh = small_pa_mesh("quads")
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=2e6, order=1)
    energy = lambda G, c: neohookean_energy(G, simp_cf(c["rho_bar"], 3e3, 3e8, 3.0), 0.4)
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),), body=darcy_body("p"),
                     thickness=1e-3, guard=lambda G, c: jacobian(G), linear=False,
                     newton=NewtonSettings(rtol=1e-12))
    field = DesignField(mesh, solid=("block",))
    chain = Chain([Embed(field), HelmholtzFilter(mesh, 0.002), HeavisideProjection(2.0),
                   FixPassive(field), dar, mech, Compliance(mech, dar),
                   output_displacement(mech, Port("output", (-1.0, 0.0))), StrainEnergy(mech),
                   MechanismRatio(scale=1.0)])
    x0 = np.random.default_rng(1).uniform(0.2, 0.8, field.n)
    chain.forward(x=x0)
    assert mech.result.converged and mech.result.iterations > 1  # really nonlinear
    for name in ("compliance", "objective"):
        assert _fd(chain, name, x0).rel_error < 1e-6  # measured 7e-9, 1e-9
