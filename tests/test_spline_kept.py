"""`cell.robot.spline.spline_path` made once for the same waypoints and limits: the same
path object when asked again, and the path made afresh (`_spline_path`, nothing kept) for
every input, sample for sample, bit for bit: the cubic spline, the shape-preserving one
where the cubic leaves the limits, and another path for other waypoints or limits (of
the same count of numbers, laid out otherwise)."""

from __future__ import annotations

import numpy as np

from cell.robot import spline
from cell.robot.model import load_robot
from cell.robot.spline import _spline_path, spline_path


def _samples(path: object) -> bytes:
    s = np.linspace(0.0, 1.0, 301)
    return b"".join(np.asarray(path(s, k)).tobytes() for k in (0, 1, 2))  # type: ignore[operator]


def test_a_kept_spline_is_the_spline_made_afresh() -> None:
    rb = load_robot("panda")
    lim = rb.limits
    rng = np.random.default_rng(65)
    spline._SPLINES.clear()
    asked = []
    for i in range(40):
        k = 2 + i % 4
        way = rb.home + 0.6 * (rb.random_configuration(rng, k) - rb.home)
        if i % 5 == 0:  # turning back near joint 1's limit: the cubic overshoots it
            way[:, 0] = lim.upper[0] - np.array([1.0, 0.001, 0.3, 0.5, 0.2][:k])
        limits = (lim.lower, lim.upper) if i % 2 == 0 else (None, None)
        asked.append((way, limits))
    shaped = 0
    for _ in range(2):  # asked twice over: the second time every one is kept
        for way, limits in asked:
            path = spline_path(list(way), *limits)
            assert spline_path(way, *limits) is path
            fresh = _spline_path(way, *limits)
            assert _samples(path) == _samples(fresh)
            shaped += len(path.ss_waypoints) > len(way)
    assert shaped >= 4  # the shape-preserving path was among them
    # the same numbers as other waypoints (3 x 4 laid out as 4 x 3 of a 3-joint path, or
    # 2 x 6): another path
    flat = rng.uniform(-1.0, 1.0, 12)
    a, b = spline_path(flat.reshape(4, 3)), spline_path(flat.reshape(3, 4))
    assert a is not b and np.asarray(a(0.5)).shape == (3,) and np.asarray(b(0.5)).shape == (4,)
    # limits or none: other paths where the cubic leaves them
    way = asked[0][0]
    free, kept = spline_path(way), spline_path(way, lim.lower, lim.upper)
    assert free is not kept and _samples(free) == _samples(_spline_path(way, None, None))
