"""The joint paths `cell.robot.spline.spline_path` keeps (by their waypoints and limits, bit
for bit) against paths made afresh.

A kept path must be the one making it again gives: evaluated here (positions and both
derivatives in s, at 1,001 parameters) against the path made with the memo emptied, float
for float; and waypoints or limits one bit off, or limits left out, must give a path of
their own, not the kept one. The waypoints include ones whose cubic spline leaves the
Panda's limits, so that the path with limits (the shape-preserving one) differs from the
path without them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import cell.robot.spline as spline
from cell.robot.model import load_robot

S = np.linspace(0.0, 1.0, 1001)


def _bits(path: Any) -> bytes:
    return b"".join(np.asarray(path(S, k)).tobytes() for k in (0, 1, 2))


def _afresh(way: np.ndarray, lower: Any, upper: Any) -> bytes:
    kept = dict(spline._PATHS)
    spline._PATHS.clear()
    try:
        return _bits(spline.spline_path(way, lower, upper))
    finally:
        spline._PATHS.clear()
        spline._PATHS.update(kept)


def _one_bit_off(a: np.ndarray, i: int) -> np.ndarray:
    b = np.array(a, float)
    flat = b.reshape(-1)
    flat[i] = np.nextafter(flat[i], np.inf)
    return b


def test_a_kept_path_is_the_one_made_afresh_and_one_bit_off_is_not_kept() -> None:
    robot = load_robot("panda")
    lower, upper = robot.limits.lower, robot.limits.upper
    rng = np.random.default_rng(5)
    shaped = 0
    for trial in range(20):
        k = int(rng.integers(2, 6))
        way = robot.home + 0.8 * (robot.random_configuration(rng, k) - robot.home)
        if trial % 2:  # a joint turning back just under its upper limit: the cubic overshoots
            j = int(rng.integers(0, robot.dof))
            way[:, j] = lower[j] + 0.3 * (upper[j] - lower[j])
            way[k // 2 :, j] = upper[j] - 1e-3
            way[-1, j] = upper[j] - 0.5
        first = spline.spline_path(way, lower, upper)
        again = spline.spline_path(list(way), lower.copy(), upper.copy())
        assert again is first
        assert _bits(again) == _afresh(way, lower, upper)
        plain = spline.spline_path(way)
        assert plain is spline.spline_path(way.copy())
        assert _bits(plain) == _afresh(way, None, None)
        if _bits(plain) != _bits(first):
            shaped += 1
        for other, args in (
            ("a waypoint", (_one_bit_off(way, int(rng.integers(0, way.size))), lower, upper)),
            ("lower", (way, _one_bit_off(lower, int(rng.integers(0, robot.dof))), upper)),
            ("upper", (way, lower, _one_bit_off(upper, int(rng.integers(0, robot.dof))))),
            ("no upper", (way, lower, None)),
        ):
            got = spline.spline_path(*args)
            assert got is not first, other
            assert _bits(got) == _afresh(*args), other
    assert shaped >= 5  # the limits made a difference to the path in enough cases
