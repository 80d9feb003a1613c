"""A port spring at a point against the same spring spread about it, on a run's part.

    python3 -m benchmarks.point_spring RUN_DIR [--maxh 0.7,0.5,0.35] [--spread 0,1]
        [--kind follower] [--no-spring]

The part of the finished run ``RUN_DIR`` is made as the run makes it (threshold 0.5, the run's
Darcy field for the wetted walls) at each element size ``--maxh`` (times the design's element
size h; the run's own part: 0.5) and analysed at the run's load (``--kind``: fixed or follower,
the run's by default; the run's model, order 2) with its output springs at the point
(``--spread 0``) and spread about it over ``--spread`` times h (:class:`~pacto_ng.physics.
loads.Spring`); ``--no-spring`` adds the analysis without them.  One line per analysis: the
part's elements, Δ, whether Newton reached the load (else the load it reached), Newton
iterations and seconds.  A point spring's Δ has no mesh limit; a spread one's settles.
"""
from __future__ import annotations

import argparse
import dataclasses
import time

from pacto_ng.post.part import make_part, part_ports, present_supports
from pacto_ng.post.part_analysis import PartAnalysis
from pacto_ng.post.runs import copy_gridfunction, load_run, rebuild
from pacto_ng.threads import compute


def floats(text: str) -> list[float]:
    return [float(v) for v in text.split(",")]


def analyse(problem, part, kind: str, ports) -> str:
    """One analysis of ``part`` at the run's load: its line."""
    setup = problem.setup
    ana = PartAnalysis(part.mesh, kind, params=problem.params.replace(order=2),
                       supports=present_supports(setup.supports, part.mesh), ports=ports)
    t0 = time.perf_counter()
    with compute():
        point = ana.solve(problem.params.load)
    reached = ("reached the load" if point.converged else
               f"NOT reached: equilibria up to {point.load_reached * problem.params.load:.5g}")
    return (f"Δ {point.delta:.5g} m, {reached}, {point.iterations} Newton iterations, "
            f"{time.perf_counter() - t0:.1f} s")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run")
    ap.add_argument("--maxh", type=floats, default=[0.7, 0.5, 0.35])
    ap.add_argument("--spread", type=floats, default=[0.0, 1.0])
    ap.add_argument("--kind", default=None)
    ap.add_argument("--no-spring", action="store_true")
    args = ap.parse_args(argv)
    run = load_run(args.run, "point_spring")
    with compute():
        problem = rebuild(run)
    kind = args.kind or run.params.load_type
    h, setup = float(problem.h), problem.setup
    print(f"{run.case.name}: h {h:g} m, load {run.load:g} ({kind}), the run's Δ "
          f"{run.summary.get('output_displacement')}")
    pressure = copy_gridfunction(problem.pressure_block.pressure)
    for share in args.maxh:
        part = make_part(problem, setup, maxh=share * h, pressure=pressure, p_in=run.load)
        head = f"maxh {share:g} h ({part.mesh.ne} elements)"
        for spread in args.spread:
            ports = tuple(dataclasses.replace(p, spread=spread * h) for p in part_ports(setup))
            print(f"{head}, spring spread {spread:g} h: {analyse(problem, part, kind, ports)}",
                  flush=True)
        if args.no_spring:
            ports = tuple(dataclasses.replace(p, spring=0.0) for p in part_ports(setup))
            print(f"{head}, no spring: {analyse(problem, part, kind, ports)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
