"""The Newton guard study: which guard check refused the steps that ended a continuation.

    python -m benchmarks.newton_guard CASE MODEL LOAD DENSITY [--set NAME=VALUE ...]
        [--nelx N --nely N] [--filtered]

Runs the analysis of ``pacto evaluate CASE --model MODEL --load LOAD --density DENSITY`` and
watches every admissibility test of Newton's line search: for each trial state it evaluates
the model's guard CF (``det F``; ``det(I + γ∇u)`` for Wang) at the quadrature points, the
vertices, the edge midpoints and the centroid of every element, split into void (ρ̄ < 0.5) and
solid.  When the continuation stops, the trials of its last failed Newton iteration (every
step length refused) say which check refused them.  Prints one JSON line: load factor reached,
the reason, for the last failed iteration the kinds of point that were non-positive in each
refused trial, whether a guard at the quadrature points alone would have accepted one of them,
and the lowest ``det F`` of the final equilibrium at the quadrature points and at the other
points (with the element, its ρ̄ and the point kind).
"""
from __future__ import annotations

import argparse
import json
import sys

import numpy as np


def point_kinds(et_key: str, n_quad: int) -> list[str]:
    """The kind of each guard point of one element (quadrature points first, as
    :func:`~pacto_ng.physics.quadrature.guard_rules` orders them)."""
    n_vert = 3 if et_key == "TRIG" else 4
    return (["quadrature point"] * n_quad + ["vertex"] * n_vert + ["edge midpoint"] * n_vert
            + ["centroid"])


def study(case_name, model, load, density, sets=(), nelx=None, nely=None, filtered=False):
    from ngsolve import QUAD, TRIG, VOL, Grad, GridFunction

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.evaluate import read_density
    from pacto_ng.physics.equilibrium import NewtonFailure
    from pacto_ng.physics.materials import jacobian
    from pacto_ng.physics.quadrature import guard_rules

    case = get_case(case_name)
    over = {"model": model, "load": str(load)}
    if nelx:
        over.update(nelx=str(nelx), nely=str(nely))
    for item in sets:
        k, v = item.split("=", 1)
        over[k] = v
    params = case.defaults.with_overrides(over)
    problem = build_problem(case, params)
    arr, filtered = read_density(density, problem, filtered=filtered)
    sched = params.schedule.schedule()
    problem.apply_schedule(*sched.final_values())
    mech = problem.mech
    mesh = mech.mesh
    et = QUAD if params.nelx > 0 else TRIG
    rules = guard_rules(mech.rules)
    n_quad = len(mech.rules[et].points)
    kinds = np.array(point_kinds("QUAD" if et == QUAD else "TRIG", n_quad))
    per_el = len(kinds)
    pts = mesh.MapToAllElements(rules, VOL)
    trial = GridFunction(mech.fes)
    if model == "wang":
        guard_cf = mech.energy.jacobian(Grad(trial), mech.coeffs).Compile()
    else:
        guard_cf = jacobian(Grad(trial)).Compile()
    detf_cf = jacobian(Grad(mech.gfu)).Compile()

    calls = []  # per admissibility test: (verdict, {(kind, region): min value})
    inner = mech.admissible

    def watched(vec):
        ok = inner(vec)
        trial.vec.data = vec
        vals = np.asarray(guard_cf(pts)).reshape(-1, per_el)
        rho = np.asarray(mech.coeffs[mech.inputs[0]].vec.FV().NumPy())
        bad = {}
        for region, rows in (("void", rho < 0.5), ("solid", rho >= 0.5)):
            sub = vals[rows]
            for kind in ("quadrature point", "vertex", "edge midpoint", "centroid"):
                m = float(np.min(sub[:, kinds == kind])) if sub.size else np.inf
                if not m > 0.0:
                    bad[f"{kind} in {region}"] = m
        calls.append((ok, bad))
        return ok

    mech.admissible = watched
    failure = None
    try:
        if filtered:
            problem.chain.forward(x=arr)
        else:
            rho = arr.copy()
            rho[problem.field.solid] = 1.0
            rho[problem.field.void] = 0.0
            problem.chain.forward(rho_bar=rho)
    except NewtonFailure as err:
        failure = err
    res = mech.result
    out = {"case": case_name, "model": model, "load": load, "density": density,
           "load_factor_reached": res.load_reached, "reason": res.reason,
           "newton_iterations": res.iterations}
    if failure is not None:
        # the last failed Newton iteration: the final run of refused trials
        tail = []
        for ok, bad in reversed(calls):
            if ok:
                break
            tail.append(bad)
        tail.reverse()
        out["last_failed_iteration"] = {
            "refused_trials": len(tail),
            "refused_by": sorted({k for bad in tail for k in bad}),
            "quadrature_points_alone_accept_a_trial": any(
                not any(k.startswith("quadrature") for k in bad) for bad in tail)}
    # where det F is lowest in the final equilibrium
    vals = np.asarray(detf_cf(pts)).reshape(-1, per_el)
    rho = np.asarray(mech.coeffs[mech.inputs[0]].vec.FV().NumPy())
    for label, cols in (("quadrature_points", kinds == "quadrature point"),
                        ("other_points", kinds != "quadrature point")):
        sub = np.where(cols[None, :], vals, np.inf)
        el, j = np.unravel_index(int(np.argmin(sub)), sub.shape)
        out[f"lowest_detF_{label}"] = {"J": float(sub[el, j]), "element": int(el),
                                       "rho_bar": float(rho[el]), "point": str(kinds[j])}
        neg = (vals[:, cols] <= 0).any(axis=1)
        out[f"elements_with_detF<=0_at_{label}"] = {"void": int(np.sum(neg & (rho < 0.5))),
                                                    "solid": int(np.sum(neg & (rho >= 0.5)))}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("case")
    ap.add_argument("model")
    ap.add_argument("load", type=float)
    ap.add_argument("density")
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--nelx", type=int)
    ap.add_argument("--nely", type=int)
    ap.add_argument("--filtered", action="store_true")
    a = ap.parse_args(argv)
    print(json.dumps(study(a.case, a.model, a.load, a.density, a.set, a.nelx, a.nely,
                           a.filtered)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
