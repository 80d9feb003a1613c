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
    pacto refine DIR [--steps N] [--model M] [--load P] [--load-type T] [--overwrite] [--quiet]
    pacto refine DIR --check-gradients [--directions N] [--tol T]
    pacto compare DIR1 DIR2 ... [--out FILE.png]

Bad input gives a one-line error on stderr and exit code 2; a run stopped by a Newton failure
exits with 1 after saving the last good design.  An output folder that already holds a run is
refused (exit 2): resume it, choose another --out, or add --overwrite.  SIGINT, SIGTERM and
SIGHUP stop a run with one line saying what is kept (exit 128 + the signal's number).

This module is the command's entry point (:func:`main`: errors, signals, MPI) and runs the
quick commands; the arguments are parsed by :mod:`pacto_ng.cli_parser`, the commands that
optimise or post-process run in :mod:`pacto_ng.commands`.
"""
from __future__ import annotations

import os
import signal
import sys

from .analysis_case import run_analysis_case
from .case import available_cases, build_problem, get_case
from .cli_parser import build_parser, params_from_args
from .errors import InputError
from .gradcheck import check_case
from .parallel import world
from .params import Parameters
from .physics.equilibrium import NewtonFailure
from .template import write_template
from .threads import compute


def _show_parameters(case, params: Parameters):
    print(f"{case.name}: {case.summary}")
    units = {"load": case.load_unit}
    derived = {**params.mechanics.set_by_material(), **params.derived}
    for name, val, unit, help_ in params.describe(units):
        how = f"  ({derived[name]})" if name in derived else ""
        shown = f"{val:.10g}" if isinstance(val, float) else str(val)  # not 0.8908799999999999
        print(f"  {name:18s} {shown:>12s} {unit:12s} {help_}{how}")
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
    comm = world()
    if comm is not None:
        sys.stderr.flush()
        comm.Abort(code)


#: the commands that run on the ranks of an MPI launch (the others run on one process)
DISTRIBUTED = ("run", "resume", "cases")


def _refused_under_mpi(command: str) -> bool:
    """Under mpirun, a command that runs on one process is refused: one line from rank 0,
    exit code 2 on every rank (without it each rank would run it alone, into one folder)."""
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


def _commands():
    """:mod:`pacto_ng.commands`, imported by the commands that optimise or post-process (it
    imports pacto_ng.runner and pacto_ng.post, about 0.5 s: 'pacto --help', 'pacto cases' and
    'pacto new' stay quick)."""
    from . import commands

    return commands


def _main(argv) -> int:
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
        path = write_template(args.name)
        print(f"wrote {path}: run it with 'pacto run {path}'")
        return 0
    if args.command in ("analyse", "export", "refine", "compare"):
        return _commands().post_command(args)
    if args.command == "resume":
        return _commands().resume_with_part(args)
    case = get_case(args.case)
    params = params_from_args(case, args)
    if args.command == "run":
        if args.show_parameters:
            _show_parameters(case, case.resolve(params))
            return 0
        if args.show_chain:
            problem = build_problem(case, params)
            print(f"{case.name} ({problem.mesh.ne} elements, model {problem.params.model}):")
            print("\n".join(problem.describe()))
            return 0
        if case.analysis_only:
            return run_analysis_case(case, params, _default_out(args, case, params),
                                     quiet=args.quiet, overwrite=args.overwrite)
        return _commands().run_with_part(case, params, _default_out(args, case, params), args)
    if args.command == "sweep":
        return _commands().sweep_command(case, params, args)
    if args.command == "evaluate":
        return _commands().evaluate_command(case, params,
                                            _default_out(args, case, params, "-evaluate"), args)
    if args.command == "check-gradients":
        explicit = args.maxh is not None or args.nelx is not None or args.nelz is not None
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
