"""A part's sweep past a pressure maximum: where Newton loses the equilibrium on its way to
a pressure (a chamber that balloons, an arch that snaps), the path is followed on from the
last equilibrium with the output's motion Δ prescribed (:func:`~pacto_ng.physics.path.trace`)
until the pressure is back up to the one asked or climbs again after falling, and Newton
goes on from there; the pressure maximum passed is reported
(:meth:`~pacto_ng.post.part_analysis.PartAnalysis.sweep`).  With contact the path's points
are paired anew until their pairs hold (tests/physics/test_contact_path.py)."""
from __future__ import annotations

import dataclasses

import numpy as np

from ..physics.equilibrium import WarmState
from ..physics.newton import NewtonResult
from ..physics.path import (PathFailure, PathPoint, climbs_again, load_maximum, retraces,
                             rising, trace)
from .sweep_result import SweepPoint

#: the path is followed in steps of this fraction of the output motion Newton reached, at
#: most PEAK_STEPS of them
PEAK_STEP, PEAK_STEPS = 0.1, 60
#: ... growing after easy steps to at most PEAK_GROWTH times the first
PEAK_GROWTH = 2.0
#: ... and a step of the path is halved down to this fraction of the first
PATH_FLOOR = 1.0 / 1024


def past_peak(analysis, failed: SweepPoint, last, say=None, record=None):
    """``(point, peak)`` of the part analysis ``analysis`` (a
    :class:`~pacto_ng.post.part_analysis.PartAnalysis`) after Newton lost the equilibrium
    on its way to ``failed.pressure``: the path from the last equilibrium it reached,
    followed with Δ prescribed (:func:`_path`) until the pressure is back up to the one
    asked, or climbs again after falling (:func:`~pacto_ng.physics.path.climbs_again`:
    walls that came to rest on each other, where Δ barely moves with the pressure); then
    Newton to that pressure from there (``past_peak``; its load ramped from the path's last
    pressure where needed, and so are the later pressures of the sweep from theirs); the
    pressure maximum passed on the way ({"pressure", "delta"}: Δ there, None if the
    pressure never fell); the failed point where the path does not get there within
    PEAK_STEPS steps.  The path starts from ``last`` ((pressure, state): the sweep's last
    equilibrium, or None) where Newton ended below its pressure.  ``say(line)`` gets one
    line per point of the path; ``record`` (a list) gets each point's pressure, Δ and
    chamber volume change."""
    mech, P = analysis.mech, abs(failed.pressure)
    x = mech.state_vector
    load = failed.load_reached * P
    if last is not None and last[0] > load:
        load, x.FV().NumPy()[:] = last
    reached = analysis.output_form.InnerProduct(x)
    if reached == 0.0:
        return failed, None
    seen = []  # this path's points: pressure, Δ and chamber volume change
    start = PathPoint(reached, load, 0, x.FV().NumPy().copy())
    earlier = [] if last is None or last[0] >= load else [  # the sweep's last equilibrium
        PathPoint(float(analysis.output_form.FV().NumPy() @ last[1]), last[0], 0, last[1])]
    path = _path(analysis, start, P, seen, say)
    if record is not None:
        record.extend(seen)
    # the maximum, also where Newton's ramp came up to it (the start its top)
    peak = load_maximum(earlier + [start] + path)
    if peak and retraces([q["pressure"] for q in seen], [q["volume_change"] for q in seen]):
        if say is not None:
            say(f"    the path turns back on itself at P = {peak[1]:.5g} (the chamber's "
                f"volume falls with the pressure): not a pressure maximum")
        peak = None
    if peak:  # the control is Δ
        peak = {"pressure": float(np.sign(failed.pressure) * peak[1]), "delta": peak[0]}
    loads = [start.load] + [q.load for q in path]
    if not path or not (loads[-1] >= P or climbs_again(loads)):
        return failed, peak
    # Newton at the pressure from the path's state; where the path went past the pressure,
    # from the state interpolated between its last two points at the pressure, its load ramped
    # from the one below.  From here on, a load ramp starts from the last equilibrium, never
    # from zero: past the maximum, a ramp from zero would meet it again (measured where it is
    # not needed, on the slotted slab of benchmarks/contact.py: 109 Newton iterations at 3 kPa
    # after 1 kPa, 37 from zero)
    below = loads[-1]
    if loads[-1] > P:  # the last point past P, the one before it below (the path's stop)
        before = ([start] + path)[-2]
        x.FV().NumPy()[:] = before.state + (P - before.load) / (loads[-1] - before.load) * (
            path[-1].state - before.state)
        below = before.load
    mech.settings = dataclasses.replace(mech.settings, ramp_from_last=True)
    mech.set_state(WarmState(x.FV().NumPy().copy(), True),
                   result=NewtonResult(True, load_reached=below))
    point = analysis.solve(failed.pressure)
    return dataclasses.replace(point, past_peak=point.converged and peak is not None), peak


def _path(analysis, start: PathPoint, P: float, seen: list, say=None) -> list:
    """The path from ``start`` (its state the block's) with Δ prescribed
    (:func:`~pacto_ng.physics.path.trace`, steps of PEAK_STEP of the Δ reached, in the
    direction in which the pressure rises there; by arc length where Δ turns back) until
    the pressure reaches ``P`` or climbs again after falling: its points (those found
    before a failure, which ``say`` is told).  Each point's pressure, Δ and chamber
    volume change go to ``seen``, and a line to ``say``."""
    mech, c, x = analysis.mech, analysis.output_form, analysis.mech.state_vector

    def line(q):  # the point's state is the block's
        dv = analysis.volume_change()
        seen.append({"pressure": float(q.load), "delta": float(q.control),
                     "volume_change": dv})
        if say is not None:
            how = " (by arc length)" if q.by_arc else ""
            vol = "" if dv is None else f", ΔV = {dv:.4g}"
            say(f"    on the path: Δ = {q.control:.5g}{vol} at P = {q.load:.5g}, "
                f"{q.iterations} Newton iterations{how}")

    loads = [start.load]

    def stop(q) -> bool:
        loads.append(q.load)
        return q.load >= P or climbs_again(loads)

    step = PEAK_STEP * abs(start.control) * rising(mech, x, start.load, c)  # on, not back
    try:
        return trace(mech, x, c, step,
                     dataclasses.replace(mech.settings, min_increment=PATH_FLOOR),
                     load=start.load, stop=stop, max_points=PEAK_STEPS,
                     max_step=PEAK_GROWTH * step, on_point=line,
                     dofs=mech.displacement_dofs)
    except PathFailure as err:
        if say is not None:
            say(f"    the path stops: {err}")
        return err.points
