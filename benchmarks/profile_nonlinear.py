"""Where the time of a nonlinear pressure-actuated optimisation iteration goes.

    python -m benchmarks.profile_nonlinear [--case pa-inverter] [--model neohookean]
        [--load 1e6] [--iterations 2] [--maxh 0.004] [--order 1]

Runs a short optimisation of the case (its defaults, the chosen model) under cProfile and
charges the time of NGSolve's built-in calls to what calls them: the Darcy solve (assembly,
factorisation, solve), the Newton iterations (residual, tangent assembly, factorisation, J
guard), the adjoint solves and sensitivity forms of the mechanics block, the responses
(strain energy and its derivatives), the filter, MMA.  The first ``WARMUP`` = 2 iterations run
before the profile starts: their one-offs (Newton from u = 0, and at the second design the
element matrices of the design-linear blocks, one assembly per colour and term) are not what
the next hundred iterations cost.  The table reports per-iteration means over the profiled
iterations, 2 and 3 counted from 0 (the Neo-Hookean pa-inverter at 1e6 Pa from the default
start has its first Newton failure at iteration 4, where adaptive load continuation takes over
in a run).  mmapy is imported before the profile starts (its import took 0.15 s, once per
process: in a 3-iteration mean it made the MMA update look like a third of an iteration).  cProfile's own overhead falls on the
Python-heavy parts, MMA most (mmapy's subproblem makes ~25 000 Python calls per update): one
update at 2900 variables took 13-16 ms outside the profiler (7 updates, 2026-12-02).
"""
from __future__ import annotations

import argparse
import cProfile
import pstats
import time

# (category, file fragment, function name) -> first match wins; order matters
CATEGORIES = [
    ("Darcy: assembly + factorisation + solve", "darcy.py", "forward"),
    ("Darcy: adjoint + sensitivity", "darcy.py", "backward"),
    ("Newton: residual (Apply)", "newton.py", "residual"),
    ("load norm (Apply at u = 0)", "equilibrium.py", "load_norm"),
    ("Newton: tangent assembly + factorisation", "newton.py", "assemble_tangent"),
    ("adjoint: tangent at the converged state (assembly + factorisation)", "adjoint.py",
     "_ensure_tangent"),
    ("Newton: det F guard", "equilibrium.py", "admissible"),
    ("Newton: linear solves", "equilibrium.py", "solve_tangent"),
    ("mechanics adjoint solve", "adjoint.py", "adjoint"),
    ("mechanics sensitivity forms (λᵀ∂R/∂ρ)", "adjoint.py", "backward"),
    ("strain energy: value", "responses.py", "forward"),
    ("strain energy: ∂SE/∂u, ∂SE/∂ρ", "responses.py", "backward"),
    ("filter (Helmholtz)", "filters.py", ""),
    ("MMA update", "mma.py", "update"),
]


#: iterations run before the profile starts: the first (Newton from u = 0) and the second
#: (where the element matrices of the design-linear blocks are built) are one-offs
WARMUP = 2


def _inclusive(stats, frag, name):
    """Cumulative time of ``name`` in a file matching ``frag``; for the mechanics methods
    ``residual`` and ``assemble_tangent`` only the calls made from the file ``frag``."""
    tot = 0.0
    for (fn, _line, func), (_cc, _nc, _tt, ct, callers) in stats.stats.items():
        if name in ("residual", "assemble_tangent") and fn.endswith("equilibrium.py") \
                and func == name:
            tot += sum(v[3] for (cf, _l, _f), v in callers.items() if frag in cf)
        elif name not in ("residual", "assemble_tangent") and frag in fn \
                and (not name or func == name):
            tot += ct
    return tot


def profile(case_name="pa-inverter", model="neohookean", load=1e6, iterations=2, maxh=0.004,
            order=1, threads=2, warmup=WARMUP):
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.optimize.driver import LoopState, optimize
    from pacto_ng.initial import initial_design

    case = get_case(case_name)
    total = warmup + iterations
    params = case.defaults.with_overrides({"model": model, "load": str(load), "maxh": str(maxh),
                                           "order": str(order), "iterations": str(total)})
    import mmapy  # noqa: F401  (its import, ~0.15 s once per process, is not an iteration's)

    with compute(threads=threads):
        problem = build_problem(case, params)
        state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
        schedule = params.schedule.schedule()
        if warmup:
            optimize(problem, schedule, iterations=warmup, tol=0.0, method="mma",
                     move=params.move, state=state)
        first = len(state.history)
        prof = cProfile.Profile()
        t0 = time.perf_counter()
        prof.enable()
        res = optimize(problem, schedule, iterations=total, tol=0.0,
                       method="mma", move=params.move, state=state)
        prof.disable()
        wall = time.perf_counter() - t0
    stats = pstats.Stats(prof)
    # the forward/backward functions nest (assemble_tangent inside Newton inside forward):
    # use leaf-level categories; the mechanics "backward" includes its adjoint, subtract it
    rows = {c: _inclusive(stats, f, n) for c, f, n in CATEGORIES}
    rows["mechanics sensitivity forms (λᵀ∂R/∂ρ)"] -= rows["mechanics adjoint solve"]
    rows["mechanics adjoint solve"] -= rows[
        "adjoint: tangent at the converged state (assembly + factorisation)"]
    n = len(state.history) - first
    newton = sum(h["newton"] for h in state.history[first:])
    out = dict(case=case_name, model=model, load=load, iterations=n, first=first, wall=wall,
               per_iteration=wall / n, newton_per_iteration=newton / n,
               elements=problem.mesh.ne, dofs=problem.mech.fes.ndof, stopped=res.stopped,
               rows={k: v / n for k, v in rows.items()})
    out["other"] = out["per_iteration"] - sum(out["rows"].values())
    return out


def markdown(r):
    lines = [f"{r['case']}, {r['model']}, load {r['load']:g}, {r['elements']} elements, "
             f"{r['dofs']} displacement dofs: iterations {r['first']}-"
             f"{r['first'] + r['iterations'] - 1} profiled (counted from 0, as in the run's "
             f"log), "
             f"{r['per_iteration']:.3f} s per iteration (mean), "
             f"{r['newton_per_iteration']:.1f} Newton iterations per optimisation iteration.", "",
             "| part | s per iteration | share |", "|---|---|---|"]
    items = sorted(r["rows"].items(), key=lambda kv: -kv[1]) + [("other (chain, numpy, I/O)",
                                                                 r["other"])]
    for k, v in items:
        lines.append(f"| {k} | {v:.3f} | {100 * v / r['per_iteration']:.0f} % |")
    if r["stopped"] == "newton":
        lines += ["", "**A Newton failure stopped the run inside the profiled iterations: the "
                  "table includes the failed attempt.**"]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="pa-inverter")
    ap.add_argument("--model", default="neohookean")
    ap.add_argument("--load", type=float, default=1e6)
    ap.add_argument("--iterations", type=int, default=2,
                    help="iterations profiled, after the warm-up")
    ap.add_argument("--maxh", type=float, default=0.004)
    ap.add_argument("--order", type=int, default=1)
    args = ap.parse_args(argv)
    r = profile(args.case, args.model, args.load, args.iterations, args.maxh, args.order)
    print(markdown(r))
    return r


if __name__ == "__main__":
    main()


def strain_energy_ab(overrides_list, repeat=7):
    """Before/after of the one library change this study made: ∂SE/∂u of the strain-energy
    response as a LinearForm of ``dens.Diff(u, v)`` (before) against ``Apply`` of a
    ``Variation`` form of the same energy (after, pacto_ng/responses.py), timed interleaved in
    one process on the same state; also their largest relative difference."""
    import statistics

    import numpy as np
    from ngsolve import Grad, LinearForm

    out = []
    for label, problem in _evaluated(overrides_list, 2):
        mech = problem.mech
        se = next(b for b in problem.chain.blocks if type(b).__name__ == "StrainEnergy")
        dens = mech.thickness * mech.energy(Grad(se.gfu), mech.coeffs)
        old = LinearForm(mech.fes)
        old += dens.Diff(se.gfu, mech.fes.TestFunction()).Compile() * mech.DX
        old.Assemble()
        se._energy_form.Apply(se.gfu.vec, se._du_vec)
        a, b = old.vec.FV().NumPy(), se._du_vec.FV().NumPy()
        diff = float(np.max(np.abs(a - b)) / np.max(np.abs(a)))
        t_old, t_new = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            old.Assemble()
            t_old.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            se._energy_form.Apply(se.gfu.vec, se._du_vec)
            t_new.append(time.perf_counter() - t0)
        out.append(dict(label=label, elements=problem.mesh.ne, dofs=mech.fes.ndof,
                        before=statistics.median(t_old), after=statistics.median(t_new),
                        diff=diff))
    return out


def ab_markdown(rows):
    lines = ["| problem | elements | dofs | ∂SE/∂u before (LinearForm of Diff) [s] | "
             "after (Variation Apply) [s] | speed-up | max rel. difference |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['label']} | {r['elements']} | {r['dofs']} | {r['before']:.4f} | "
                     f"{r['after']:.4f} | {r['before'] / r['after']:.2f}x | {r['diff']:.1e} |")
    return "\n".join(lines)


def _ab(before, after, repeat):
    """Median times of two callables, interleaved (before, after, before, ...)."""
    import statistics

    before(), after()
    tb, ta = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        before()
        tb.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        after()
        ta.append(time.perf_counter() - t0)
    return statistics.median(tb), statistics.median(ta)



def _evaluated(overrides_list, threads):
    """``(label, problem)`` per ``(label, overrides)``: the pa-inverter with those overrides,
    built and evaluated once at its initial design, inside NGSolve's TaskManager."""
    from pacto_ng.threads import compute

    from pacto_ng.case import build_problem, get_case
    from pacto_ng.initial import initial_design

    case = get_case("pa-inverter")
    for label, over in overrides_list:
        with compute(threads=threads):
            problem = build_problem(case, case.defaults.with_overrides(over))
            problem.evaluate(initial_design(problem))
            yield label, problem

def fast_paths_ab(overrides_list, repeat=7, threads=1):
    """Before/after of the library changes of the second performance round, timed interleaved
    in one process on the same state (median of ``repeat``), with their largest relative
    difference:

    * load norm of a design-dependent load on a stress-free energy: the residual at u = 0
      (``Apply`` of the energy plus the body load; before) against the assembled LinearForm of
      the loads (after);
    * element-wise field derivatives (λᵀ∂R/∂ρ of the mechanics block, ∂SE/∂ρ): a LinearForm
      of ``dens.Diff(ρ, q)`` (before) against the library's form (after): automatic
      differentiation in ρ (``FieldGradient``), or for linear mechanics the tangent's
      ``∂C/∂ρ``.
    """
    import numpy as np
    from ngsolve import Grad, LinearForm

    out = []
    for label, problem in _evaluated(overrides_list, threads):
        m = problem.mech
        rel = lambda a, b: float(np.max(np.abs(a - b)) / np.max(np.abs(b)))
        rows = []
        if m.assembly["load_norm"] == "load_vectors":
            zero, r = m.gfu.vec.CreateVector(), m.gfu.vec.CreateVector()
            zero[:] = 0.0
            res = {}

            def old_norm():  # the residual at u = 0: Apply of the energy + the body load
                m.residual(zero, r, 1.0)
                res["old"] = float(np.linalg.norm(r.FV().NumPy()[m.free]))

            def new_norm():
                res["new"] = m.load_norm(1.0)

            tb, ta = _ab(old_norm, new_norm, repeat)
            rows.append(("load norm", tb, ta, abs(res["old"] - res["new"]) / res["old"]))
        rho = m.fields[0]
        q = rho.space.TestFunction()
        m.lam.vec.FV().NumPy()[:] = np.where(m.free, np.random.default_rng(0).standard_normal(
            len(m.free)), 0.0)
        dens = m.volume_density(m.gfu).Diff(m.gfu, m.lam)
        old = LinearForm(rho.space)
        old += dens.Diff(rho.gf, q).Compile() * m.DX
        got = {}

        def new():
            got["sens"] = m.field_sensitivity(rho.name)

        tb, ta = _ab(old.Assemble, new, repeat)
        rows.append(("λᵀ∂R/∂ρ form", tb, ta, rel(got["sens"], old.vec.FV().NumPy())))
        se = next(b for b in problem.chain.blocks if type(b).__name__ == "StrainEnergy")
        sdens = m.thickness * m.energy(Grad(se.gfu), m.coeffs)
        old = LinearForm(rho.space)
        old += sdens.Diff(rho.gf, q).Compile() * m.DX
        new = se._dfield[rho.name]
        if m.linear_system is not None and se.uses_linear_system:
            m.linear_system.prepare_fields()
        tb, ta = _ab(old.Assemble, new.Assemble, repeat)
        rows.append(("∂SE/∂ρ form", tb, ta, rel(new.vec.FV().NumPy(), old.vec.FV().NumPy())))
        for name, tb, ta, d in rows:
            out.append(dict(label=label, part=name, elements=problem.mesh.ne, before=tb,
                            after=ta, diff=d))
    return out


def fast_ab_markdown(rows):
    lines = ["| problem | part | elements | before [s] | after [s] | speed-up | max rel. difference |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['label']} | {r['part']} | {r['elements']} | {r['before']:.4f} | "
                     f"{r['after']:.4f} | {r['before'] / r['after']:.2f}x | {r['diff']:.1e} |")
    return "\n".join(lines)
