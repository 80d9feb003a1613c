"""Run the performance and robustness benchmarks and regenerate their parts of the report.

    python -m benchmarks all [--quick] [--out docs/studies.md] [--plots docs]
    python -m benchmarks peer|trade|stability|profile|mbb [--quick] ...
    python -m benchmarks solvers_3d|iteration_3d|iteration_ratio|locking|limit_point|silicone|
        scaling|iterative_tolerance|contact [--out FILE]   (one at a time)

Each study writes one marked block of the report (``<!-- BEGIN name -->`` ... ``<!-- END name
-->``); the rest of the file (other engineers' sections) is kept as it is.  The default run
writes docs/studies.md and docs/*.png and takes 10-25 minutes on 2 cores; ``--quick`` (the
smoke run of ``pytest -m slow``, ~2 minutes) runs every study on its smallest set-up and
writes to a file in the temp folder unless ``--out`` is given, so that it never replaces the
full numbers.
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import sys
import tempfile
import time

STUDIES = ("peer", "trade", "stability", "profile", "mbb")
# Studies with their own command line and report block, run one at a time (not by `all`:
# they take 20-25 minutes each): `python -m benchmarks NAME` runs `benchmarks.NAME`.
STANDALONE = ("solvers_3d", "iteration_3d", "iteration_ratio", "locking", "limit_point",
              "silicone", "scaling", "iterative_tolerance", "contact")


def machine() -> str:
    cpu = "unknown"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import ngsolve
    import scipy

    from pacto_ng.threads import thread_count

    n = thread_count()

    load = os.getloadavg()
    return (f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC; "
            f"{os.cpu_count()} cores ({cpu}); load average at the start of the study "
            f"{load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} (1 / 5 / 15 min); Python "
            f"{platform.python_version()}, NGSolve {ngsolve.__version__}, SciPy "
            f"{scipy.__version__}; {n} NGSolve thread{'s' if n > 1 else ''}")


def replace_block(path: str, name: str, body: str) -> None:
    """Replace (or append) the block ``name`` of ``path``; re-read just before writing."""
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    text = open(path).read() if os.path.exists(path) else (
        "# Benchmarks\n\nMeasured by the scripts in `benchmarks/`; each section says how to "
        "regenerate it.\n")
    block = f"{begin}\n{body.rstrip()}\n{end}"
    pat = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    if pat.search(text):
        text = pat.sub(lambda _m: block, text)
    else:
        text = text.rstrip() + "\n\n" + block + "\n"
    with open(path, "w") as f:
        f.write(text)


def standalone(argv, name: str, title: str, doc: str, items, one, report) -> None:
    """The command line of a standalone study ``python3 -m benchmarks NAME [--out FILE]``:
    ``one(item)`` for each of ``items`` (printed as it comes), then the block
    ``benchmarks-NAME`` of ``--out`` (default docs/studies.md): ``title``, the command and
    the machine, the third paragraph of ``doc`` (the study's module docstring) and
    ``report(results)``."""
    from pacto_ng.threads import compute

    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--out", default=os.path.join("docs", "studies.md"))
    args = ap.parse_args(argv)
    mach = machine()
    print(f"[{name}] {mach}", flush=True)
    results = []
    with compute():
        for item in items:
            results.append(one(item))
            print(results[-1], flush=True)
    body = (f"## {title}\n\n`python3 -m benchmarks {name}` ({mach}).  "
            + doc.split("\n\n")[2].replace("\n", " ") + "\n\n" + report(results))
    replace_block(args.out, "benchmarks-" + name.replace("_", "-"), body)
    print(body)


def _describe(module):
    """The module docstring without its title and usage lines (the study's description)."""
    parts = module.__doc__.strip().split("\n\n")
    return "\n\n".join(p.strip() for p in parts[2:])


def _regen(cmd):
    return f"Regenerate: `python -m benchmarks {cmd}` (or `python -m benchmarks all`)."


def run_peer(quick):
    from benchmarks import peer_pa_inverter as P

    sizes = [(60, 40)] if quick else [(60, 40), (120, 80), (240, 160)]
    rows = []
    for nx, ny in sizes:
        rows.append(P.compare(nx, ny, repeat=5))
        print(f"  peer {nx}x{ny}: rel diff {rows[-1]['rel_f']:.1e}, scipy/ours "
              f"{rows[-1]['ratio']:.2f}", flush=True)
    bad = [r for r in rows if not (r["rel_f"] < 1e-8 and r["rel_grad"] < 1e-6)]
    text = ["## Peer comparison: linear pressure-actuated inverter, one analysis + sensitivities",
            "", _describe(P), "",
            P.peer_markdown(rows), ""]
    if bad:
        text.append(f"**VALIDATION FAILED** for {', '.join(r['mesh'] for r in bad)}: the two "
                    "implementations disagree; the timings are meaningless there.")
    text.append("Times are medians of 5 evaluations after a warm-up; the ratio > 1 means "
                "ours is faster.  Each evaluation is on the other of two designs (the test "
                "design and a 1 % perturbation of it) than the one before, as in an "
                "optimisation, so every forward pass solves.  The scipy peer uses `splu` with "
                "the `MMD_AT_PLUS_A` ordering (scipy has no sparse Cholesky), ours NGSolve's "
                "`sparsecholesky` with a numeric refactorisation (`Update`) per evaluation.")
    text.append("")
    text.append("What the linear block does here (`LinearSystem`, "
                "pacto_ng/physics/linear_system.py): the SIMP energy declares C = ∂²(tφ)/∂G² "
                "a modulus times a fixed tensor per element (checked once), so K and the Darcy matrix come from "
                "element matrices computed once, at the second design (pacto_ng/physics/"
                "scatter.py: a sparse product per design, no integration), and so do ∂SE/∂ρ, λᵀ∂R/∂ρ and the Darcy "
                "sensitivity; the Darcy load is a design-independent coupling matrix B (f = B p, "
                "λᵀ∂R/∂p = -s Bᵀλ); the residual R(u) = K u - s f and ∂SE/∂u are evaluated "
                "element by element (`Apply` of the symbolic form, exact to the round-off of "
                "∇u where the structure moves rigidly; with products with the assembled K the "
                "PneuNet's finite-difference checks lost three to four digits), SE is the "
                "integral of the energy density.  Where the time goes: the section after this "
                "block (a profile, measured separately).")
    tol = 1e-2

    def study(**kw):
        """The order study (its quick or full set-up) and, unless ``kw`` is the point spring's
        (no limit to compare against), the equal-accuracy comparison."""
        if quick:
            ref, rows, picks = P.order_study(levels=(30,), fine=60, repeat=1, tol=tol, **kw)
        else:
            ref, rows, picks = P.order_study(levels=(30, 60, 120, 240), fine=480, repeat=3,
                                             tol=tol, max_dofs=260_000, **kw)
        eq = P.equal_accuracy(ref, rows, repeat=1 if quick else 3) if kw else None
        return ref, rows, picks, eq

    ref, orows, picks, _ = study()
    text += ["", "### Same accuracy with higher order",
             "", "The physical pa-inverter (0.2 x 0.1 m, plane stress, E1 = 1, P_in = 1, "
             "Δs = 0.01 m, no filter, no projection) with a fixed piecewise-constant design on "
             "a 30 x 15 grid (exactly representable on every structured mesh used): objective "
             "of each (mesh, order) against the finest Q1 mesh.", "",
             "**With the output spring** (k_out = 0.1 at the output corner, as in the peer "
             "comparison).  The spring's reaction is a point force, under which the "
             "displacement of 2D elasticity is logarithmically singular: Δ and SE, and so the "
             "objective, have no limit as h → 0, at any order.", "",
             P.order_markdown(ref, orows, picks, tol)]
    text += [t for t in (P.decrement_line(ref, orows, k) for k in (1, 2, 3)) if t]
    # the same without the spring: -Δ/SE of the free output corner converges
    ref0, orows0, picks0, eq = study(k_out=0.0)
    text += ["", "**Without the output spring** (k_out = 0; the same design, load and "
             "supports): the objective converges, so the time to a given accuracy can be "
             "compared.  Each order is picked at the coarsest mesh from which it stays within "
             "the tolerance on every finer mesh of the study (the sequences oscillate at first); "
             "the scipy peer is timed on the mesh of the Q1 pick (unit elements, the same "
             "matrix sizes).  Times with one NGSolve thread, as the peer's splu.", "",
             P.order_markdown(ref0, orows0, picks0, tol, fine_q1_lines=False)]
    text += [t for t in (P.decrement_line(ref0, orows0, k) for k in (1, 2, 3)) if t]
    text += ["", P.equal_accuracy_markdown(eq)]
    # the spring and the port spread over a short edge: the reaction is a traction, and the
    # objective with a spring converges
    w = P.SPREAD_OUTPUT
    refw, orowsw, picksw, eqw = study(output_width=w)
    text += ["", f"**With the output spring spread over an edge** (k_out = 0.1 as above, on the "
             f"right edge's first {w:.5g} m from the output corner, `--set output_width`: the "
             f"spring k_out/2 mean((d·u)²) and Δ the edge's mean of -u_x; the same design, "
             f"load and supports): the spring's reaction is a traction, so the objective "
             f"converges.  Picks and times as in the table before.", "",
             P.order_markdown(refw, orowsw, picksw, tol, fine_q1_lines=False)]
    text += [t for t in (P.decrement_line(refw, orowsw, k) for k in (1, 2, 3)) if t]
    text += ["", P.equal_accuracy_markdown(eqw), "", _regen("peer")]
    return "\n".join(text)


def run_trade(quick, plots):
    from benchmarks import trade as T

    res = T.study(quick, repeat=1 if quick else 3)
    png = os.path.join(plots, "trade_curves.png")
    T.plot(res, png)
    text = ["## Trade curves: time against accuracy (mesh size x element order)", "",
            _describe(T), "",
            f"![trade curves]({os.path.relpath(png, os.path.dirname(os.path.abspath(ARGS.out)))})",
            "", T.markdown(res), "Times are medians of "
            f"{1 if quick else 3} evaluations after a warm-up; the error is relative to the run "
            "with the most dofs of that case and model (the reference).", "", _regen("trade")]
    return "\n".join(text)


def run_stability(quick):
    from benchmarks import stability as S

    rows = S.study(quick)
    text = ["## Stability map: the largest pressure an analysis completes", "",
            _describe(S), "", S.markdown(rows), "",
            _regen("stability")]
    return "\n".join(text)


def run_profile(quick):
    from benchmarks import profile_nonlinear as PR

    r = PR.profile()
    ab = PR.strain_energy_ab(
        [("pa-inverter neohookean, default mesh", {"model": "neohookean"})] if quick else
        [("pa-inverter neohookean, default mesh", {"model": "neohookean"}),
         ("pa-inverter linear, unit elements 120 x 80",
          __import__("benchmarks.peer_pa_inverter", fromlist=["x"]).ours_params(120, 80))])
    fast = PR.fast_paths_ab(
        [("pa-inverter neohookean, default mesh", {"model": "neohookean"})] if quick else
        [("pa-inverter neohookean, default mesh", {"model": "neohookean"}),
         ("pa-inverter wang, default mesh", {"model": "wang"})])
    text = ["## Profile of a nonlinear pressure-actuated optimisation iteration", "",
            _describe(PR), "", PR.markdown(r), "",
            "### Second round: element-wise field derivatives and the load norm", "",
            "Why the Wang model cost several times Neo-Hookean per iteration with the same "
            "Newton counts: its sensitivity forms.  The element-wise derivatives λᵀ∂R/∂ρ and "
            "∂SE/∂ρ were LinearForms of the symbolic `dens.Diff(ρ, q)`, whose CF tree blows up "
            "for Wang (γ = H(ρ^p) inside φ_H(γG) - φ_L(γG) + φ_L(G)).  They are now the "
            "gradient of the same integrand by automatic differentiation in ρ: `Apply` of a "
            "`Variation` form in the field's trial function (`FieldGradient`, "
            "pacto_ng/physics/sensitivities.py; same values), and for linear mechanics the "
            "tangent's ∂C/∂ρ.  And the "
            "load norm of a design-dependent load on a stress-free energy (∂φ/∂G = 0 at G = 0, "
            "checked once) is now the norm of the loads' LinearForm instead of an `Apply` of "
            "the whole energy at u = 0.  Timed interleaved on the same state (1 thread, "
            "median of 7):", "", PR.fast_ab_markdown(fast), "",
            "A whole optimisation iteration of the Wang profile (`python -m benchmarks.profile_nonlinear --model wang --iterations 3`, 2 threads) went from 5.71 / 5.75 s to 2.30 / 1.97 s, Neo-Hookean from 1.94 / 1.14 s to 2.26 / 2.30 s (before / after run interleaved twice on 2026-12-01 at load average 4-6: the Neo-Hookean figures are within the noise of the loaded machine; the parts changed are timed in the table above).  The profile table at the top is measured with all these changes (the table of 2026-11-23, before them and at a load average of 10, gave 4.09 s per Neo-Hookean iteration).", "",
            "Other findings: in plane stress, Neo-Hookean residual and tangent cost 6-7x "
            "plane strain (the local Newton iteration for F33, unrolled at every quadrature "
            "point); the Wang energy costs about 2x Neo-Hookean in plane strain (φ_H(γG) plus "
            "two linear energies), of which the γ CF is 7-10 % of the tangent; a symbolic "
            "tangent (`Diff` twice, `BilinearForm.Assemble`) was not faster than "
            "`AssembleLinearization` for the nonlinear models (0.110 against 0.110 s "
            "Neo-Hookean, 0.27 against 0.22 s Wang), so they keep `Variation`.", "",
            "### The change made: ∂SE/∂u by `Apply` of a `Variation` form",
            "", "`StrainEnergy.backward` (pacto_ng/responses.py) assembled ∂SE/∂u as a "
            "LinearForm of `dens.Diff(u, v)`; it now evaluates the same integrand with the same "
            "quadrature as `Apply` of a `BilinearForm(Variation(t φ(∇u)))`, built once.  Timed "
            "interleaved on the same state (median of 7):", "", PR.ab_markdown(ab), "",
            "(For the linear row: a linear problem with a quadratic energy now takes ∂SE/∂u "
            "as K u - K_springs u, applied element by element (`Apply` of the tangent's "
            "symbolic form, not a product with the assembled matrix: see the peer section); "
            "the row times the `Variation` form that non-quadratic energies use.)", "",
            _regen("profile")]
    return "\n".join(text)


def run_mbb(quick):
    from benchmarks import mbb_iteration as MB

    rows = MB.study(sizes=MB.SIZES[:1] if quick else MB.SIZES, runs=1 if quick else 3)
    text = ["## MBB: time per optimisation iteration against one factorisation + solve", "",
            _describe(MB), "", MB.markdown(rows), "",
            "Where an iteration's time goes besides the factorisation (linear SIMP): the "
            "stiffness matrix is a sparse product of element matrices computed once "
            "(pacto_ng/physics/scatter.py), the compliance adjoint is the primal (no second "
            "solve), and the element sensitivities are quadratic forms of the same element "
            "matrices.  A ratio below 1 is possible: the iterations refactorise numerically "
            "(`Update`, the ordering and symbolic factorisation kept from the first), the "
            "reference is a new `Inverse`.", "", _regen("mbb")]
    return "\n".join(text)


ARGS = None


def main(argv=None):
    global ARGS
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study", choices=STUDIES + STANDALONE + ("all",))
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default=None)
    ap.add_argument("--plots", default=None)
    ARGS = args = ap.parse_args(argv)
    if args.study in STANDALONE:
        import importlib

        return importlib.import_module(f"benchmarks.{args.study}").main(
            [] if args.out is None else ["--out", args.out])
    if args.out is None:
        args.out = (os.path.join(tempfile.gettempdir(), "pacto_benchmarks_quick.md")
                    if args.quick else os.path.join("docs", "studies.md"))
    if args.plots is None:
        args.plots = os.path.dirname(os.path.abspath(args.out))
    os.makedirs(args.plots, exist_ok=True)
    todo = STUDIES if args.study == "all" else (args.study,)
    t_all = time.perf_counter()
    for name in todo:
        t0 = time.perf_counter()
        mach = machine()
        print(f"[{name}] {mach}", flush=True)
        if name == "peer":
            body = run_peer(args.quick)
        elif name == "trade":
            body = run_trade(args.quick, args.plots)
        elif name == "stability":
            body = run_stability(args.quick)
        elif name == "mbb":
            body = run_mbb(args.quick)
        else:
            body = run_profile(args.quick)
        took = time.perf_counter() - t0
        body += (f"\n\n*Measured {mach}; this study took {took:.0f} s"
                 f"{' (--quick)' if args.quick else ''}.  The machine was shared with other "
                 "jobs: absolute times are noisy, ratios and medians less so.*")
        replace_block(args.out, f"benchmarks-{name}", body)
        print(f"[{name}] done in {took:.0f} s -> {args.out}", flush=True)
    print(f"all done in {time.perf_counter() - t_all:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
