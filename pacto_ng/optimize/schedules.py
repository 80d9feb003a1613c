"""Continuation schedules of the outer iteration ``k``.

A :class:`Schedule` gives the SIMP penalty ``p(k)``, the projection sharpness ``β(k)`` and the
load factor ``s(k)``.  Wang et al. (2014) — p from 1 to 3 in steps of 0.05 per iteration, then
β from 4 to 64 doubling every 10 iterations — is ``Schedule(penal=3, penal_start=1,
penal_step=0.05, beta_start=4, beta_max=64, beta_every=10)``.  The driver's convergence test
restarts whenever a value changes (:meth:`Schedule.settled`), so a run cannot stop
mid-continuation.

The penalty and the load are functions of ``k`` alone.  β is one too, unless ``beta_settle``
> 0: then a β stage also ends as soon as it has settled — each of the objective's last
``SETTLE_WINDOW`` changes, at the full load, below ``beta_settle`` relative — and at the
latest after ``beta_every`` iterations.  β then depends on the run's history (the rows the
driver records, each with the β it used), which every caller passes: the rows of the
iterations before ``k``, or more.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..settings import Settings, setting

#: objective changes a β stage must hold below ``beta_settle`` to end early (the driver's
#: stopping test looks at as many)
SETTLE_WINDOW = 5


@dataclass(frozen=True)
class Schedule:
    penal: float = 3.0  # final penalty
    penal_start: float | None = None  # None: no penalty continuation
    penal_step: float = 0.0
    penal_every: int = 1
    beta_start: float = 1.0  # projection sharpness (0: no projection)
    beta_max: float | None = None  # None: constant beta
    beta_every: int = 0  # a β stage's length (with beta_settle: its largest length)
    beta_settle: float = 0.0  # a β stage ends once settled to this (0: after beta_every)
    load_ramp: int = 0  # iterations over which the load factor rises to 1 (0: full load)

    def __post_init__(self):
        if self.penal <= 0:
            raise ValueError("penal must be positive")
        if self.penal_start is not None and (self.penal_step <= 0 or self.penal_start > self.penal):
            raise ValueError("penalty continuation needs penal_step > 0 and penal_start <= penal")
        if self.penal_every < 1:
            raise ValueError("penal_every must be >= 1")
        if self.beta_start < 0:
            raise ValueError("beta must be >= 0")
        if self.beta_max is not None and self.beta_every < 1:
            raise ValueError("beta continuation needs beta_every >= 1")
        if self.load_ramp < 0:
            raise ValueError("load_ramp must be >= 0")
        if self.beta_settle < 0:
            raise ValueError("beta_settle must be >= 0")

    def penal_done(self) -> int:
        """First iteration at which the penalty has its final value."""
        if self.penal_start is None:
            return 0
        steps = math.ceil((self.penal - self.penal_start) / self.penal_step - 1e-9)
        return steps * self.penal_every

    def final_at(self) -> int:
        """First iteration at which the penalty and β have their final values (with
        ``beta_settle``, the latest such iteration)."""
        k = self.penal_done()
        if self.beta_max is not None and self.beta_start > 0 and self.beta_max > self.beta_start:
            k += self.beta_every * math.ceil(math.log2(self.beta_max / self.beta_start) - 1e-9)
        return k

    def penalty(self, k: int) -> float:
        if self.penal_start is None:
            return self.penal
        return min(self.penal, self.penal_start + self.penal_step * (k // self.penal_every))

    def beta(self, k: int, history=()) -> float:
        """β of iteration ``k``; with ``beta_settle``, from ``history`` (the driver's rows of
        the iterations before ``k`` at least: the β a row records is the one it used)."""
        if self.beta_max is None or self.beta_start == 0:
            return self.beta_start
        k0 = self.penal_done()
        if k < k0:
            return self.beta_start
        if self.beta_settle > 0:
            return self._beta_settled(k, k0, history)
        doublings = min((k - k0) // self.beta_every, 1000)  # no float overflow for huge k
        return min(self.beta_max, self.beta_start * 2.0 ** doublings)

    def _beta_settled(self, k: int, k0: int, history) -> float:
        if k < len(history) and history[k]["iteration"] == k:  # the β this iteration used
            return history[k]["beta"]
        rows = [r for r in history if k0 <= r["iteration"] < k]
        if not rows:
            return self.beta_start
        last = rows[-1]["beta"]
        stage = 0  # iterations the current β has run for
        while stage < len(rows) and rows[-1 - stage]["beta"] == last:
            stage += 1
        if last == self.final_beta() or stage < min(self.beta_every, SETTLE_WINDOW + 1):
            return last
        tail = rows[-SETTLE_WINDOW - 1:]
        f = np.array([r["objective"] for r in tail])
        settled = (all(r["load"] >= 1.0 for r in tail) and
                   np.max(np.abs(np.diff(f))) < self.beta_settle * max(abs(f[-1]), 1e-300))
        if stage >= self.beta_every or settled:
            return min(self.beta_max, 2.0 * last)
        return last

    def final_beta(self) -> float:
        return self.beta(10 ** 9) if self.beta_settle == 0 else (
            self.beta_start if self.beta_max is None or self.beta_start == 0 else self.beta_max)

    def load(self, k: int) -> float:
        if self.load_ramp <= 0:
            return 1.0
        return min(1.0, (k + 1) / self.load_ramp)

    def values(self, k: int, history=()) -> tuple[float, float, float]:
        """``(p, β, s)`` of iteration ``k`` (``history``: see :meth:`beta`)."""
        return self.penalty(k), self.beta(k, history), self.load(k)

    def final_values(self) -> tuple[float, float, float]:
        """The values of the final problem."""
        return self.penal, self.final_beta(), 1.0

    def settled(self, k: int, window: int = 1, history=()) -> bool:
        """True when the values have not changed over the last ``window`` iterations and are
        final (the convergence test may run)."""
        now = self.values(k, history)
        if any(abs(a - b) > 1e-12 for a, b in zip(now, self.final_values())):
            return False
        return all(self.values(max(k - j, 0), history) == now for j in range(window + 1))


@dataclass(frozen=True)
class ScheduleSettings(Settings):
    """The continuation of the SIMP penalty, the projection's β and the load factor."""

    penal: float = setting(3.0, "", "SIMP penalty p (final value)", range="(0, 20]")
    penal_start: float = setting(0.0, "", "penalty continuation start (0: none)",
                                 range="[0, 20]")
    penal_step: float = setting(0.05, "", "penalty increment per penal_every iterations",
                                range="(0, 20]")
    penal_every: int = setting(1, "", "iterations between penalty increments",
                               range="[1, 100000]")
    beta: float = setting(1.0, "", "projection sharpness β (start value; 0: no projection)",
                          range="[0, 1e4]")
    beta_max: float = setting(0.0, "", "final β of the doubling schedule (0: constant β)",
                              range="[0, 1e4]")
    beta_every: int = setting(10, "", "iterations between β doublings (with beta_settle: at "
                              "most)", range="[1, 100000]")
    beta_settle: float = setting(0.0, "", "double β as soon as the objective's last 5 changes "
                                 "at the full load are each below this (relative), after at "
                                 "least 6 iterations at that β (0: every beta_every)",
                                 range="[0, 1]")
    load_ramp: int = setting(-1, "", "iterations over which the load rises to full (0: none; "
                             "-1: chosen from the load, one iteration per 1 % of linear strain "
                             "the load causes, ending no later than the penalty and β "
                             "continuation and before the last iteration; none for the "
                             "linear model)", range="[-1, 100000]")

    def check(self):
        if self.penal_start > self.penal:
            raise InputError(f"penal_start: must not exceed penal ({self.penal_start:g} > "
                             f"{self.penal:g})")

    def schedule(self) -> Schedule:
        """The schedule these settings describe.  ``load_ramp=-1`` is resolved by ``pacto
        run`` (:func:`pacto_ng.auto.choose`); unresolved (a single analysis), it means the
        full load."""
        return Schedule(penal=self.penal,
                        penal_start=self.penal_start if self.penal_start > 0 else None,
                        penal_step=self.penal_step, penal_every=self.penal_every,
                        beta_start=self.beta, beta_max=self.beta_max if self.beta_max > 0 else None,
                        beta_every=self.beta_every, beta_settle=self.beta_settle,
                        load_ramp=max(self.load_ramp, 0))
