"""history.csv's ``newton`` and ``load_steps``: the Newton work each optimisation iteration did.

With GCMMA the inner loop analyses trial designs; the accepted one is the next iteration's
design, whose analysis then starts at its own equilibrium and needs no Newton iteration.  The
trial analyses' work belongs to the iteration that ran them (a row read ``newton 0`` for
iterations that took seconds of Newton solves).
"""
import numpy as np
import pytest

from pacto_ng.optimize.driver import LoopState, optimize
from pacto_ng.optimize.schedules import Schedule
from pacto_ng.physics.newton import NewtonResult

pytestmark = pytest.mark.usefixtures("pacto_one_thread")


class _Mech:
    def __init__(self):
        self.target, self.result, self.at = 1.0, None, None


class TwoRealisations:
    """min Σ cos(6 x_i) + 2 (x_i - 0.4)²  s.t. mean(x) <= 0.5, analysed by two stand-in mechanics
    blocks (as the robust realisations): each takes 0 Newton iterations at the design of its
    last equilibrium and ``its[i]`` elsewhere, in one load step.  It records the work of every
    analysis under the outer iteration it belongs to."""

    constraints = ("volume",)
    reports = ()
    its = (3, 4)

    def __init__(self):
        self.mechanics = [_Mech(), _Mech()]
        self.mech = self.mechanics[0]
        self.k = -1
        self.work = {}  # outer iteration -> [Newton iterations, load steps, analyses at 0]
        self.values = {}

    def apply_schedule(self, penal, beta, load):
        self.k += 1  # called once at the start of each outer iteration

    def evaluate(self, x, gradients=True):
        w = self.work.setdefault(self.k, [0, 0, 0])
        for m, its in zip(self.mechanics, self.its):
            again = m.at is not None and np.array_equal(m.at, x)
            m.result = NewtonResult(True, iterations=0 if again else its, load_reached=1.0,
                                    steps=1)
            m.at = x.copy()
            w[0] += m.result.iterations
            w[1] += m.result.steps
            w[2] += again
        f0 = float(np.sum(np.cos(6 * x) + 2 * (x - 0.4) ** 2))
        f = np.array([x.mean() - 0.5])
        if not gradients:
            return f0, f
        return (f0, f, -6 * np.sin(6 * x) + 4 * (x - 0.4),
                np.full((1, x.size), 1.0 / x.size))

    def volume_fraction(self):
        return 0.5


def test_gcmma_trial_analyses_count_in_their_iteration():
    prob = TwoRealisations()
    state = LoopState(k=0, x=np.linspace(0.1, 0.9, 8), opt_state=None, scale=1.0)
    optimize(prob, Schedule(), iterations=8, tol=0.0, method="gcmma", move=0.3, state=state)
    rows = state.history
    assert len(rows) == 8
    # the situation of the report: iterations whose own design's analyses took no Newton
    # iteration (an accepted trial design, already at equilibrium)
    assert sum(prob.work[k][2] for k in range(8)) >= 4
    for r in rows:
        newton, steps, _ = prob.work[r["iteration"]]
        assert (r["newton"], r["load_steps"]) == (newton, steps)
        assert r["newton"] > 0


def test_each_row_counts_the_tangent_solves_of_its_iteration(monkeypatch):
    """A real chain (the pa-inverter, 12 x 6 quads, Wang, GCMMA at a fixed penalty and β): each
    row's ``newton`` is the number of Newton tangent solves made between the end of the
    iteration before and the end of its own, counted at the solver."""
    from pacto_ng.case import build_problem, get_case
    from pacto_ng.physics.equilibrium import Equilibrium
    from pacto_ng.initial import initial_design

    solves = [0]
    solve = Equilibrium.solve_tangent

    def counted(self, rhs, out):
        solves[0] += 1
        return solve(self, rhs, out)

    monkeypatch.setattr(Equilibrium, "solve_tangent", counted)
    case = get_case("pa-inverter")
    params = case.defaults.replace(model="wang", nelx=12, nely=6, load_ramp=0, penal_start=0.0,
                                   beta=2.0, beta_max=0.0, iterations=6)
    problem = build_problem(case, params)
    state = LoopState(k=0, x=initial_design(problem), opt_state=None, scale=None)
    per_iteration = []

    def on_iteration(st, row):
        per_iteration.append(solves[0] - sum(per_iteration))

    optimize(problem, params.schedule.schedule(), iterations=6, tol=0.0, method="gcmma",
             move=0.1, state=state, on_iteration=on_iteration)
    rows = state.history
    assert [r["newton"] for r in rows] == per_iteration
    assert all(n > 0 for n in per_iteration)
