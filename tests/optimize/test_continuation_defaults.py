"""The continuation a case's defaults give.  pa-gripper-3d's and mm-gripper's final problems
(p = 3, β = 32) start early enough for their default runs to converge (docs/studies.md,
"Convergence at defaults" and "3D cases at defaults": with the pa-inverter's continuation,
final from iteration 100 or 125 of 160, both stopped at the cap still improving)."""
import pytest

from pacto_ng.case import get_case


def _schedule(case):
    params = get_case(case).defaults
    return params, params.schedule.schedule()


@pytest.mark.parametrize("case, final_at, left", [("pa-gripper-3d", 60, 100),
                                                   ("mm-gripper", 85, 75)])
def test_the_final_problem_starts_early_enough(case, final_at, left):
    params, schedule = _schedule(case)
    assert schedule.final_at() == final_at
    assert params.iterations - schedule.final_at() == left
    assert schedule.values(final_at - 1)[:2] == (3.0, 16.0)
    assert schedule.values(final_at)[:2] == (3.0, 32.0)


def test_what_the_shorter_continuations_change():
    pa3, schedule = _schedule("pa-gripper-3d")
    assert abs(schedule.penalty(9) - 2.9) < 1e-12 and schedule.penalty(10) == 3.0
    assert _schedule("mm-gripper")[0].move == 0.1
    # the cases they were measured against keep the longer continuation
    assert _schedule("pa-inverter-3d")[1].final_at() == 100
    assert _schedule("pa-gripper")[1].final_at() == 125


@pytest.mark.parametrize("case, latest_final, left", [("pneunet-3d", 200, 100)])
def test_settled_stages_leave_the_final_problem_room_even_if_none_ends_early(case,
                                                                            latest_final, left):
    """pneunet-3d's β stages end once settled (at the latest after beta_every); its final
    problem needed 55-80 iterations to converge (the case's docstring, docs/studies.md '3D
    cases at defaults')."""
    params, schedule = _schedule(case)
    assert schedule.beta_settle == 3e-3
    assert schedule.final_at() == latest_final
    assert params.iterations - schedule.final_at() == left
