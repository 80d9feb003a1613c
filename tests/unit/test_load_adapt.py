"""Adaptive load continuation in the optimisation loop (driver ``load_adapt``).

A stand-in problem whose "Newton" can carry a load factor of at most ``capacity(k)``: above it
the analysis fails with the load reached equal to the capacity, as the mechanics block reports.
"""
import numpy as np
import pytest

from pacto_ng.optimize.driver import LoopState, optimize
from pacto_ng.optimize.schedules import Schedule
from pacto_ng.physics.equilibrium import NewtonFailure
from pacto_ng.physics.newton import NewtonResult

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


class _Mech:
    def __init__(self):
        self.target = 1.0
        self.result = None


class CappedProblem:
    """min s (1 + Σ (x - 0.3)²)  s.t. mean(x) <= 0.5; loads above capacity(k) fail in Newton."""

    constraints = ("volume",)
    reports = ()

    def __init__(self, capacity, overshoot=1.0):
        self.capacity = capacity
        self.overshoot = overshoot  # a failure reports this multiple of the capacity reached
        self.mech = _Mech()
        self.k = 0
        self.asked = []  # (iteration, load factor asked for)
        self.values = {}

    def apply_schedule(self, penal, beta, load):
        self.mech.target = load

    def evaluate(self, x, gradients=True):
        cap = self.capacity(self.k)
        self.asked.append((self.k, self.mech.target))
        if self.mech.target > cap + 1e-15:
            res = NewtonResult(False, iterations=7, load_reached=min(cap * self.overshoot,
                                                                     self.mech.target * 0.999),
                               reason="stand-in failure")
            self.mech.result = res
            raise NewtonFailure(res)
        self.mech.result = NewtonResult(True, iterations=2, load_reached=self.mech.target, steps=1)
        f0 = (float(np.sum((x - 0.3) ** 2)) + 1.0) * self.mech.target
        f = np.array([x.mean() - 0.5])
        if not gradients:
            return f0, f
        self.k += 1
        return f0, f, 2 * (x - 0.3) * self.mech.target, np.full((1, x.size), 1.0 / x.size)

    def volume_fraction(self):
        return 0.5


def _run(problem, load_adapt, iterations=60):
    state = LoopState(k=0, x=np.full(6, 0.8), opt_state=None, scale=1.0)
    return optimize(problem, Schedule(), iterations=iterations, tol=5e-3, method="mma", move=0.1,
                    state=state, obj_tol=1e-3, load_adapt=load_adapt)


def capacity(k):
    """The design can carry 0.3 of the load at first, the full load from iteration 12 on."""
    return min(1.0, 0.3 + 0.06 * k)


def test_without_adaptation_the_first_failure_stops_the_run():
    result = _run(CappedProblem(capacity), load_adapt=0.0)
    assert result.stopped == "newton"
    assert result.state.k == 0 and "Newton failed" in result.message


def test_adaptive_continuation_goes_on_at_the_load_reached_and_returns_to_full_load():
    prob = CappedProblem(capacity)
    result = _run(prob, load_adapt=1.25)
    loads = [h["load"] for h in result.state.history]
    # never above what the design could carry, first at the capacity of iteration 0
    assert all(ld <= capacity(h["iteration"]) + 1e-12 for ld, h in zip(loads, result.state.history))
    assert loads[0] == pytest.approx(0.3)
    # after a failure the load is held for two iterations, then grows by the factor
    assert loads[1] == pytest.approx(0.3) and loads[2] == pytest.approx(0.3)
    assert loads[3] == pytest.approx(min(0.3 * 1.25, capacity(3)))
    # ... and the full load is reached again
    first_full = loads.index(1.0)
    assert 0 < first_full <= 20
    assert all(ld == 1.0 for ld in loads[first_full:])
    # the failed attempt's Newton iterations are counted (7 failed + 2 converged)
    assert result.state.history[0]["newton"] == 9
    # the run converges only at the full load, to the constrained optimimum x = 0.3
    assert result.converged and result.stopped == "converged"
    assert len(loads) - first_full >= 5
    np.testing.assert_allclose(result.state.x, 0.3, atol=1e-2)


def test_adaptive_continuation_reports_a_run_that_never_reaches_full_load():
    prob = CappedProblem(lambda k: 0.5)
    result = _run(prob, load_adapt=1.5, iterations=10)
    assert result.stopped == "iterations" and not result.converged
    assert "load factor 0.5 of the full load" in result.message
    assert max(h["load"] for h in result.state.history) == pytest.approx(0.5)


def test_adaptive_continuation_stops_when_nothing_is_carried():
    result = _run(CappedProblem(lambda k: 0.0), load_adapt=1.5)
    assert result.stopped == "newton" and result.state.k == 0


def test_a_retry_that_falls_short_again_retries_lower():
    """Near a limit point a fresh solve may not reach the load the failed one reported: the
    retries go on at least 5 % lower each time instead of stopping the run."""
    prob = CappedProblem(capacity, overshoot=1.02)
    result = _run(prob, load_adapt=1.25)
    assert result.stopped != "newton", result.message
    first = [ld for k, ld in prob.asked if k == 0]
    # 1.0 fails (reports 0.306), 0.306 fails (reports 0.306 -> 5 % lower: 0.2907) succeeds
    assert first[:2] == [1.0, pytest.approx(0.306)]
    assert first[2] == pytest.approx(0.95 * 0.306) and first[2] <= capacity(0)
    assert result.state.history[-1]["load"] == 1.0


def test_retries_give_up_after_three():
    """A design that can carry almost nothing from iteration 3 on, while every failed solve
    reports nearly its target reached: 1 + 4 attempts, each at least 5 % lower, then a clean
    stop with the last good design."""
    prob = CappedProblem(lambda k: 1.0 if k < 3 else 1e-3, overshoot=1e6)
    result = _run(prob, load_adapt=1.25)
    assert result.stopped == "newton" and result.state.k == 3
    asked = [ld for k, ld in prob.asked if k == 3]
    assert len(asked) == 5 and all(b <= 0.999 * a for a, b in zip(asked, asked[1:]))


class StepLimited:
    """min Σ (x - 0.9)²  s.t. mean(x) <= 0.8; on a design further than ``reach`` (max norm)
    from the last design it analysed, as a design step that opens a mechanism, "Newton" carries
    the load factor ``reached`` at most (0: none) and fails above it."""

    constraints = ("volume",)
    reports = ()

    def __init__(self, reach, reached=0.0):
        self.reach = reach
        self.reached = reached  # the load factor a failure reports carried (0: none)
        self.mech = _Mech()
        self.analysed = []  # the designs analysed, in order
        self.failed = 0
        self.restored = []  # (the warm start restored, the last analysed design) per cut
        self.values = {}

    def apply_schedule(self, penal, beta, load):
        self.mech.target = load

    def evaluate(self, x, gradients=True):
        far = self.analysed and np.max(np.abs(x - self.analysed[-1])) > self.reach
        if far and self.mech.target > self.reached * (1 + 1e-12):
            self.failed += 1
            res = self.mech.result = NewtonResult(False, iterations=5,
                                                  load_reached=self.reached * self.mech.target,
                                                  reason="every step length inverted an element")
            raise NewtonFailure(res)
        self.analysed.append(x.copy())
        self.mech.result = NewtonResult(True, iterations=2, load_reached=self.mech.target, steps=1)
        f0, f = float(np.sum((x - 0.9) ** 2)), np.array([x.mean() - 0.8])
        if not gradients:
            return f0, f
        return f0, f, 2 * (x - 0.9), np.full((1, x.size), 1.0 / x.size)

    def volume_fraction(self):
        return float(self.analysed[-1].mean())

    @property
    def warm(self):
        """Stands for the equilibria: which analysed design they belong to."""
        return len(self.analysed) - 1

    def set_warm(self, warm):
        self.restored.append((warm, len(self.analysed) - 1))


def _run_steps(problem, iterations=40):
    state = LoopState(k=0, x=np.full(6, 0.1), opt_state=None, scale=1.0)
    return optimize(problem, Schedule(), iterations=iterations, tol=1e-3, method="mma", move=0.2,
                    state=state, obj_tol=1e-6, load_adapt=1.2)


@pytest.mark.parametrize("reached", [0.0, 0.05])
def test_a_design_newton_cannot_analyse_is_moved_back_towards_the_last_good_one(reached):
    """Steps of the move limit (0.2) fail, carrying no load or 5 % of it; the driver halves
    them (0.1 <= reach 0.12) and the run goes on to the optimum at the full load, each cut
    recorded in its row (history.csv ``design_cuts``)."""
    prob = StepLimited(reach=0.12, reached=reached)
    result = _run_steps(prob)
    assert result.stopped == "converged", result.message
    assert prob.failed > 0
    rows = result.state.history
    cuts = [r["design_cuts"] for r in rows]
    assert sum(cuts) == prob.failed and max(cuts) == 1
    # every analysed design is within reach of the one before (the cut design is analysed)
    steps = [np.max(np.abs(b - a)) for a, b in zip(prob.analysed, prob.analysed[1:])]
    assert max(steps) <= 0.12
    # the mean is at its bound 0.8 (the unconstrained optimum 0.9 is not feasible)
    assert result.state.x.mean() == pytest.approx(0.8, abs=2e-3)
    assert all(r["load"] == 1.0 for r in rows)
    # each cut design starts from the last good design's equilibria
    assert len(prob.restored) == prob.failed and all(a == b for a, b in prob.restored)
    # the row's Newton count includes the failed attempts' (5 each)
    assert sum(r["newton"] for r in rows) == 2 * len(rows) + 5 * prob.failed


def test_after_three_cuts_the_run_stops_with_the_last_good_design():
    """A step that still fails when halved three times (0.2 / 8 = 0.025 > reach 0.01) stops
    the run cleanly: the message says so, the last analysed design is kept."""
    prob = StepLimited(reach=0.01)
    result = _run_steps(prob)
    assert result.stopped == "newton"
    assert "design step halved 3 times" in result.message
    assert prob.failed == 4  # the step, then three halvings
    np.testing.assert_array_equal(result.state.last_good, prob.analysed[-1])
    # the stopped run leaves the last good design's equilibria in place, for the final
    # analysis of that design (pacto_ng.runner); three cuts, then the stop
    assert len(prob.restored) == 4 and all(a == b for a, b in prob.restored)


class BetaLimited(StepLimited):
    """The same problem, but "Newton" fails when β exceeds 1.5 times the β of the last design
    it analysed (a sharper projection that opens a leak at once), having carried the load
    factor ``reached`` (0: none)."""

    def __init__(self, reached=0.0):
        super().__init__(reach=np.inf)
        self.beta = self.last_beta = None
        self.beta_failures = 0
        self.reached = reached

    def apply_schedule(self, penal, beta, load):
        self.beta = beta
        self.mech.target = load

    def evaluate(self, x, gradients=True):
        if self.last_beta is not None and self.beta > 1.5 * self.last_beta:
            self.beta_failures += 1
            res = self.mech.result = NewtonResult(False, iterations=4,
                                                  load_reached=self.reached * self.mech.target,
                                                  reason="every step length inverted an element")
            raise NewtonFailure(res)
        self.last_beta = self.beta
        return super().evaluate(x, gradients)


@pytest.mark.parametrize("reached", [0.0, 0.001])
def test_a_beta_step_newton_cannot_take_is_cut_and_held(reached):
    """β doubles every 3 iterations from 1 to 4; doublings fail, carrying no load or a
    thousandth of it.  The driver cuts each failed step to √2 (it does not lower the load),
    holds the cut β for BETA_HOLD (5) iterations, raises it by √2 at a time to the schedule's
    4, and the convergence test waits for that."""
    from pacto_ng.optimize.driver import BETA_HOLD

    prob = BetaLimited(reached)
    state = LoopState(k=0, x=np.full(6, 0.1), opt_state=None, scale=1.0)
    result = optimize(prob, Schedule(beta_start=1.0, beta_max=4.0, beta_every=3), iterations=60,
                      tol=1e-3, method="mma", move=0.2, state=state, obj_tol=1e-6, load_adapt=1.2)
    assert result.stopped == "converged", result.message
    betas = [r["beta"] for r in state.history]
    assert prob.beta_failures == 1  # the first doubling; the steps after it are √2
    assert max(b / a for a, b in zip(betas, betas[1:])) == pytest.approx(np.sqrt(2), rel=1e-12)
    levels = [1.0, np.sqrt(2), 2.0, 2 * np.sqrt(2), 4.0]
    runs = [sum(1 for b in betas if b == pytest.approx(v, rel=1e-12)) for v in levels]
    assert runs[0] == 3 and runs[1:4] == [BETA_HOLD] * 3 and runs[4] >= 6
    assert sum(runs) == len(betas)
    assert all(r["design_cuts"] == 0 and r["load"] == 1.0 for r in state.history)


def test_a_failure_that_carries_more_than_a_tenth_of_the_load_lowers_the_load_instead():
    """A failed design step that still carries half the load is not cut: the adaptive load
    continuation goes on at the load reached."""
    prob = StepLimited(reach=0.12, reached=0.5)
    result = _run_steps(prob, iterations=3)
    rows = result.state.history
    assert all(r["design_cuts"] == 0 for r in rows)
    assert rows[1]["load"] == pytest.approx(0.5)
