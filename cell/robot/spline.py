"""The geometric joint path through waypoints: a cubic spline, or the shape-preserving
cubic where that would leave the joint limits."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.robot.trajectory import (
    POSITION_TOL_RAD,
)


def spline_path(
    waypoints_q: Sequence[np.ndarray],
    lower: np.ndarray | None = None,
    upper: np.ndarray | None = None,
) -> Any:
    """The geometric path through distinct joint waypoints [rad] that a move follows: a
    cubic spline (toppra's `SplineInterpolator`, C²), its parameter s ∈ [0, 1] at each
    waypoint proportional to the cumulative joint-space distance. Callable: path(s) gives
    configurations, path(s, 1) and path(s, 2) their derivatives in s.

    Through the waypoints themselves. Given joint limits `lower`/`upper` [rad] that this
    spline leaves between waypoints (it overshoots where a joint turns back near a limit),
    through 8 (else 16, 32: SHAPE_SAMPLES) points of each segment of the shape-preserving
    cubic instead (`monotone_samples`), which never leaves the range of two neighbouring
    waypoints: the spline keeps close to it, so within the limits unless a waypoint lies
    on one. Without limits, or when none stays within them, the spline through the
    waypoints."""
    way = np.array(waypoints_q, float)
    key = _path_key(way, lower, upper)
    found = _PATHS.get(key)
    if found is None:
        if len(_PATHS) >= _PATHS_MAX:
            _PATHS.clear()
        found = _spline_path(way, lower, upper)
        _PATHS[key] = found
    return found


# The paths made so far, by every bit of their inputs (`_path_key`): a decision asks again
# for the spline through waypoints an earlier one asked for (a carry timed again at another
# scale, a route checked again), and the same waypoints and limits are the same spline
# (scipy's `CubicSpline`, deterministic). Every caller gets the same object: nothing in the
# cell or in toppra writes into a path. Bounded: cleared when full.
_PATHS: dict[tuple[Any, ...], Any] = {}
_PATHS_MAX = 512


def _path_key(way: np.ndarray, lower: Any, upper: Any) -> tuple[Any, ...]:
    """`spline_path`'s inputs as a key: the waypoints [rad] (float64, their shape and
    bytes) and each limit's shape and bytes as float64 (None where not given), the values
    `_within` compares with (it subtracts a float from each limit)."""

    def limit(x: Any) -> tuple[Any, ...] | None:
        if x is None:
            return None
        a = np.asarray(x, float)
        return (a.shape, a.tobytes())

    return (way.shape, way.tobytes(), limit(lower), limit(upper))


def _spline_path(way: np.ndarray, lower: Any, upper: Any) -> Any:
    """`spline_path` made afresh through the waypoints `way` (float64, shape (k, dof))."""
    import toppra as ta

    seg = np.linalg.norm(np.diff(way, axis=0), axis=1)
    ss = np.concatenate([[0.0], np.cumsum(seg)])
    ss /= ss[-1]
    cubic = ta.SplineInterpolator(ss, way)
    if lower is None or upper is None or _within(cubic, lower, upper):
        return cubic
    for per_segment in SHAPE_SAMPLES:
        shaped = ta.SplineInterpolator(*monotone_samples(ss, way, per_segment))
        if _within(shaped, lower, upper):
            return shaped
    return cubic


# points per segment of the shape-preserving cubic that `spline_path` fits a spline
# through, fewest first: the spline's overshoot shrinks as the points close in
SHAPE_SAMPLES = (8, 16, 32)


def monotone_samples(
    ss: np.ndarray, way: np.ndarray, per_segment: int
) -> tuple[np.ndarray, np.ndarray]:
    """(parameters, configurations [rad]) of `per_segment` evenly spaced points of each
    segment of the shape-preserving piecewise cubic through the waypoints (Fritsch and
    Carlson's, scipy's `PchipInterpolator`, per joint), the waypoints among them: between
    two waypoints no joint leaves the range of their values."""
    from scipy.interpolate import PchipInterpolator

    s = np.concatenate(
        [
            np.linspace(a, b, per_segment, endpoint=False)
            for a, b in zip(ss[:-1], ss[1:], strict=True)
        ]
        + [ss[-1:]]
    )
    return s, np.asarray(PchipInterpolator(ss, way, axis=0)(s))


def _within(path: Any, lower: np.ndarray, upper: np.ndarray, n: int = 400) -> bool:
    """Does the path stay within [lower, upper] (POSITION_TOL_RAD) on n samples?"""
    qs = path(np.linspace(0.0, 1.0, n))
    return bool(np.all(qs >= lower - POSITION_TOL_RAD) and np.all(qs <= upper + POSITION_TOL_RAD))
