"""Adjoint gradients of compliance and strain energy through every mechanics model, checked
against central finite differences (relative error < 1e-6) on the small cantilever of cases/cantilever.py
(1.0 x 0.25 m, clamped left edge, 2e5 N spread over 0.05 m of the right edge, E1 = 3e9,
E0 = 3e3, ν = 0.4, t = 0.1 m: tip rotations of ~0.5 rad, far from linear).

The chain is x -> [Helmholtz filter -> projection β = 2] -> ρ̄ -> u -> (f·u, ∫φ).  Fast by
default: P1 triangles (with and without filter) and Q2 quads with filter; the other
combinations carry the ``slow`` mark.
"""
import numpy as np
import pytest

from nonlinear_setup import MODELS, cantilever, cantilever_mesh
from pacto_ng.core import Chain, check_gradient
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import HeavisideProjection, HelmholtzFilter, IdentityFilter
from pacto_ng.interpolation import heaviside_np
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.responses import StrainEnergy, compliance


pytestmark = pytest.mark.usefixtures("one_thread")


TOL = 1e-6
SETTINGS = NewtonSettings(rtol=1e-12, initial_increment=0.25)
FAST = {("trig", 1, False), ("trig", 1, True), ("quad", 2, True)}


def chain_for(mesh, mech, filtered):
    f = DesignField(mesh)
    if filtered:
        blocks = [Embed(f), HelmholtzFilter(mesh, 0.1), HeavisideProjection(2.0), FixPassive(f)]
    else:
        blocks = [Embed(f), IdentityFilter(output="rho_bar")]
    return f, Chain(blocks + [mech, compliance(mech), StrainEnergy(mech)])


def check(chain, x0, names=("compliance", "se")):
    errors = {}
    for name in names:
        fun = lambda x: chain.forward(x=x)[name]

        def grad(x):
            chain.forward(x=x)
            return chain.gradient(name)

        errors[name] = check_gradient(fun, grad, x0, h=1e-5, directions=2).rel_error
    return errors


def _cases():
    for model in MODELS:
        for kind, order in (("trig", 1), ("trig", 2), ("quad", 1), ("quad", 2)):
            for filtered in (False, True):
                marks = () if (kind, order, filtered) in FAST else (pytest.mark.slow,)
                yield pytest.param(model, kind, order, filtered, marks=marks,
                                   id=f"{model}-{kind}{order}-{'filter' if filtered else 'raw'}")


@pytest.mark.parametrize("model,kind,order,filtered", list(_cases()))
def test_adjoint_matches_finite_differences(model, kind, order, filtered):
    mesh = cantilever_mesh(kind)
    mech = cantilever(mesh, model, order, load=2e5, newton=SETTINGS)
    f, chain = chain_for(mesh, mech, filtered)
    x0 = np.random.default_rng(1).uniform(0.4 if filtered else 0.5, 0.9, f.n)
    chain.forward(x=x0)
    errors = check(chain, x0)
    assert max(errors.values()) < TOL, errors


def test_wang_gradient_through_gamma():
    """Densities where γ = H(ρ̄³; 0.001, 100) spans (0.1, 1): the adjoint must carry dγ/dρ̄.
    The part of the gradient that comes through γ is measured against the same model with γ
    frozen at its current values, so that the check cannot pass without it."""
    from ngsolve import GridFunction, L2

    mesh = cantilever_mesh("trig")
    x0 = np.random.default_rng(5).uniform(0.1, 0.6, mesh.ne)
    mech = cantilever(mesh, "wang", 1, load=2e4, newton=SETTINGS)
    f, chain = chain_for(mesh, mech, False)
    chain.forward(x=x0)
    gamma = heaviside_np(x0 ** 3, 0.001, 100.0)  # eq. 5.2 with the default β1, η1
    assert gamma.min() < 0.2 and gamma.max() > 0.99
    errors = check(chain, x0)
    assert max(errors.values()) < TOL, errors
    # the same derivative without dγ/dρ̄ differs by much more than the tolerance
    frozen = GridFunction(L2(mesh, order=0))
    frozen.vec.FV().NumPy()[:] = gamma
    mech2 = cantilever(mesh, "wang", 1, load=2e4, newton=SETTINGS, gamma_fn=lambda c: frozen)
    _, chain2 = chain_for(mesh, mech2, False)
    for name in ("compliance", "se"):
        chain.forward(x=x0)
        g = chain.gradient(name)
        chain2.forward(x=x0)
        g2 = chain2.gradient(name)
        assert chain.values[name] == pytest.approx(chain2.values[name], rel=1e-10)
        assert np.linalg.norm(g - g2) > 1e-3 * np.linalg.norm(g)


@pytest.mark.parametrize("model", ["neohookean", "wang"])
def test_plane_stress_gradients(model):
    """Plane-stress Neo-Hookean (F33 from S33 = 0) and its Wang interpolation."""
    mesh = cantilever_mesh("trig")
    mech = cantilever(mesh, model, 1, load=1e5, plane="stress", newton=SETTINGS)
    f, chain = chain_for(mesh, mech, True)
    x0 = np.random.default_rng(2).uniform(0.4, 0.9, f.n)
    chain.forward(x=x0)
    errors = check(chain, x0)
    assert max(errors.values()) < TOL, errors
