import pytest

from pacto_ng.optimize.schedules import Schedule


def test_wang_2014_schedule():
    s = Schedule(penal=3.0, penal_start=1.0, penal_step=0.05, beta_start=4.0, beta_max=64.0,
                 beta_every=10)
    assert s.penalty(0) == 1.0
    assert abs(s.penalty(20) - 2.0) < 1e-12
    assert s.penal_done() == 40 and s.penalty(40) == 3.0 and s.penalty(100) == 3.0
    assert s.beta(39) == 4.0 and s.beta(40) == 4.0 and s.beta(50) == 8.0 and s.beta(80) == 64.0
    assert s.beta(500) == 64.0 and s.beta(10 ** 9) == 64.0  # the final value, no overflow
    assert not s.settled(60) and s.settled(81)


def test_load_ramp_and_settling():
    s = Schedule(load_ramp=4)
    assert [s.load(k) for k in range(5)] == [0.25, 0.5, 0.75, 1.0, 1.0]
    assert not s.settled(2) and s.settled(4)


def test_bad_schedules():
    with pytest.raises(ValueError):
        Schedule(penal_start=1.0, penal_step=0.0)
    with pytest.raises(ValueError):
        Schedule(beta_max=8.0, beta_every=0)


def _rows(schedule, objectives, loads=None):
    """The driver's rows for a run whose iterations gave ``objectives``: each row records the
    β the schedule gave it from the rows before."""
    rows = []
    for k, f in enumerate(objectives):
        beta = schedule.beta(k, rows)
        rows.append(dict(iteration=k, objective=float(f), beta=beta,
                         load=1.0 if loads is None else loads[k]))
    return rows


def test_settled_stages_end_at_beta_every_when_the_objective_keeps_moving():
    fixed = Schedule(penal=3.0, penal_start=1.0, penal_step=0.5, beta_start=1.0, beta_max=16.0,
                     beta_every=10)
    adaptive = Schedule(penal=3.0, penal_start=1.0, penal_step=0.5, beta_start=1.0,
                        beta_max=16.0, beta_every=10, beta_settle=1e-3)
    falling = [1.0 - 0.01 * k for k in range(80)]  # 1 % of the objective per iteration
    rows = _rows(adaptive, falling)
    assert [r["beta"] for r in rows] == [fixed.beta(k) for k in range(80)]
    assert adaptive.final_values() == fixed.final_values() == (3.0, 16.0, 1.0)
    assert adaptive.settled(79, window=5, history=rows) and not adaptive.settled(
        43, history=rows)


def test_a_settled_stage_doubles_beta_after_six_iterations():
    s = Schedule(penal=3.0, beta_start=2.0, beta_max=8.0, beta_every=20, beta_settle=1e-3)
    # objective changes of 5e-4 relative: below 1e-3 from the first iteration on
    flat = [-1.0 - 5e-4 * k for k in range(30)]
    betas = [r["beta"] for r in _rows(s, flat)]
    # stage lengths: 6 iterations at β 2 (the five changes of its first six rows), 6 at β 4
    assert betas[:6] == [2.0] * 6 and betas[6:12] == [4.0] * 6 and betas[12:] == [8.0] * 18
    # one change of 2e-3 inside the window keeps the stage going until the window clears it
    bumped = [f - (2e-3 if k >= 3 else 0.0) for k, f in enumerate(flat)]
    betas = [r["beta"] for r in _rows(s, bumped)]
    assert betas[:9] == [2.0] * 9 and betas[9] == 4.0


def test_a_stage_does_not_settle_below_the_full_load():
    s = Schedule(penal=3.0, beta_start=2.0, beta_max=8.0, beta_every=12, beta_settle=1e-3,
                 load_ramp=10)
    flat = [-1.0] * 40
    loads = [s.load(k) for k in range(40)]
    betas = [r["beta"] for r in _rows(s, flat, loads)]
    # the ramp's rows (load < 1 up to iteration 8) hold β 2 for the full 12 iterations;
    # the next stage settles in six
    assert betas[:12] == [2.0] * 12 and betas[12:18] == [4.0] * 6 and betas[18] == 8.0
