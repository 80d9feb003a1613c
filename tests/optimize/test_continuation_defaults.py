"""The continuation a case's defaults give.  pa-gripper-3d's and mm-gripper's final problems
(p = 3, β = 32) start early enough for their default runs to converge (docs/benchmarks.md,
"Convergence at defaults" and "3D cases at defaults": with the pa-inverter's continuation,
final from iteration 100 or 125 of 160, both stopped at the cap still improving)."""
from pacto_ng.case import get_case


def _schedule(case):
    params = get_case(case).defaults
    return params, params.schedule.schedule()


def test_pa_gripper_3d_leaves_100_iterations_to_the_final_problem():
    params, schedule = _schedule("pa-gripper-3d")
    assert schedule.final_at() == 60
    assert params.iterations - schedule.final_at() == 100
    assert schedule.values(59)[:2] == (3.0, 16.0)
    assert schedule.values(60)[:2] == (3.0, 32.0)
    assert abs(schedule.penalty(9) - 2.9) < 1e-12 and schedule.penalty(10) == 3.0
    assert _schedule("pa-inverter-3d")[1].final_at() == 100


def test_mm_gripper_leaves_75_iterations_to_the_final_problem_at_move_limit_0_1():
    params, schedule = _schedule("mm-gripper")
    assert schedule.final_at() == 85
    assert params.iterations - schedule.final_at() == 75
    assert schedule.values(84)[:2] == (3.0, 16.0)
    assert schedule.values(85)[:2] == (3.0, 32.0)
    assert params.move == 0.1
    assert _schedule("pa-gripper")[1].final_at() == 125
