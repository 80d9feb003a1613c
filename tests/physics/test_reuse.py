"""The bookkeeping of a preconditioner kept across designs (pacto_ng/physics/reuse.py): when it
is rebuilt and where a solve stops, followed by hand through a sequence of designs."""
from __future__ import annotations

from pacto_ng.physics.reuse import SETUP_ITERATIONS, Reuse


def test_rebuilt_once_the_iterations_lost_reach_a_set_up():
    r = Reuse()
    assert r.due and r.cap is None  # nothing built yet
    r.built()
    r.count(50)  # the design it was built at: two solves, the larger 50
    r.count(30)
    assert not r.due and not r.kept
    r.new_design()  # the reference: 80 iterations per design, 50 per solve
    assert r.kept and r.cap == max(2 * 50, 50 + SETUP_ITERATIONS)
    r.count(60)
    r.count(30)  # 90: 10 lost
    r.new_design()
    assert not r.due and r.kept_designs == 1
    r.count(80 + SETUP_ITERATIONS - 10)  # 10 + (SETUP - 10) lost: a set-up's worth
    r.new_design()
    assert r.due and r.kept_designs == 2
    r.built()
    assert not r.due and not r.kept and r.builds == 2


def test_a_design_with_fewer_iterations_loses_none():
    r = Reuse()
    r.built()
    r.count(70)
    r.new_design()
    for _ in range(5):
        r.count(40)  # the design settles: fewer iterations than at the set-up
        r.new_design()
    assert not r.due and r.kept_designs == 5


def test_a_rebuild_within_a_solve_keeps_the_reference_and_backs_off():
    r = Reuse()
    r.built()
    r.count(40)
    r.new_design()
    r.count(r.cap)  # the cap reached: rebuilt from the current matrix, CG goes on
    r.built(in_solve=True)
    r.count(5)
    assert r.rebuilt_in_solve == 1 and r.builds == 2 and not r.kept
    assert r.cap == max(2 * 40, 40 + SETUP_ITERATIONS)  # the reference of the last design
    r.new_design()  # that design paid a set-up, not lost iterations; the next is built afresh
    assert r.due and r.kept_designs == 0
    r.built()
    r.count(40)
    r.new_design()
    assert not r.due  # kept again
    r.count(r.cap)
    r.built(in_solve=True)  # a second cap in a row: two designs afresh
    r.new_design()
    for _ in range(2):
        assert r.due
        r.built()
        r.count(40)
        r.new_design()
    assert not r.due
    r.count(40)  # a design served through by a kept preconditioner ends the run of misses
    r.new_design()
    r.count(r.cap)
    r.built(in_solve=True)
    r.new_design()
    assert r.due
    r.built()
    r.new_design()
    assert not r.due  # one design afresh again, not four


def test_a_design_without_a_solve_sets_no_reference():
    r = Reuse()
    r.built()
    r.new_design()  # the same design again: no solve
    assert r.cap is None
    r.count(45)
    r.new_design()
    assert r.cap == max(2 * 45, 45 + SETUP_ITERATIONS)
