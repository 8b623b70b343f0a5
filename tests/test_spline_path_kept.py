"""`spline_path` keeps the paths it made, by every bit of its inputs: a kept path answers
as one made afresh, bit for bit, and a call differing in any one input is not answered
by another's path."""

import numpy as np
import pytest

import cell.robot.spline as spline
from cell.robot.model import load_robot
from cell.robot.spline import spline_path

_S = np.linspace(0.0, 1.0, 257)


def _bits(path):
    """The path's configurations and their first two derivatives in s on a grid, as bytes
    (shape included)."""
    out = []
    for order in (0, 1, 2):
        q = np.asarray(path(_S, order), float)
        out.append((q.shape, q.tobytes()))
    return out


def _afresh(*args):
    spline._PATHS.clear()
    return _bits(spline_path(*args))


def _near_limit(robot, rng, side):
    """Three waypoints that turn back near joint 1's upper (side +1) or lower (-1) limit,
    the rest random: the cubic spline through them leaves the limit."""
    lim = robot.limits
    a, b, c = (rng.uniform(lim.lower + 0.5, lim.upper - 0.5) for _ in range(3))
    edge = lim.upper[0] if side > 0 else lim.lower[0]
    a[0], b[0], c[0] = edge - side * 1.0, edge - side * 0.001, edge - side * 0.3
    return np.array([a, b, c])


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_kept_path_is_the_path_made_afresh(name):
    robot = load_robot(name)
    lim = robot.limits
    rng = np.random.default_rng(7)
    calls = []
    for i in range(24):
        if i % 3 == 0:
            way = _near_limit(robot, rng, 1 if i % 2 else -1)
        else:
            k = int(rng.integers(2, 6))
            way = rng.uniform(lim.lower, lim.upper, size=(k, robot.dof))
        calls.append((way, lim.lower, lim.upper))
        calls.append((way,))
    spline._PATHS.clear()
    first = [_bits(spline_path(*c)) for c in calls]
    kept = [_bits(spline_path(*c)) for c in calls]  # every one answered by the memo
    limits = [(c[1], c[2]) if len(c) == 3 else (None, None) for c in calls]
    assert all(
        spline._path_key(np.array(c[0], float), *lim) in spline._PATHS
        for c, lim in zip(calls, limits, strict=True)
    )
    assert kept == first
    assert kept == [_afresh(*c) for c in calls]
    # the library's own answer: toppra's spline through the waypoints at their cumulative
    # joint-space distances, where no limit shapes it
    import toppra as ta

    for c in calls[1::2]:
        way = c[0]
        ss = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(way, axis=0), axis=1))])
        assert _bits(spline_path(way)) == _bits(ta.SplineInterpolator(ss / ss[-1], way))


def test_calls_differing_in_one_input_get_their_own_paths():
    # each pair differs in one of the key's fields and has different paths made afresh:
    # a key without that field would answer the second from the first's path
    robot = load_robot("ur5")
    lo, up = robot.limits.lower, robot.limits.upper
    rng = np.random.default_rng(3)
    w_up, w_lo = _near_limit(robot, rng, 1), _near_limit(robot, rng, -1)
    nudged = w_up.copy()
    nudged[1, 2] = np.nextafter(nudged[1, 2], np.inf)  # one bit of one waypoint
    pairs = [
        ((w_up, lo, up), (w_up, None, up)),  # the lower limit (given or not)
        ((w_up, lo, up), (w_up, lo, None)),  # the upper limit (given or not)
        ((w_up, lo, up), (w_up, lo, up + 1.0)),  # the upper limit's values
        ((w_lo, lo, up), (w_lo, lo - 1.0, up)),  # the lower limit's values
        ((w_up, lo, up), (nudged, lo, up)),  # the waypoints' bits
        ((w_up[:, :4], None, None), (w_up[:, :4].reshape(4, 3), None, None)),  # their shape
    ]
    for a, b in pairs:
        assert _afresh(*a) != _afresh(*b)
        spline._PATHS.clear()
        spline_path(*a)
        assert _bits(spline_path(*b)) == _afresh(*b)


def test_the_kept_paths_are_bounded():
    spline._PATHS.clear()
    rng = np.random.default_rng(1)
    for _ in range(spline._PATHS_MAX + 40):
        spline_path(rng.uniform(-1.0, 1.0, size=(3, 2)))
        assert len(spline._PATHS) <= spline._PATHS_MAX
