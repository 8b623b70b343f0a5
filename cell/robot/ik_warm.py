"""Warm starts for the release IK: the solutions of poses already solved, found by nearness.

A release search asks for many poses a few millimetres apart (the release bounds, the
rolls, the seeds of one plan; the same object thrown to the same spot item after item).
Where the search's first seed (the arm's configuration) misses, the cold search descends
from home and random seeds until three converge (~14 ms on the demo); a descent from the
solution of a pose within a millimetre or two converges in a few iterations instead
(`solve_ik`'s `warm`). `WarmStarts` keeps the solved poses, by roll, and gives the
solution of the nearest such pose within a distance and an angle. `FarPoses` keeps the
release poses a whole search missed by `ArmTuning.ik_out_of_reach_m` or more, and finds
one near a pose (the same distance and angle): a pose within 1 mm of one missed by 5 mm
or more is missed by 4 mm or more, out of reach on the same grounds.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cell.robot.ik_pose import ReleasePose

# the most solved poses a record keeps (all rolls together); cleared when full
WARM_KEPT_MAX = 4096


class _Poses:
    """The solved poses of one roll: positions [m, W], axes (unit) and solutions [rad],
    row by row, in arrays grown by doubling."""

    def __init__(self, n: int) -> None:
        self.count = 0
        self.payload: list[Any] = []
        self.position = np.empty((16, 3))
        self.axis = np.empty((16, 3))
        self.q = np.empty((16, n))

    def add(self, pose: ReleasePose, q: np.ndarray, payload: Any = None) -> None:
        if self.count == len(self.q):
            grow = len(self.q)
            self.position = np.concatenate([self.position, np.empty((grow, 3))])
            self.axis = np.concatenate([self.axis, np.empty((grow, 3))])
            self.q = np.concatenate([self.q, np.empty((grow, self.q.shape[1]))])
        self.position[self.count] = pose.position
        self.axis[self.count] = pose.axis
        self.q[self.count] = q
        self.payload.append(payload)
        self.count += 1

    def close(self, pose: ReleasePose, within_m: float, within_rad: float) -> np.ndarray:
        """The rows within `within_m` [m] of `pose`'s position and `within_rad` [rad] of
        its axis, in the order kept."""
        k = self.count
        gap = self.position[:k] - pose.position
        close = np.einsum("ij,ij->i", gap, gap) <= within_m * within_m
        close &= self.axis[:k] @ pose.axis >= math.cos(within_rad)
        return np.flatnonzero(close)


class _PoseRecord:
    """Poses kept by a key (a roll, and for `FarPoses` a search's rule), at most
    WARM_KEPT_MAX of them (all cleared when full), found by nearness: what `WarmStarts` and
    `FarPoses` share."""

    def __init__(self) -> None:
        self._by_key: dict[str, _Poses] = {}
        self._count = 0

    def __len__(self) -> int:
        return self._count

    def clear(self) -> None:
        self._by_key.clear()
        self._count = 0

    def _add(self, key: str, pose: ReleasePose, q: np.ndarray, payload: Any = None) -> None:
        if self._count >= WARM_KEPT_MAX:
            self.clear()
        self._by_key.setdefault(key, _Poses(q.shape[0])).add(pose, q, payload)
        self._count += 1

    def _close(
        self, key: str, pose: ReleasePose, within_m: float, within_rad: float
    ) -> tuple[_Poses, np.ndarray] | None:
        """The poses kept under `key` and the rows of those near `pose` (`_Poses.close`),
        or None where none is."""
        kept = self._by_key.get(key)
        if kept is None or kept.count == 0:
            return None
        rows = kept.close(pose, within_m, within_rad)
        return (kept, rows) if rows.size else None


class WarmStarts(_PoseRecord):
    """Solutions of release poses already solved, by roll (free, or fixed at a value), at
    most WARM_KEPT_MAX of them (all cleared when full)."""

    def add(self, pose: ReleasePose, q: np.ndarray) -> None:
        """Keep q [rad], a solution of `pose` (within the IK's tolerances)."""
        self._add(repr(pose.roll), pose, np.asarray(q, dtype=float))

    def near(
        self, pose: ReleasePose, q_ref: np.ndarray, within_m: float, within_rad: float
    ) -> np.ndarray | None:
        """The kept solution, of a pose at the same roll within `within_m` [m] of `pose`'s
        position and `within_rad` [rad] of its axis, nearest q_ref [rad] (the Euclidean
        norm of the joints' difference; the earliest kept of equals), or None."""
        found = self._close(repr(pose.roll), pose, within_m, within_rad)
        if found is None:
            return None
        kept, rows = found
        dq = kept.q[rows] - q_ref
        best = rows[int(np.argmin(np.einsum("ij,ij->i", dq, dq)))]
        return kept.q[best].copy()


class FarPoses(_PoseRecord):
    """Release poses a whole search missed by `ArmTuning.ik_out_of_reach_m` or more, each
    with its error (an IKNoSolution), by roll and the search's rule (a string: the give-up,
    reach and polish constants), at most WARM_KEPT_MAX of them (all cleared when full)."""

    def copy(self) -> FarPoses:
        """A record with the same poses, which adding to this one leaves as it is."""
        out = FarPoses()
        for kind, kept in self._by_key.items():
            mine = _Poses(0)
            mine.count = kept.count
            mine.position, mine.axis, mine.q = kept.position.copy(), kept.axis.copy(), kept.q
            mine.payload = list(kept.payload)
            out._by_key[kind] = mine
        out._count = self._count
        return out

    def add(self, pose: ReleasePose, rule: str, error: Any) -> None:
        """Keep `pose` as out of reach under `rule`, with the error its search raised."""
        self._add(repr(pose.roll) + rule, pose, np.empty(0), error)

    def near(self, pose: ReleasePose, rule: str, within_m: float, within_rad: float) -> Any:
        """The error of the earliest pose kept under `rule`, at the same roll, within
        `within_m` [m] and `within_rad` [rad] of `pose`, or None."""
        found = self._close(repr(pose.roll) + rule, pose, within_m, within_rad)
        if found is None:
            return None
        kept, rows = found
        return kept.payload[int(rows[0])]
