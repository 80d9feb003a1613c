"""Finite-difference checks of the chain with the Darcy pressure as a follower load (docs/theory.md §4).

x -> Embed -> HelmholtzFilter -> HeavisideProjection -> FixPassive -> DarcyPressure ->
Mechanics (residual density ``-cof(F)∇p``: unsymmetric tangent, transposed adjoint, and
``λᵀ ∂R/∂p`` in the backward pass) -> output displacement, strain energy, -Δ/SE with an output
spring.  Neo-Hookean and Wang, triangles and quads, Newton rtol 1e-12, load sensitivity on.
Central differences along random directions (:func:`pacto_ng.core.check_gradient`).
"""
from __future__ import annotations

import numpy as np
import pytest

from small_cases import PA_H, PA_L, chain_fd, pa_chain, small_pa_layout, small_pa_mesh
from pacto_ng.interpolation import simp_cf
from pacto_ng.physics.darcy import DarcyPressure
from pacto_ng.physics.darcy_load import darcy_follower
from pacto_ng.physics.loads import PointLoad, Port, Spring
from pacto_ng.physics.materials import jacobian, neohookean_energy
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.wang import wang_model

pytestmark = pytest.mark.usefixtures("one_thread")

L, H = PA_L, PA_H  # the small pa-inverter of tests/small_cases.py


def _model(name):
    modulus = lambda c: simp_cf(c["rho_bar"], 3e3, 3e8, 3.0)
    if name == "wang":
        return wang_model(modulus, 0.4, "strain", "rho_bar", 3.0)
    return (lambda G, c: neohookean_energy(G, modulus(c), 0.4)), (lambda G, c: jacobian(G))


def _chain(kind, model):
    mesh = small_pa_mesh(kind)
    dar = DarcyPressure(mesh, inlet="inlet", zero="zero", p_in=2e6, order=1)
    energy, guard = _model(model)
    mech = Mechanics(mesh, order=1, energy=energy, fields=("rho_bar", dar.field()),
                     supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
                     springs=(Spring("output", 1e4, (1.0, 0.0)),),
                     residual_density=darcy_follower("p"), thickness=1e-3, guard=guard,
                     newton=NewtonSettings(rtol=1e-12))
    chain, x0 = pa_chain(mesh, dar, mech)
    return chain, dar, mech, x0


def _fd(chain, name, x0):
    return chain_fd(chain, name, x0, h=1e-5, directions=3)


@pytest.mark.parametrize("kind", ["trig", "quad"])
@pytest.mark.parametrize("model", ["neohookean", "wang"])
def test_follower_chain_gradient(kind, model):
    """-Δ/SE, Δ and SE through the whole chain; then without the load sensitivity the check
    must fail (the follower term's ``λᵀ ∂R/∂p`` is the only way p enters the residual)."""
    chain, dar, mech, x0 = _chain(kind, model)
    chain.forward(x=x0)
    assert not mech.symmetric and mech.result.converged
    assert mech.result.iterations > 1  # really nonlinear
    errs = {name: _fd(chain, name, x0).rel_error for name in ("objective", "delta", "se")}
    print(kind, model, errs)
    assert max(errs.values()) < 1e-6, errs
    dar.sensitivity = False
    off = _fd(chain, "objective", x0).rel_error
    print("without load sensitivity", off)
    assert off > 0.05


# -- the same through the case machinery (load_type=follower) ----------------------------------
def _case(objective="mechanism", pressure=True):
    from pacto_ng.case import Case
    from pacto_ng.setup import Pressure, Setup
    from pacto_ng.params import Parameters

    defaults = Parameters(model="neohookean", nelx=20, nely=10, E1=3e8, E0=3e3, nu=0.4,
                          thickness=1e-3, volfrac=0.4, filter_radius=0.002, beta=2.0,
                          load=2e6, k_out=1e4, delta_s=0.002, load_type="follower",
                          newton_rtol=1e-12)
    setup = lambda p: Setup(
        supports=Supports(clamp=("fixed",), fix_y=("symmetry",)),
        springs=(Spring("output", p.k_out, (1.0, 0.0)),), port=Port("output", (-1.0, 0.0)),
        solid=("block",), objective=objective,
        loads=() if pressure else (PointLoad("output", (-p.load * 1e-6, 0.0)),),
        pressure=Pressure(inlet=("inlet",), zero=("zero",)) if pressure else None)
    return Case(name="follower-test", summary="small pa-inverter", source="this test",
                defaults=defaults, geometry=lambda p: small_pa_layout(), setup=setup, load_unit="Pa")


@pytest.mark.parametrize("model", ["neohookean", "wang"])
def test_build_problem_follower(model):
    """``load_type=follower`` in :func:`pacto_ng.case.build_problem`: an unsymmetric Mechanics
    with the follower residual density and no fixed body load; FD check of every response."""
    from pacto_ng.case import build_problem

    case = _case()
    problem = build_problem(case, case.defaults.replace(model=model))
    mech = problem.mech
    assert not mech.symmetric and mech.body is None and mech.has_residual_density
    x0 = np.random.default_rng(4).uniform(0.3, 0.7, problem.field.n)
    problem.chain.forward(x=x0)
    assert mech.result.converged and mech.result.iterations > 1
    for name in [problem.objective] + problem.constraints + problem.reports:
        err = _fd(problem.chain, name, x0).rel_error
        print(model, name, err)
        assert err < 1e-6, (name, err)


def test_build_problem_follower_input_errors():
    """Compliance is not defined with a follower load; a case without a pressure load has
    nothing to follow."""
    from pacto_ng.case import build_problem
    from pacto_ng.params import InputError

    case = _case()
    with pytest.raises(InputError, match="compliance is not defined for a follower load"):
        build_problem(case, case.defaults.replace(objective="compliance"))
    case = _case(pressure=False)
    with pytest.raises(InputError, match="has no pressure load"):
        build_problem(case, case.defaults)
