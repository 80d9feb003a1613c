"""``--model auto``: model only what the scene requires.

The first analysis is run with the linear model on the initial design at the full load; if the
Green–Lagrange strain (Frobenius norm of ``E = ½(∇u + ∇uᵀ + ∇uᵀ∇u)``) stays below ``threshold``
(1 % by default) at 99 % of the integration points, the small-strain assumption holds and the
run stays linear; otherwise it switches to the Neo-Hookean model.  The 99th percentile, not
the maximum, decides: the corner of a load patch or a clamp is singular in linear elasticity
and would otherwise always vote "nonlinear" on a fine mesh.  Both figures are recorded.  The choice, the
measured strain and the reason are recorded in summary.json.
"""
from __future__ import annotations


import numpy as np

STRAIN_THRESHOLD = 0.01


def green_lagrange_norms(mech) -> np.ndarray:
    """Frobenius norm of the Green–Lagrange strain of ``mech.gfu`` at every integration point
    of the mechanics block's quadrature rule."""
    from ngsolve import QUAD, TRIG, VOL, Grad, InnerProduct, sqrt

    from .physics.materials import green_lagrange

    E = green_lagrange(Grad(mech.gfu))
    pts = mech.mesh.MapToAllElements({TRIG: mech.rules[TRIG], QUAD: mech.rules[QUAD]}, VOL)
    return np.asarray(sqrt(InnerProduct(E, E))(pts)).ravel()


def choose_model(case, params, threshold: float = STRAIN_THRESHOLD):
    """Return ``(params with the chosen model, record)`` for ``params.model == 'auto'``."""
    from .case import build_problem
    from .runner import initial_design

    lin = params.replace(model="linear")
    problem = build_problem(case, lin)
    sched = lin.schedule.schedule()
    problem.apply_schedule(*sched.values(0))
    problem.evaluate(initial_design(problem), gradients=False)
    norms = green_lagrange_norms(problem.mech)
    strain, largest = float(np.percentile(norms, 99.0)), float(norms.max())
    chosen = "linear" if strain < threshold else "neohookean"
    reason = (f"Green-Lagrange strain of the first linear analysis (99th percentile) is {strain:.3g} "
              f"{'<' if chosen == 'linear' else '>='} {threshold:g}: "
              + ("small strains, the linear model suffices" if chosen == "linear"
                 else "finite strains, the Neo-Hookean model is needed"))
    record = {"requested": "auto", "chosen": chosen, "strain_p99": strain, "strain_max": largest,
              "threshold": threshold, "reason": reason}
    return params.replace(model=chosen), record
