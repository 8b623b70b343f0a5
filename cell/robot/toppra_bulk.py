"""Two of toppra's steps done over whole arrays at once, bitwise as toppra does them one
point at a time in Python: the gridpoints it proposes along a path
(`toppra.interpolator.propose_gridpoints`) and the joint states of its constant-acceleration
parameterisation at many instants (`toppra.parametrizer.ParametrizeConstAccel.__call__`).

Each is the same arithmetic on the same numbers in the same order (a square taken as
Python's `x ** 2`, as toppra's NumPy scalars take it: not `np.square`, which rounds
differently in about one case in a thousand), so a plan is the same to the last bit; only
the Python loop over the points is gone. tests/test_toppra_bulk.py checks both against
toppra's own on random paths.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def _squares(x: np.ndarray) -> np.ndarray:
    """x² element by element as a NumPy float64 scalar's `** 2` gives it (C's pow)."""
    return np.array([v**2 for v in x.tolist()], dtype=float)


def propose_gridpoints(
    path: Any,
    max_err_threshold: float = 1e-4,
    max_iteration: int = 100,
    max_seg_length: float = 0.05,
    min_nb_points: int = 100,
) -> np.ndarray:
    """toppra's `propose_gridpoints` (same arguments, same gridpoints [path parameter]):
    halve every segment longer than `max_seg_length` or whose interpolation error
    estimate 0.5 max|p''(mid)| d² exceeds `max_err_threshold`, pass after pass, then
    halve every segment until there are `min_nb_points`; with each pass's second
    derivatives evaluated at all its midpoints in one call. ValueError as toppra's where
    the passes do not settle within `max_iteration`."""
    g = np.asarray(path.path_interval, dtype=float)[:2].copy()
    iteration = 0
    for iteration in range(max_iteration):  # noqa: B007 - checked after the loop, as toppra's
        mids = 0.5 * (g[:-1] + g[1:])
        dist = g[1:] - g[:-1]
        add = dist > max_seg_length
        check = ~add
        if np.any(check):
            dd = np.atleast_2d(path(mids[check], 2))
            err = np.max(np.abs(0.5 * dd * _squares(dist[check])[:, None]), axis=1)
            add[check] = err > max_err_threshold
        if not np.any(add):
            break
        g = np.sort(np.concatenate([g, mids[add]]))
    while len(g) < min_nb_points:
        g = np.sort(np.concatenate([g, 0.5 * (g[:-1] + g[1:])]))
    if iteration == max_iteration - 1:
        raise ValueError("Unable to find a good gridpoint for this path.")
    return g


def const_accel_states(raw: Any, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, dq, ddq), each shape (k, dof), of toppra's `ParametrizeConstAccel` `raw` at the
    times ts [s] (within its interval), as raw(ts, 0), raw(ts, 1) and raw(ts, 2) give them:
    the path parameter, its rate and its acceleration at each instant computed once (not
    three times, point by point), and the path's first derivative once (not twice)."""
    t_grid, u, v, s_grid = raw._ts, raw._us, raw._velocities, raw._ss
    idx = np.searchsorted(t_grid, ts, side="right") - 1
    idx[idx == len(u)] -= 1
    dt = ts - t_grid[idx]
    us, v0 = u[idx], v[idx]
    vs = v0 + dt * us
    ss = s_grid[idx] + dt * v0 + 0.5 * _squares(dt) * us
    path = raw._path
    d1 = path(ss, 1)
    q = path(ss)
    dq = np.multiply(d1, vs[:, np.newaxis])
    ddq = np.multiply(path(ss, 2), vs[:, np.newaxis] ** 2) + np.multiply(d1, us[:, np.newaxis])
    return q, dq, ddq
