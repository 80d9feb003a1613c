"""Following a path through a snap-back, where the prescribed displacement turns back
(pacto_ng.physics.path: displacement control, then arc length), against its closed form.

A load ``s`` pulls the free end ``v`` of a linear spring (stiffness ``k``) whose other end ``w``
hangs on a softening-stiffening spring of force ``N(w) = w - 3 w² + 2 w³``:

    N(w) - k (v - w) = 0,    k (v - w) - s = 0.

Along the path, parametrised by ``w``: ``s = N(w)`` and ``v = w + N(w) / k``.  The load peaks
at ``N' = 0``, ``w* = (3 - √3) / 6``, ``s* = N(w*)``; with ``k`` below ``-min N' = 1/2`` the
load point ``v`` turns back where ``N'(w) = -k``: prescribing ``v`` cannot pass there.
"""
import numpy as np
import pytest
from ngsolve import BaseVector

from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.path import PathFailure, climbs_again, load_maximum, retraces, trace

K = 0.2


def force(w):
    return w - 3.0 * w ** 2 + 2.0 * w ** 3


def stiffness(w):
    return 1.0 - 6.0 * w + 6.0 * w ** 2


class SnapBack:
    """The two-spring chain as the problem object the path follower drives."""

    free = np.array([True, True])

    def residual(self, x, out, s):
        w, v = x.FV().NumPy()
        out.FV().NumPy()[:] = [force(w) - K * (v - w), K * (v - w) - s]

    def assemble_tangent(self, x, s):
        w = x.FV().NumPy()[0]
        self.K = np.array([[stiffness(w) + K, -K], [-K, K]])

    def solve_tangent(self, rhs, out):
        out.FV().NumPy()[:] = np.linalg.solve(self.K, rhs.FV().NumPy())

    def admissible(self, x):
        return bool(np.all(np.isfinite(x.FV().NumPy())))

    def load_norm(self, s):
        return abs(s)


def turning_points():
    """``w`` where the load point turns: ``N'(w) = -K``."""
    return np.sort(np.roots([6.0, -6.0, 1.0 + K]).real)


@pytest.fixture
def start():
    x = BaseVector(2)
    x[:] = 0.0
    return x


SETTINGS = NewtonSettings(rtol=1e-12)
c = BaseVector(2)
c[:] = 0.0
c[1] = 1.0  # the control: the load point's displacement v


def test_prescribing_the_load_point_stops_where_it_turns_back(start):
    """Displacement control alone passes the load's maximum (v still grows there) and stops
    short of the load point's turning point, within 0.2 % of the closed form's: it does not
    jump to the far branch, where equilibria with a larger v exist."""
    with pytest.raises(PathFailure) as err:
        trace(SnapBack(), start, c, 0.05, SETTINGS, stop=lambda q: False, arc=False)
    reached = err.value.points[-1]
    w_turn = turning_points()[0]
    v_turn = w_turn + force(w_turn) / K
    assert v_turn * (1 - 2e-3) < reached.control <= v_turn
    assert all(q.state[0] < w_turn for q in err.value.points)
    assert max(q.load for q in err.value.points) > force(w_turn)  # past the load's maximum


def test_arc_length_follows_the_snap_back_to_the_load_beyond_the_maximum(start):
    """By arc length past the turning point: every point on the closed-form path, the load
    point moving back by as much as the closed form says, the load through its maximum and
    minimum and on to 1.5 times the maximum with no jump, the maximum reported to the sampling's
    accuracy."""
    w_star = (3.0 - np.sqrt(3.0)) / 6.0
    s_star = force(w_star)
    goal = 1.5 * s_star
    points = trace(SnapBack(), start, c, 0.05, SETTINGS, stop=lambda q: q.load >= goal,
                   max_points=400)
    w = np.array([q.state[0] for q in points])
    v = np.array([q.control for q in points])
    s = np.array([q.load for q in points])
    assert np.max(np.abs(s - force(w))) < 1e-12
    assert np.max(np.abs(v - (w + force(w) / K))) < 1e-10
    assert s[-1] >= goal and any(q.by_arc for q in points)
    # the load point went back by (nearly all of) the closed form's snap-back
    w_in, w_out = turning_points()
    v_back = (w_in + force(w_in) / K) - (w_out + force(w_out) / K)
    top = int(np.argmax(v[:np.argmin(s)]))
    assert v[top] - v[np.argmin(s)] > 0.9 * v_back
    # w advances along the whole path with no jump, through the load's minimum (-s*)
    assert np.all(np.diff(w) > 0) and np.max(np.diff(w)) < 0.2
    assert s.min() < -0.9 * s_star
    # the final point: the closed form's w where N(w) = s
    roots = np.roots([2.0, -3.0, 1.0, -s[-1]])
    assert w[-1] == pytest.approx(max(roots.real), rel=1e-10)
    # the maximum: the parabola through the largest sampled load and its neighbours (steps of
    # 0.05 in v growing to 0.4: 1.2 % low), the closed form's position between the neighbours
    at, peak = load_maximum(points)
    assert peak == pytest.approx(s_star, rel=1.5e-2)
    first = int(np.argmax(s[:np.argmin(s)]))
    assert v[first - 1] < w_star + s_star / K < v[first + 1]
    assert v[first - 1] < at < v[first + 1]


def test_a_path_whose_pressure_and_volume_fall_together_retraces_itself():
    """``retraces``: past a true pressure maximum of a closed chamber the volume goes on
    growing (the sphere's path, the balloon's); where it falls with the pressure the path is
    turning back on itself; without volumes nothing is said."""
    loads = [1.0, 2.0, 3.0, 2.5, 2.0]
    assert not retraces(loads, [0.1, 0.2, 0.3, 0.4, 0.5])
    assert retraces(loads, [0.1, 0.2, 0.3, 0.25, 0.2])
    assert not retraces(loads, [0.1, 0.2, None, 0.4, 0.5])


def test_a_path_climbs_again_once_its_load_rises_after_a_real_fall():
    """The valley past a maximum (walls that came to rest on each other): the load fell more
    than DROP below its largest and rises at the last point; the wiggles of arc length round
    a maximum are no fall."""
    assert not climbs_again([1.0, 2.0, 3.0])
    assert not climbs_again([190.0, 193.0, 190.0, 191.0])  # 1.6 % below the top
    assert not climbs_again([193.0, 150.0, 108.0, 107.0])  # still falling
    assert climbs_again([193.0, 150.0, 108.0, 109.0])
