"""The ``pacto`` commands that optimise or post-process a design: ``run`` and ``resume`` (the
optimisation, then its part), ``sweep``, ``evaluate``, ``analyse``, ``export``, ``refine``
and ``compare``, each from the parsed arguments (:mod:`pacto_ng.cli_parser`) to its exit code.

They need :mod:`pacto_ng.runner` and :mod:`pacto_ng.post`, about 0.5 s to import (pyvista,
meshio): :mod:`pacto_ng.cli` imports this module for these commands only, so that
``pacto --help``, ``pacto cases`` and ``pacto new`` stay quick.
"""
from __future__ import annotations

import argparse
import sys

from .case import get_case
from .cli_parser import params_from_args
from .errors import InputError
from .evaluate import evaluate_design
from .parallel import leads
from .post.analyse import analyse_run
from .post.analysis_options import parse_pressures
from .post.as_built import analyse_as_built
from .post.cli_commands import export_run
from .post.compare import compare_runs
from .post.finish import say
from .post.part_stage import finish_run
from .post.refine_check import check_refine_gradients
from .post.refine_run import refine_run
from .post.refine_setup import Loading, refuses
from .post.runs import load_run, rebuild
from .runner import optimise_case, resume_run
from .sweep import run_sweep
from .sweep_plan import parse_loads, parse_models


def post_command(args) -> int:
    """``pacto analyse``, ``pacto export``, ``pacto refine`` and ``pacto compare``."""
    if args.command == "analyse":
        return _analyse_command(args)
    if args.command == "refine":
        loading = Loading(args.model, args.load, args.load_type, args.contact)
        if args.check_gradients:
            return check_refine_gradients(args.dir, directions=args.directions, tol=args.tol,
                                          quiet=args.quiet, loading=loading)
        return refine_run(args.dir, steps=args.steps, quiet=args.quiet,
                          overwrite=args.overwrite, loading=loading,
                          pressures=parse_pressures(args.pressures) if args.pressures else (),
                          min_wall=args.min_wall)
    if args.command == "export":
        return export_run(args.dir, args.format, out=args.out, threshold_value=args.threshold,
                          maxh=args.maxh, quiet=args.quiet, threshold2=args.threshold2,
                          units=args.units, mirror=args.mirror)
    return compare_runs(args.dirs, out=args.out, quiet=args.quiet)


def _analyse_command(args) -> int:
    """``pacto analyse DIR`` (pacto_ng.post.analyse) or ``pacto analyse CASE --as-built``
    (pacto_ng.post.as_built)."""
    pressures = parse_pressures(args.pressures) if args.pressures is not None else None
    kinds = None if args.kinds is None else tuple(
        k.strip() for k in args.kinds.split(",") if k.strip())
    if args.as_built:
        case = get_case(args.dir)
        params = params_from_args(case, argparse.Namespace(
            set=args.set, model=args.model, maxh=args.maxh, nelx=None))
        return analyse_as_built(case, params, pressures=pressures, kinds=kinds,
                                order=args.order, out=args.out, quiet=args.quiet,
                                time_limit=args.time_limit, contact=args.contact)
    for flag, value in (("--set", args.set), ("--out", args.out)):
        if value:
            raise InputError(f"{flag}: applies to --as-built; a run's part is analysed with the "
                             f"run's parameters (--model names another law) in DIR/analysis/")
    return analyse_run(args.dir, pressures=pressures, threshold_value=args.threshold,
                       maxh=args.maxh, order=args.order,
                       kinds=kinds if kinds is not None else ("darcy", "fixed", "follower"),
                       quiet=args.quiet, connect=not args.keep_threshold,
                       threshold2=args.threshold2, model=args.model, time_limit=args.time_limit,
                       contact=args.contact)


def run_with_part(case, params, out, args) -> int:
    """``pacto run``: the optimisation, then its part (:mod:`pacto_ng.post.part_stage`) made,
    checked and analysed by the rank that writes the folder."""
    done = optimise_case(case, params, out, quiet=args.quiet, overwrite=args.overwrite)
    return _with_part(done, out, args)


def resume_with_part(args) -> int:
    """``pacto resume``: the optimisation continued, then its part, as ``pacto run``."""
    done = resume_run(args.dir, quiet=args.quiet, iterations=args.iterations)
    return _with_part(done, args.dir, args)


def _with_part(done, out, args) -> int:
    """A finished optimisation's part made, checked and analysed (unless ``--no-part``), and
    then, for a run the refinement applies to (:func:`~pacto_ng.post.refine_setup.refuses`: a
    pressure case with an output port) whose part is sealed, and unless ``--no-refine`` or the
    optimisation stopped on a failure, its shape refined as ``pacto refine DIR`` does (the
    refinement keeps the part's topology: an open chamber stays open, and the part line has
    said so; :func:`why_not_refined` says which sealed parts are not refined; a refinement
    that cannot be made is said in one line; the run's result stands); the run's exit code."""
    if leads() and not args.no_part and (problem := _part_problem(done, out, args.command)):
        summary = finish_run(out, problem, done.summary, quiet=args.quiet)
        if (args.no_refine or done.exit_code != 0 or not summary["part"].get("made")
                or summary.get("sealed") is False or refuses(run := load_run(out, "refine"))):
            return done.exit_code
        why = why_not_refined(summary["part"], run.params.model, done.problem.mesh.dim, out)
        if why:
            say(args.quiet, why)
        else:
            try:
                refine_run(out, quiet=args.quiet, overwrite=args.command == "resume"
                           or args.overwrite)
            except InputError as err:
                print(f"pacto: warning: the part was not refined: {err}", file=sys.stderr,
                      flush=True)
    return done.exit_code


def _part_problem(done, out, command: str):
    """The problem whose final design the part is made of: the run's own, or a distributed
    run's final design analysed by its rank 0 on the serial mesh (the other ranks are done);
    None where that serial problem cannot be made (e.g. it would not fit this machine), said
    in one line: the run's result stands, and ``pacto analyse DIR`` makes the part."""
    if done.problem.numbering is None:
        return done.problem
    try:
        return rebuild(load_run(out, command))
    except InputError as err:
        print(f"pacto: warning: the part was not made: {err} ('pacto analyse {out}' makes it "
              "where the run's design fits one process)", file=sys.stderr, flush=True)
        return None


def why_not_refined(part: dict, model: str, dim: int, out) -> str:
    """Why a finished run's sealed part (its summary entry ``part``) is not refined by
    default, in one line, or "" where it is: a part whose analysis found no equilibrium at
    the run's load (there is nothing to start from), and a 3D part under a nonlinear model
    (its refinement was not measured to end in a time of the run's order; a 2D one does:
    pneunet-silicone's took 368 s after a run of 68 s, docs/guide.md)."""
    if part.get("converged") is False:
        return "the part is not refined: its analysis found no equilibrium at the run's load"
    if model != "linear" and dim == 3:
        return (f"the 3D part is not refined by default under the {model} model (its "
                f"refinement takes many times the run): pacto refine {out} refines it")
    return ""


def sweep_command(case, params, args) -> int:
    """``pacto sweep``: the case over the grid of ``--loads`` and ``--models``."""
    loads = parse_loads(args.loads)
    models = parse_models(args.models, params.model)
    return run_sweep(case, params, models, loads, args.out or f"output/sweep-{case.name}",
                     scheduler=args.scheduler, workers=args.workers, quiet=args.quiet)


def evaluate_command(case, params, out, args) -> int:
    """``pacto evaluate``: the given design analysed into ``out``."""
    return evaluate_design(case, params, args.density, out, filtered=args.filtered,
                           quiet=args.quiet, overwrite=args.overwrite)
