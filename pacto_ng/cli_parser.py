"""The ``pacto`` command's arguments: its parser (:func:`build_parser`, one sub-command per
command; a bad argument is an InputError) and the parameters of a case from them
(:func:`params_from_args`).  What each command does: :mod:`pacto_ng.cli`.
"""
from __future__ import annotations

import argparse
import math

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
    r.add_argument("--no-refine", action="store_true", help="end with the part as made: do "
                   "not refine its shape (by default a pressure case's sealed part is refined "
                   "as 'pacto refine DIR' does, into DIR/refine/)")
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
    s.add_argument("--no-refine", action="store_true", help="as for run (without it, the "
                   "refinement replaces an earlier DIR/refine/)")
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
    """analyse, export, refine, compare: from a finished run to a part
    (pacto_ng.post.cli_commands, pacto_ng.post.refine_run, pacto_ng.post.compare)."""
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
    a.add_argument("--contact", action="store_true", help="the part's walls in frictionless "
                   "self-contact, so that they cannot pass through each other")
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
    _refine_parser(sub)
    c = sub.add_parser("compare", help="designs side by side and their analysis curves")
    c.add_argument("dirs", nargs="+", help="finished run folders")
    c.add_argument("--out", help="picture (default compare.png)")
    c.add_argument("--quiet", action="store_true")


def _refine_parser(sub):
    """refine: a finished pressure run's part, its shape refined (pacto_ng.post.refine_run)."""
    f = sub.add_parser("refine", help="refine the shape of a finished pressure run's part",
                       description="Make the part of a finished pressure run (2D or 3D) as "
                       "'pacto analyse' does and move its boundary to raise the output "
                       "displacement at the run's load with no more volume than the part "
                       "starts with and, for a mechanism, no lower Δ/SE (the clamp, the ports "
                       "and the symmetry lines held; the part remeshed when its mesh would "
                       "fold), then check it on an independent remesh; writes DIR/refine/ "
                       "(history.csv, summary.json, refined.vtu, refined.png, refined.stl).")
    f.add_argument("dir", help="a finished run folder (a pressure case, 2D or 3D)")
    f.add_argument("--steps", type=int, default=20, help="descent steps (default 20)")
    f.add_argument("--model", help="the material law of the part's analysis (default: the "
                   "run's), e.g. neohookean")
    f.add_argument("--load", type=float, help="the inlet pressure in the case's load unit "
                   "(default: the load the run reached)")
    f.add_argument("--load-type", choices=("fixed", "follower"), help="the wall pressure "
                   "fixed or following the deformation (default: the run's load_type)")
    f.add_argument("--pressures", help="comma-separated inlet pressures at which the refined "
                   "part is analysed afterwards (summary.json 'sweep'), e.g. 1e5,3e5,1e6")
    f.add_argument("--min-wall", type=float, help="no wall of the refined part thinner "
                   "than this (m): the descent is steered to keep the walls above it and a "
                   "step below it is refused (default: no floor; summary.json and the last "
                   "line report the thinnest wall either way)")
    f.add_argument("--contact", action="store_true", help="the part's walls in frictionless "
                   "self-contact, in its analysis and in the shape gradient (slower: each "
                   "equilibrium is solved again with the pairs sought anew until they hold)")
    f.add_argument("--check-gradients", action="store_true", help="instead of refining, "
                   "check the refinement's shape gradients (Δ, volume, and Δ/SE for a "
                   "mechanism) against central differences on the run's part; writes nothing; "
                   "exit code 1 if an error is above --tol")
    f.add_argument("--directions", type=int, default=3, help="with --check-gradients: the "
                   "random smooth directions checked (default 3)")
    f.add_argument("--tol", type=float, default=1e-5, help="with --check-gradients: the "
                   "largest relative error accepted (default 1e-5)")
    f.add_argument("--overwrite", action="store_true", help="replace the files of an earlier "
                   "DIR/refine/ (by default it is refused)")
    f.add_argument("--quiet", action="store_true", help="no progress lines")


def params_from_args(case, args) -> Parameters:
    """The case's parameters with the command line's options (``--model``, ``--maxh``, ...)
    and ``--set NAME=VALUE`` overrides (``--maxh`` alone sets nelx, nely, nelz to 0)."""
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
