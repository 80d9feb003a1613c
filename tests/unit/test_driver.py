"""The optimisation loop's stopping test, its switch from MMA to GCMMA when MMA zigzags on the
final problem, and the best iterate it reports."""
import numpy as np
import pytest

from pacto_ng.optimize.driver import LoopState, _stalled, best_iterate, optimize, zigzag_at
from pacto_ng.optimize.schedules import Schedule


def _rows(objectives, **extra):
    return [dict(iteration=i, objective=f, penal=3.0, beta=1.0, load=1.0, constraint=-0.01,
                 **extra) for i, f in enumerate(objectives)]


def test_stalled_needs_every_one_of_the_last_five_changes_below_obj_tol():
    slow = [1.0 - 5e-4 * i for i in range(8)]           # 5e-4 per iteration
    assert _stalled(_rows(slow), 1e-3)
    zigzag = [1.0, 0.9, 1.0, 0.9, 1.0, 0.9, 1.0]        # a 2-cycle: never
    assert not _stalled(_rows(zigzag), 1e-3)
    jump = [1.0, 1.0, 1.0, 0.99, 0.99, 0.99, 0.99]      # one change of 1 % in the window
    assert not _stalled(_rows(jump), 1e-3)
    assert _stalled(_rows(jump + [0.99, 0.99]), 1e-3)    # ... which then left it
    assert not _stalled(_rows(slow[:5]), 1e-3)           # too few iterations to tell
    assert not _stalled(_rows(slow), 0.0)                # 0: off


def test_best_iterate_is_the_lowest_feasible_objective_of_the_final_problem():
    sched = Schedule(penal=3.0, penal_start=1.0, penal_step=1.0, beta_start=1.0, beta_max=4.0,
                     beta_every=1)
    rows = _rows([-1.0, -2.0, -3.0, -2.5, -2.9])
    rows[0]["penal"] = 2.0                              # an earlier problem: not compared
    rows[0]["objective"] = -9.0
    for r in rows:
        r["beta"] = 4.0
    rows[2]["constraint"] = 0.01                        # infeasible: not compared
    assert best_iterate(rows, sched, final_objective=-2.7) == {"iteration": 4, "objective": -2.9}
    assert best_iterate(rows, sched, final_objective=-2.95) is None
    assert best_iterate([], sched, final_objective=0.0) is None


class _Mech:
    target, result = 1.0, None


def test_zigzag_at_finds_the_first_two_cycle():
    assert zigzag_at([1.0, 0.9, 1.0, 0.9, 1.0]) == 4
    assert zigzag_at([1.0, 0.9, 0.8, 0.9, 0.8, 0.9]) == 5
    assert zigzag_at([1.0, 0.9, 0.8, 0.7, 0.6]) is None
    assert zigzag_at([1.0, 0.9, 1.0, 0.9]) is None          # three alternations only
    assert zigzag_at([1.0, 0.9, 0.9, 1.0, 0.9, 1.0]) is None  # a flat step is no alternation
    assert zigzag_at([1.0, 0.9, 0.9, 1.0, 0.9, 1.0, 0.9]) == 6


class Rugged:
    """min Σ cos(12 x_i) + 3 (x_i - 0.5)²  s.t. mean(x) <= 0.6: at a move limit of 0.5 MMA's
    steps cross the wells and the objective zigzags.  Counts the value-only evaluations
    (GCMMA's inner loop) per outer iteration."""

    constraints = ("volume",)
    reports = ()

    def __init__(self):
        self.mech, self.values, self.k = _Mech(), {}, 0
        self.inner = {}

    def apply_schedule(self, penal, beta, load):
        pass

    def volume_fraction(self):
        return 0.0

    def evaluate(self, x, gradients=True):
        f0 = float(np.sum(np.cos(12 * x) + 3 * (x - 0.5) ** 2)) + 20.0
        f = np.array([x.mean() / 0.6 - 1.0])
        if not gradients:
            self.inner[self.k] = self.inner.get(self.k, 0) + 1
            return f0, f
        self.k += 1
        return f0, f, -12 * np.sin(12 * x) + 6 * (x - 0.5), np.full((1, x.size), 1 / (0.6 * x.size))


#: the zigzag starts at iteration 17 (measured); 28 iterations leave MMA's last 8 in its 2-cycle
#: and GCMMA 10 updates to settle (mmapy's subsolver takes ~0.25 s per update on these 8
#: variables)
ITERATIONS = 28


def _run(method):
    prob = Rugged()
    state = LoopState(k=0, x=np.linspace(0.05, 0.95, 8), opt_state=None, scale=1.0)
    optimize(prob, Schedule(), iterations=ITERATIONS, tol=0.0, method=method, move=0.5, state=state,
             obj_tol=0.0)
    return prob, [r["objective"] for r in state.history]


def test_mma_gcmma_switches_to_gcmma_at_the_first_zigzag_and_settles():
    _, mma = _run("mma")
    first = zigzag_at(mma)
    assert first is not None                                 # MMA alone zigzags here ...
    assert zigzag_at(mma[-8:]) is not None                   # ... to the end
    prob, both = _run("mma-gcmma")
    start = zigzag_at(both)
    assert start == first and both[:start + 1] == mma[:start + 1]   # MMA up to the zigzag
    # GCMMA's inner loop evaluates values only: from the update after the zigzag on
    assert min(prob.inner) == start + 1 and sum(prob.inner.values()) >= ITERATIONS - start - 1
    # afterwards the objective does not rise by more than GCMMA's acceptance tolerance
    # (epsimin = 1e-7: an accepted step is conservative up to it)
    tail = both[start + 1:]
    assert all(b <= a + 1e-7 for a, b in zip(tail, tail[1:]))


class Reported(Rugged):
    """Rugged with a reported value (``delta``: the objective of the design analysed last) and
    the volume of the design analysed last, as a problem's ``values`` are: GCMMA's trial
    designs overwrite them.  ``fail_trials``: a value-only analysis fails as Newton does (the
    values then lack ``delta``)."""

    reports = ("delta",)

    def __init__(self, fail_trials=False):
        super().__init__()
        self.fail_trials, self.last, self.trials = fail_trials, None, 0

    def volume_fraction(self):
        return float(self.last.mean())

    def evaluate(self, x, gradients=True):
        from pacto_ng.physics.equilibrium import NewtonFailure
        from pacto_ng.physics.newton import NewtonResult

        self.last, self.values = x.copy(), {}
        self.trials += not gradients
        if not gradients and self.fail_trials:
            raise NewtonFailure(NewtonResult(False, iterations=3, load_reached=0.5))
        out = super().evaluate(x, gradients)
        self.values = {"delta": out[0]}
        return out


@pytest.mark.parametrize("fail_trials", [False, True])
def test_gcmma_rows_record_the_iterate_not_its_trial_designs(fail_trials):
    """Each history row's reports and volume are those of the iterate x_k, read before GCMMA
    analyses its trial designs (before: the last trial's; with a trial that fails, a
    KeyError)."""
    prob = Reported(fail_trials)
    x0 = np.linspace(0.05, 0.95, 8)
    state = LoopState(k=0, x=x0.copy(), opt_state=None, scale=1.0)
    optimize(prob, Schedule(), iterations=6, tol=0.0, method="gcmma", move=0.5, state=state,
             obj_tol=0.0)
    assert prob.trials >= 6  # the trials ran (and, failing, ended each loop)
    rows = state.history
    assert len(rows) == 6
    for r in rows:
        assert r["delta"] == r["objective"]
    assert rows[0]["volume"] == pytest.approx(x0.mean(), rel=1e-15)
