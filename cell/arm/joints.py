"""Pure functions of joint configurations [rad] that the arm's parts share: gaps, distinct
waypoints, how long a chain of moves takes.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


def joint_gap(qa: np.ndarray, qb: np.ndarray) -> float:
    """The largest joint move between two configurations [rad]."""
    return float(np.max(np.abs(np.asarray(qb) - np.asarray(qa))))


def distinct_waypoints(waypoints: list[np.ndarray]) -> list[np.ndarray]:
    """The waypoints [rad] without those equal to the one before (a spline needs distinct
    knots): the first, then each that moves a joint more than 1e-9 rad from its predecessor."""
    return [waypoints[0]] + [
        w for a, w in zip(waypoints, waypoints[1:], strict=False) if joint_gap(a, w) > 1e-9
    ]


GRIP_DOWN = (-math.pi / 2, 0.0)  # (elevation, azimuth) [rad] of the throw axis pointing down


# Where a carry starts, for planning it before the pick (`Orchestrator._departure`): the
# pick's configuration [rad], the item's centre there [m, W] (None: not known), the item and
# the stroke it is held at [m].
PickState = tuple[np.ndarray, np.ndarray | None, ObjectParams, float]


def plan_time(trajs: list[Any], settle_s: float) -> float:
    """How long [s] `_move` takes along `_move_plan`'s trajectories: their durations and a
    settle of `settle_s` [s] at each stop between them."""
    return sum(float(t.duration) for t in trajs) + settle_s * (len(trajs) - 1)


def clip(v: float, lim: float) -> float:
    return max(-lim, min(lim, v))
