"""``pacto check-gradients``: central finite differences of the full chain of a case.

Every scalar the optimiser sees (objective and constraints) and every reported response
(output displacement, strain energy) is differentiated by the backward pass and compared with
central differences along random directions on a random design.  Unless the user chose a mesh,
a coarse one is used so that the check takes seconds.
"""
from __future__ import annotations


import numpy as np

from .case import build_problem
from .core import check_gradient
from .geometry_kinds import extent


#: the projection's β of a robust chain's check (:func:`check_case`)
ROBUST_BETA = 2.0


def coarse_params(case, params, explicit_mesh: bool):
    """A coarse mesh for the check unless the user gave one; tight Newton tolerance."""
    changes = {"newton_rtol": min(params.newton_rtol or 1e-12, 1e-12)}
    if not explicit_mesh:
        size = extent(case.make_geometry(params))
        if params.nelx > 0:
            nx = min(params.nelx, 24)
            ny = max(2, round(nx * params.nely / params.nelx))
            changes.update(nelx=nx, nely=ny)
            if params.nelz > 0:
                changes["nelz"] = max(2, round(nx * params.nelz / params.nelx))
        elif size is not None:
            changes["maxh"] = max(params.maxh, size / 8)
    return params.replace(**changes)


def check_case(case, params, *, seed: int = 0, quiet: bool = False, explicit_mesh: bool = False,
               h: float = 1e-4) -> float:
    """Worst relative error over every checked response.

    Five-point central differences (error O(h⁴)) with ``h = 1e-4``: Newton stops at a residual
    of ~1e-12 of the load, and that noise of the responses, divided by h, must stay well below
    the tolerance.  With the three-point stencil it did not: the strain energy of the
    pressure-actuated cases, along random directions where its derivative is 1e3-5e4 times
    smaller than the sum of its terms' magnitudes, came out 1.5e-5 to 3.9e-5 off at every h
    (measured 2026-12-01; the five-point stencil at h = 1e-4 gives 9e-7 on the same
    directions).  Directions with such cancellation (factor > 100) are drawn again: along them
    the check measures the finite difference's error, not the gradient.
    """
    params = coarse_params(case, params, explicit_mesh)
    problem = build_problem(case, params)
    sched_beta = params.beta_max if params.beta_max > 0 else params.beta
    if problem.objective_terms:
        # a robust chain's eroded design (threshold η + Δη) of a random field ρ̃ ≈ 0.5 is
        # nearly void at a sharp β, where a hyperelastic equilibrium under the pressure does
        # not exist (pa-inverter, Neo-Hookean, β 64: Newton stops at load factor 0.054): β 2
        sched_beta = min(sched_beta, ROBUST_BETA)
    problem.apply_schedule(params.penal, sched_beta, 1.0)
    rng = np.random.default_rng(seed)
    n = problem.n_design * problem.n_design_fields
    x0 = rng.uniform(0.3, 0.7, n)
    names = [problem.objective] + problem.constraints + [r for r in problem.reports
                                                          if r != problem.objective]
    # every response's check draws the same first directions (one seed): the perturbed designs
    # are analysed once, and their responses kept for the checks of the others
    analysed: dict[bytes, dict[str, float]] = {}

    def responses(x):
        key = x.tobytes()
        if key not in analysed:
            out = problem.chain.forward(x=x)
            analysed[key] = {nm: float(out[nm]) for nm in names}
        return analysed[key]

    worst = 0.0
    for name in names:
        fun = lambda x, nm=name: responses(x)[nm]

        def grad(x, nm=name):
            problem.chain.forward(x=x)
            return np.asarray(problem.chain.gradient(nm))

        res = check_gradient(fun, grad, x0, h=h, directions=3, seed=seed, stencil=4,
                             max_cancellation=100.0)
        worst = max(worst, res.rel_error)
        if not quiet:
            print(f"  {case.name}/{params.model}: d({name})/dx  {res}  "
                  f"[{problem.mesh.ne} elements, order {problem.params.order}]")
    return worst
