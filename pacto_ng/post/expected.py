"""The expected Δ of ``pacto analyse DIR``: the run's density design re-analysed with the
optimisation's own model along the sweep of pressures (:func:`expected_sweep`), the same for
the part's solid rounded onto the design mesh (:func:`rounded_sweep`, the first step of the
gap's decomposition), and the note when the final design's Δ depends on the load path
(:func:`load_path_note`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..physics.equilibrium import NewtonFailure
from ..threads import compute
from .part import Part
from .post3d import solid_elements
from .runs import thresholded_elements


def expected_sweep(problem, pressures, load, **design) -> list[dict]:
    """Δ of the density design (``x=`` design variables, or ``rho_bar=`` physical densities)
    with the optimisation's own model at every pressure (load factor P/load; Newton with load
    stepping, warm-started along the sweep; after a failure the larger pressures are not
    attempted).  A linear model's Δ is linear in P (the Darcy pressure is linear in P_in):
    one analysis at the run's load, scaled.  Leaves the problem at the last pressure."""
    mech = problem.mech
    warm = mech.state
    mech.set_state(replace(warm, u=np.zeros_like(warm.u), converged=False))
    if mech.linear:
        with compute():
            mech.target = 1.0
            delta = float(problem.chain.forward(**design)["delta"])
        return [dict(pressure=P, delta=delta * P / load, newton_iterations=1, converged=True)
                for P in pressures]
    rows, failed, settings = [], False, mech.settings
    sweep = replace(settings, sweep=True)
    with compute():
        for P in pressures:
            if failed:
                rows.append(dict(pressure=P, delta=None, newton_iterations=0, converged=False))
                continue
            mech.target = P / load
            try:
                vals = problem.chain.forward(**design)
                rows.append(dict(pressure=P, delta=float(vals["delta"]),
                                 newton_iterations=int(mech.result.iterations), converged=True))
                # the next pressure's tangents are near this one's (NewtonSettings.sweep)
                mech.settings = sweep
            except NewtonFailure as err:
                failed = True
                rows.append(dict(pressure=P, delta=None,
                                 newton_iterations=int(err.result.iterations), converged=False,
                                 load_reached=float(err.result.load_reached) * load))
    mech.settings = settings
    return rows


def load_path_note(rebuilt, summary, rtol: float = 1e-4):
    """A note when the final design's Δ loaded from rest (``rebuilt``) differs from the
    optimisation's (``summary``, its equilibrium reached by warm starts along the design
    history) by more than ``rtol``: the design has more than one equilibrium at that load,
    so Δ depends on the load path; None when they agree (or one is missing)."""
    if rebuilt is None or summary is None:
        return None
    scale = max(abs(float(summary)), abs(float(rebuilt)), 1e-300)
    if abs(float(rebuilt) - float(summary)) <= rtol * scale:
        return None
    return (f"the final design's output displacement depends on the load path: {rebuilt:.4g} m "
            f"loaded from rest, {float(summary):.4g} m in summary.json (the optimisation's "
            f"equilibrium, reached by warm starts along the design history): the design has "
            f"more than one equilibrium at this load, and Δ below is read on the path from rest")


def rounded_density(problem, part: Part) -> np.ndarray:
    """The part's solid as element densities of the design mesh: 1 where at least half of an
    element lies in the clipped solid the part was made from, else 0 (2D
    :func:`~.runs.thresholded_elements`, 3D :func:`~.post3d.solid_elements`)."""
    source = part.pieces[0]
    return (thresholded_elements(source) if part.dim == 2 else
            solid_elements(source.solid, problem.field.areas))


def rounded_sweep(problem, part: Part, pressures, load) -> list[dict] | None:
    """:func:`expected_sweep` of the part's solid rounded onto the design mesh
    (:func:`rounded_density`): the first step from the density design to the part, which
    the gap's decomposition (:mod:`.report`, ``gap_parts``) takes apart from remeshing and
    from the load on the walls.  None for two materials (one rounded field is not their
    design)."""
    if problem.n_design_fields != 1:
        return None
    rho = rounded_density(problem, part)
    rho[problem.field.solid] = 1.0
    rho[problem.field.void] = 0.0
    return expected_sweep(problem, pressures, load, rho_bar=rho)
