"""The ``pacto`` command.

    pacto cases
    pacto new NAME
    pacto run CASE [--model M] [--load V] [--iterations N]
                   [--maxh H | --nelx NX --nely NY [--nelz NZ]]
                   [--order K] [--optimizer mma|gcmma] [--set NAME=VALUE ...] [--out DIR]
                   [--overwrite] [--quiet] [--show-parameters]
    pacto evaluate CASE --density FILE [--filtered] [same options] [--overwrite]
    pacto check-gradients CASE [same options] [--tol T]
    pacto resume DIR [--quiet]
    pacto sweep CASE --loads L1,L2,... [--models M1,M2] [--scheduler ADDRESS] [--workers N]
                [run options but --model/--load]
    pacto analyse DIR [--pressures P1,P2,...] [--threshold T|volume] [--keep-threshold]
                  [--threshold2 T2] [--maxh H] [--order K]
                  [--kinds darcy,fixed,follower] [--quiet]
    pacto export DIR --format stl|vtk|vtu|msh [--out FILE] [--units mm|m] [--no-mirror]
                 [--threshold T] [--threshold2 T2] [--maxh H]
    pacto compare DIR1 DIR2 ... [--out FILE.png]

Bad input gives a one-line error on stderr and exit code 2; a run stopped by a Newton failure
exits with 1 after saving the last good design.  An output folder that already holds a run is
refused (exit 2): resume it, choose another --out, or add --overwrite.  SIGINT, SIGTERM and
SIGHUP stop a run with one line saying what is kept (exit 128 + the signal's number).
"""
from __future__ import annotations

import argparse
import math
import os
import sys

from .errors import InputError
from .params import Parameters


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise InputError(message)


def _positive(text: str) -> float:
    """A finite positive number (argparse type)."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number, got '{text}'")
    return value


def _seed(text: str) -> int:
    """A random seed: an integer in [0, 2**32) (argparse type)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value < 2 ** 32:
        raise argparse.ArgumentTypeError(f"expected an integer from 0 to 2**32 - 1, got '{text}'")
    return value


def _case_options(p: argparse.ArgumentParser):
    p.add_argument("case", help="a built-in case's name (see 'pacto cases') or the path of a "
                   "case file (my_case.py; 'pacto new' writes one)")
    p.add_argument("--model", help="linear | gnl | neohookean | wang")
    p.add_argument("--load", type=float, help="load magnitude (N, or Pa for pressure cases)")
    p.add_argument("--iterations", type=int, help="maximum optimisation iterations")
    p.add_argument("--maxh", type=float, help="Netgen triangle size")
    p.add_argument("--nelx", type=int, help="structured quads in x")
    p.add_argument("--nely", type=int, help="structured quads in y")
    p.add_argument("--nelz", type=int, help="structured hexahedra in z (a 3D box case)")
    p.add_argument("--order", type=int, help="displacement element order (1, 2, 3)")
    p.add_argument("--optimizer", help="mma | gcmma")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override any case parameter (see --show-parameters)")
    p.add_argument("--out", help="output folder (default: output/CASE-MODEL)")
    p.add_argument("--quiet", action="store_true", help="no progress output")


def build_parser() -> argparse.ArgumentParser:
    ap = _Parser(prog="pacto", description="Topology optimisation of pressure-actuated soft "
                 "robots and compliant mechanisms (NGSolve).")
    sub = ap.add_subparsers(dest="command", parser_class=_Parser)
    sub.add_parser("cases", help="list the built-in cases")
    n = sub.add_parser("new", help="write a commented case file that runs as written")
    n.add_argument("name", help="the new case's file (NAME.py; NAME alone adds .py)")
    r = sub.add_parser("run", help="optimise a case")
    _case_options(r)
    r.add_argument("--show-parameters", action="store_true", help="print every parameter and exit")
    r.add_argument("--show-chain", action="store_true",
                   help="build the case's chain of blocks, print it and exit")
    r.add_argument("--overwrite", action="store_true", help="the --out folder may hold an earlier "
                   "run: remove that run's files first (by default such a folder is refused)")
    r.add_argument("--no-part", action="store_true", help="end without making and analysing "
                   "the part (pacto analyse DIR makes it later)")
    e = sub.add_parser("evaluate", help="analyse a given design (no optimisation)")
    _case_options(e)
    e.add_argument("--density", required=True, help="element densities ρ̄ (.npy, .csv, .txt: "
                   "one per element in NGSolve's order; a run's design.vtu), or a run's "
                   "checkpoint.npz (its design variables, filtered and projected)")
    e.add_argument("--filtered", action="store_true",
                   help="treat the densities as design variables (filter and project them)")
    e.add_argument("--overwrite", action="store_true", help="the --out folder may hold earlier "
                   "results: remove them first (default --out: output/CASE-MODEL-evaluate)")
    g = sub.add_parser("check-gradients", help="finite-difference check of the full chain")
    _case_options(g)
    g.add_argument("--tol", type=_positive, default=1e-5, help="largest relative error accepted")
    g.add_argument("--seed", type=_seed, default=0, help="seed of the random design and "
                   "directions (0 to 2**32 - 1)")
    _post_parsers(sub)
    s = sub.add_parser("resume", help="continue a run from its checkpoint")
    s.add_argument("dir")
    s.add_argument("--iterations", type=int, default=None,
                   help="raise the run's iteration cap (e.g. a run that stopped at the cap)")
    s.add_argument("--quiet", action="store_true")
    s.add_argument("--no-part", action="store_true", help="as for run")
    w = sub.add_parser("sweep", help="run a case over a grid of loads and models (Dask)")
    w.add_argument("case", help="a built-in case's name or a case file's path")
    w.add_argument("--loads", required=True, help="comma-separated loads, e.g. 1e5,1e6,1e7")
    w.add_argument("--models", help="comma-separated models (default: the case's model)")
    w.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    w.add_argument("--workers", type=int, help="local worker processes (default: the cores)")
    for opt, kind in (("--iterations", int), ("--maxh", float), ("--nelx", int), ("--nely", int),
                      ("--nelz", int), ("--order", int), ("--optimizer", str)):
        w.add_argument(opt, type=kind, help="as for run")
    w.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="as for run")
    w.add_argument("--out", help="sweep folder (default: output/sweep-CASE)")
    w.add_argument("--quiet", action="store_true", help="no progress lines")
    return ap


def _post_parsers(sub):
    """analyse, export, compare: from a finished run to a part (pacto_ng.post.cli_commands,
    pacto_ng.post.compare)."""
    a = sub.add_parser("analyse", help="analyse the part of a finished run (pressure cases), "
                       "or a case's own geometry as built", description="Make the part of a "
                       "finished run's final design (threshold, body-fitted remesh, seal check) "
                       "and analyse it over a pressure sweep with the run's own material law "
                       "(--model: another): the Darcy pressure of the thresholded design and "
                       "the pressure on the wetted walls, fixed and follower, beside the Δ the "
                       "optimisation expected; writes DIR/analysis/ (analysis.json, "
                       "analysis.csv, analysis.png, deformed.png, report.md, part.stl, "
                       "remeshed.vtu, deformed.vtu), in 2D and 3D.  With --as-built, CASE (a "
                       "built-in case or a case file) is analysed as its geometry stands: all "
                       "its material, the void regions removed, the pressure on the inlet "
                       "walls; regions named 'stiff' take E2.  Pressure cases only.")
    a.add_argument("dir", metavar="DIR|CASE", help="a finished run folder; with --as-built a "
                   "built-in case's name or a case file")
    a.add_argument("--as-built", action="store_true", help="analyse the case's own geometry as "
                   "the part (no optimisation; output in --out, default output/CASE-as-built)")
    a.add_argument("--pressures", help="comma-separated inlet pressures in the case's load unit "
                   "(default: 5 log-spaced values from load/100 to the load)")
    a.add_argument("--kinds", help="analyses to run: darcy, fixed, follower (default: all three "
                   "for a run; fixed,follower as built)")
    a.add_argument("--model", help="the part's material law (default: the run's, or the "
                   "case's as built), e.g. neohookean for a linear run")
    a.add_argument("--order", type=int, help="displacement order of the part's analysis "
                   "(default: a run's part 2, as the run's own part; as built 2 in 2D, 1 in 3D)")
    a.add_argument("--maxh", type=float, help="element size of the part (default: the run's own "
                   "part's, half the run's in 2D, the run's in 3D; as built: the case's mesh "
                   "size)")
    a.add_argument("--threshold", default="0.5", help="density threshold in (0, 1), or 'volume': "
                   "the threshold at which the part has the design's material volume (2D)")
    a.add_argument("--keep-threshold", action="store_true", help="do not lower the threshold "
                   "when the part kept on the clamp misses an output (by default it is "
                   "lowered until it reaches them)")
    a.add_argument("--threshold2", default="0.5", help="two materials: the stiff material is "
                   "where the stiff-material density rho_bar2 >= this, inside the part (default "
                   "0.5)")
    a.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="as built: any parameter, as for run (e.g. material=ecoflex-00-30)")
    a.add_argument("--out", help="as built: the output folder (default output/CASE-as-built)")
    a.add_argument("--time-limit", type=_positive, default=3600.0, help="refuse an analysis "
                   "estimated to take longer (seconds, default 3600)")
    a.add_argument("--quiet", action="store_true", help="no progress output")
    x = sub.add_parser("export", help="the thresholded, remeshed part of a run as STL, VTK, "
                       "VTU or MSH")
    x.add_argument("dir", help="a finished run folder")
    x.add_argument("--format", required=True, choices=("stl", "vtk", "vtu", "msh"),
                   help="stl: extruded by the case's thickness (closed, binary; 3D: the smoothed "
                   "iso-surface); vtk, vtu: the part's cells with the run's final rho_bar, u, p, "
                   "strain and stress; msh: Gmsh 2.2 with the boundary names as physical groups "
                   "(2D)")
    x.add_argument("--units", choices=("mm", "m"),
                   help="length unit of the file (default: mm for stl, as slicers and CAD read "
                   "it; m, the solver's SI unit, for vtk, vtu and msh)")
    x.add_argument("--mirror", action=argparse.BooleanOptionalAction, default=True,
                   help="a case solved on a symmetric half (or quarter): write the whole mechanism, "
                   "the part and its mirror images joined along the symmetry lines or planes "
                   "(default); --no-mirror: the part as solved")
    x.add_argument("--out", help="output file (default DIR/export/design.FORMAT)")
    x.add_argument("--threshold", type=float, help="density threshold in (0, 1) (default: the "
                   "analysis's, else 0.5)")
    x.add_argument("--threshold2", help="two materials: threshold of rho_bar2 (stiff) in (0, 1) "
                   "(default: the analysis's, else 0.5)")
    x.add_argument("--maxh", type=float, help="element size (default: the analysis's, else half "
                   "the run's)")
    x.add_argument("--quiet", action="store_true")
    c = sub.add_parser("compare", help="designs side by side and their analysis curves")
    c.add_argument("dirs", nargs="+", help="finished run folders")
    c.add_argument("--out", help="picture (default compare.png)")
    c.add_argument("--quiet", action="store_true")


def _post_command(args) -> int:
    from .post import cli_commands as pc

    if args.command == "analyse":
        return _analyse_command(args)
    if args.command == "export":
        return pc.export_run(args.dir, args.format, out=args.out, threshold_value=args.threshold,
                             maxh=args.maxh, quiet=args.quiet, threshold2=args.threshold2,
                             units=args.units, mirror=args.mirror)
    from .post.compare import compare_runs

    return compare_runs(args.dirs, out=args.out, quiet=args.quiet)


def _analyse_command(args) -> int:
    """``pacto analyse DIR`` (pacto_ng.post.analyse) or ``pacto analyse CASE --as-built``
    (pacto_ng.post.as_built)."""
    from .post.analyse import analyse_run, parse_pressures

    pressures = parse_pressures(args.pressures) if args.pressures is not None else None
    kinds = None if args.kinds is None else tuple(
        k.strip() for k in args.kinds.split(",") if k.strip())
    if args.as_built:
        from .case import get_case
        from .post.as_built import analyse_as_built

        case = get_case(args.dir)
        params = params_from_args(case, argparse.Namespace(
            set=args.set, model=args.model, maxh=args.maxh, nelx=None))
        return analyse_as_built(case, params, pressures=pressures, kinds=kinds,
                                order=args.order, out=args.out, quiet=args.quiet,
                                time_limit=args.time_limit)
    for flag, value in (("--set", args.set), ("--out", args.out)):
        if value:
            raise InputError(f"{flag}: applies to --as-built; a run's part is analysed with the "
                             f"run's parameters (--model names another law) in DIR/analysis/")
    return analyse_run(args.dir, pressures=pressures, threshold_value=args.threshold,
                       maxh=args.maxh, order=args.order,
                       kinds=kinds if kinds is not None else ("darcy", "fixed", "follower"),
                       quiet=args.quiet, connect=not args.keep_threshold,
                       threshold2=args.threshold2, model=args.model, time_limit=args.time_limit)


def params_from_args(case, args) -> Parameters:
    p = case.defaults
    direct = {}
    for name in ("model", "load", "iterations", "maxh", "nelx", "nely", "nelz", "order",
                 "optimizer"):
        val = getattr(args, name, None)
        if val is not None:
            direct[name] = str(val)
    if (args.maxh is not None) and args.nelx is None:
        direct["nelx"], direct["nely"], direct["nelz"] = "0", "0", "0"
    sets = {}
    for item in args.set:
        if "=" not in item:
            raise InputError(f"--set: expected NAME=VALUE, got '{item}'")
        k, v = item.split("=", 1)
        sets[k.strip()] = v.strip()
    return p.with_overrides({**direct, **sets})


def _show_parameters(case, params: Parameters):
    print(f"{case.name}: {case.summary}")
    units = {"load": case.load_unit}
    derived = params.derived
    for name, val, unit, help_ in params.describe(units):
        how = f"  ({derived[name]})" if name in derived else ""
        print(f"  {name:18s} {val!s:>12s} {unit:12s} {help_}{how}")
    if not case.analysis_only:  # the set-up's objective scale, where derived
        found = case.derived_objective_ref(params)
        if found is not None:
            print(f"  {'objective_ref':18s} {found[0]:>12.4g} {'':12s} the set-up's typical "
                  f"objective, scaled to 10  ({found[1]})")


def _default_out(args, case, params, suffix=""):
    return args.out or f"output/{case.name}-{params.model}{suffix}"


class _Signalled(KeyboardInterrupt):
    """SIGTERM or SIGHUP, raised like Ctrl-C's KeyboardInterrupt so that a run stops the same
    way (its checkpoint kept, no file half written)."""


def _raise_signalled(signum, frame):
    raise _Signalled(signum)


def _stop_signals():
    """SIGTERM and SIGHUP stop the command as SIGINT does; returns the handlers to restore."""
    import signal

    old = {}
    for name in ("SIGTERM", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is None:
            continue
        try:
            old[sig] = signal.signal(sig, _raise_signalled)
        except ValueError:  # not the main thread: leave the signals alone
            break
    return old


def _interrupted(err: KeyboardInterrupt) -> int:
    """The one line of an interrupted command (what is kept, how to go on); 128 + signal."""
    import signal

    signum = err.args[0] if isinstance(err, _Signalled) and err.args else signal.SIGINT
    name = signal.Signals(signum).name
    note = getattr(err, "pacto_note", None)
    try:
        print(f"pacto: interrupted by {name}" + (f": {note}" if note else ""), file=sys.stderr)
    except OSError:  # a hung-up terminal
        pass
    return 128 + int(signum)


def _abort_other_ranks(code: int) -> None:
    """In an MPI run, stop every rank (the others wait in a collective call for this one)."""
    from .parallel import world

    comm = world()
    if comm is not None:
        sys.stderr.flush()
        comm.Abort(code)


#: the commands that run on the ranks of an MPI launch (the others run on one process)
DISTRIBUTED = ("run", "resume", "cases")


def _refused_under_mpi(command: str) -> bool:
    """Under mpirun, a command that runs on one process is refused: one line from rank 0,
    exit code 2 on every rank (without it each rank would run it alone, into one folder)."""
    from .parallel import world

    comm = world()
    if comm is None:
        return False
    if comm.rank == 0:
        print(f"pacto: error: {command}: runs on one process, not under mpirun (only 'run' "
              f"and 'resume' are distributed): start it as 'pacto {command} ...' without "
              "mpirun", file=sys.stderr)
    comm.Barrier()
    return True


def main(argv=None) -> int:
    import signal

    from .threads import compute

    argv = sys.argv[1:] if argv is None else argv
    handlers = _stop_signals()
    try:
        with compute():
            return _main(argv)
    except InputError as err:
        print(f"pacto: error: {err}", file=sys.stderr)
        _abort_other_ranks(2)
        return 2
    except KeyboardInterrupt as err:
        return _interrupted(err)
    except BrokenPipeError:
        # the reader of the output went away (e.g. '| head'): stop quietly, as the
        # Python documentation advises, so that the interpreter's final flush cannot fail
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    finally:
        for sig, handler in handlers.items():
            signal.signal(sig, handler)


def _run_with_part(case, params, out, args) -> int:
    """``pacto run``: the optimisation, then its part (:mod:`pacto_ng.post.part_stage`) made,
    checked and analysed by the rank that writes the folder."""
    from .runner import optimise_case

    done = optimise_case(case, params, out, quiet=args.quiet, overwrite=args.overwrite)
    return _with_part(done, out, args)


def _resume_with_part(args) -> int:
    """``pacto resume``: the optimisation continued, then its part, as ``pacto run``."""
    from .runner import resume_run

    done = resume_run(args.dir, quiet=args.quiet, iterations=args.iterations)
    return _with_part(done, args.dir, args)


def _with_part(done, out, args) -> int:
    """A finished optimisation's part made, checked and analysed (unless ``--no-part``);
    the run's exit code."""
    from .parallel import leads

    if leads() and not args.no_part:
        from .post.part_stage import finish_run  # after the run: a refusal stays quick

        finish_run(out, done.problem, done.summary, quiet=args.quiet)
    return done.exit_code


def _main(argv) -> int:
    from .case import available_cases, get_case

    ap = build_parser()
    args = ap.parse_args(argv)
    if args.command is None:
        ap.print_help()
        return 2
    if args.command not in DISTRIBUTED and _refused_under_mpi(args.command):
        return 2
    if args.command == "cases":
        for c in available_cases():
            kind = "analysis" if c.analysis_only else "optimisation"
            print(f"{c.name:12s} {c.summary}  [{kind}; load in {c.load_unit}]")
        return 0
    if args.command == "new":
        from .template import write_template

        path = write_template(args.name)
        print(f"wrote {path}: run it with 'pacto run {path}'")
        return 0
    if args.command in ("analyse", "export", "compare"):
        return _post_command(args)
    if args.command == "resume":
        return _resume_with_part(args)
    case = get_case(args.case)
    params = params_from_args(case, args)
    if args.command == "run":
        if args.show_parameters:
            _show_parameters(case, case.resolve(params))
            return 0
        if args.show_chain:
            from .case import build_problem

            problem = build_problem(case, params)
            print(f"{case.name} ({problem.mesh.ne} elements, model {problem.params.model}):")
            print("\n".join(problem.describe()))
            return 0
        if case.analysis_only:
            from .analysis_case import run_analysis_case

            return run_analysis_case(case, params, _default_out(args, case, params),
                                     quiet=args.quiet, overwrite=args.overwrite)
        return _run_with_part(case, params, _default_out(args, case, params), args)
    if args.command == "sweep":
        from . import sweep

        loads = sweep.parse_loads(args.loads)
        models = sweep.parse_models(args.models, params.model)
        return sweep.run_sweep(case, params, models, loads, args.out or f"output/sweep-{case.name}",
                               scheduler=args.scheduler, workers=args.workers, quiet=args.quiet)
    if args.command == "evaluate":
        from .evaluate import evaluate_design

        return evaluate_design(case, params, args.density,
                               _default_out(args, case, params, "-evaluate"),
                               filtered=args.filtered, quiet=args.quiet, overwrite=args.overwrite)
    if args.command == "check-gradients":
        from .gradcheck import check_case

        explicit = args.maxh is not None or args.nelx is not None or args.nelz is not None
        from .physics.equilibrium import NewtonFailure

        try:
            worst = check_case(case, params, seed=args.seed, quiet=args.quiet,
                               explicit_mesh=explicit)
        except NewtonFailure as err:
            print(f"pacto: check-gradients {case.name}: the equilibrium of the check's random "
                  f"design was not found: {err}", file=sys.stderr)
            return 1
        ok = worst <= args.tol
        print(f"worst relative error {worst:.3e} ({'pass' if ok else 'FAIL'}, tolerance {args.tol:g})")
        return 0 if ok else 1
    return 2


if __name__ == "__main__":
    sys.exit(main())
