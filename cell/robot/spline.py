"""The geometric joint path through waypoints: a cubic spline, or the shape-preserving
cubic where that would leave the joint limits."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.robot.kept import Kept
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
    waypoints.

    Made once for the same waypoints and limits (`_SPLINES`): the same path object."""
    way = np.array(waypoints_q, float)
    key = repr(way.shape).encode() + way.tobytes()
    if lower is not None and upper is not None:
        key += np.asarray(lower, float).tobytes() + np.asarray(upper, float).tobytes()
    return _SPLINES.get(key, lambda: _spline_path(way, lower, upper))


# `spline_path`'s paths by the bytes of the waypoints (their shape too) and of the limits
# where they are given. The arm's route checks ask again for the splines they asked for
# before (a departure's rise from the station, its move, the twist of a carry): 107 of 287
# on tune layout 0's first 10 items, 0.4 ms each (scipy's CubicSpline and its two
# derivatives). A spline is the same for the same waypoints; nothing writes into one
# (`plan_path`'s own `_PATHS` shares them too). Bounded: cleared when full.
_SPLINES: Kept[Any] = Kept(256)


def _spline_path(way: np.ndarray, lower: np.ndarray | None, upper: np.ndarray | None) -> Any:
    """`spline_path` made: the waypoints `way` [rad], shape (k, dof)."""
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
