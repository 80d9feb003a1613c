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
