"""The mover: the only part of the arm that steps the plant. It times and follows the arm's
moves; after each it calls the hook the loop handed it (`on_moved`), which scores the
flights that have come to rest.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.grip_limits import (
    carry_hold,
)
from cell.arm.joints import plan_time, spline_within_limits
from cell.errors import (
    TrajectoryError,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


def stops_bound_s(
    robot: Any, q_from: np.ndarray, waypoints: list[np.ndarray], settle_s: float
) -> float:
    """A lower bound [s] on how long a move from q_from stopping at each of the waypoints
    [rad] takes (`plan_time` of `Mover._stops`): each stretch from rest to rest no
    quicker than its slowest joint's bang-bang time at `robot`'s full velocity and
    acceleration limits (as `_cycle_bound_s` bounds a cycle: a carry's limits are these or
    a fraction of them), and the settles of `settle_s` [s] between. Where it is no sooner
    than the path through them, `_move_plan` keeps the path without planning the stops:
    they would not be taken (tests/test_stops_bound.py)."""
    lim = robot.limits
    v, a = lim.velocity * (1 + 1e-3), lim.acceleration * (1 + 1e-3)
    d = np.abs(np.diff(np.asarray([q_from, *waypoints], float), axis=0))
    t = np.where(d <= v * v / a, 2.0 * np.sqrt(d / a), d / v + v / a)
    return float(np.sum(np.max(t, axis=1))) + settle_s * (len(waypoints) - 1)


def _joint_bytes(qs: list[np.ndarray]) -> bytes:
    """Joint waypoints [rad] as one key: their float64 bytes, in order."""
    return b"".join(np.asarray(q, float).tobytes() for q in qs)


class Mover(ArmBase):
    """The mover (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def move(self, waypoints: list[np.ndarray], settle_s: float | None = None) -> float:
        """Follow a toppra path through joint waypoints in the scene; returns its duration [s].

        Empty, the path uses `speed_scale` of the joint limits; carrying, the
        fastest time-scaling of it whose item acceleration the grip holds
        (`cell.robot.carry`).

        Where the cubic spline through the waypoints would leave the joint limits, the path
        keeps to the shape-preserving one (`cell.robot.motion.spline_path`) and is timed
        as a whole; stopping at each waypoint is timed too, each stretch at its own pace,
        and the sooner of the two is taken (a carry is slowed to its hardest stretch all
        along: on random layout 2, one path took 0.6-0.7 s longer than the stops for two
        of the three such carries). When no path through them is found, the arm stops at
        each.
        """
        settle_s = self.tuning.settle_s if settle_s is None else settle_s
        trajs = self._move_plan(self.q, waypoints, settle_s)
        ends = waypoints if len(trajs) > 1 else waypoints[-1:]
        return sum(self.follow(t, w, settle_s) for t, w in zip(trajs, ends, strict=True))

    def _move_plan(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        settle_s: float,
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[Any]:
        """The trajectories `move` follows from q_from through the waypoints [rad]: the
        one path, or one per waypoint when it stops at each (`move`'s choice, a settle of
        `settle_s` [s] at each stop). `carried`: the item and its stroke [m] carried
        (default: what the grip holds)."""
        path: Any = None
        try:
            path = self._path(q_from, waypoints, carried)
        except TrajectoryError:
            if len(waypoints) < 2:
                raise
        if len(waypoints) >= 2 and (
            path is None or spline_within_limits(self.robot, [q_from, *waypoints], 400) is None
        ):
            if path is not None and stops_bound_s(self.robot, q_from, waypoints, settle_s) >= (
                path.duration
            ):
                return [path]  # stopping at each cannot be sooner: not planned
            stops = self._stops(q_from, waypoints, carried)
            t_stops = plan_time(stops, settle_s)
            if path is None or t_stops < path.duration:
                return stops
        return [path]

    def _path(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float] | None = None,
    ) -> Any:
        """The trajectory of a move from q_from through the waypoints [rad]: empty, at
        `speed_scale` of the joint limits; carrying (`carried`, else what the grip
        holds), the fastest the grip holds the item along (`_carry_path`).
        TrajectoryError when there is none."""
        from cell.robot.motion import plan_path

        if carried is None and self.ee.item is None:
            qs = [q_from, *waypoints]
            return self._planned(
                ("empty", _joint_bytes(qs), self.speed_scale),
                lambda: plan_path(
                    qs,
                    self.robot,
                    velocity_scale=self.speed_scale,
                    acceleration_scale=self.speed_scale,
                ),
            )
        return self._carry_path([q_from, *waypoints], carried)

    def _planned(self, key: tuple[Any, ...], plan: Callable[[], Any]) -> Any:
        """`plan()`, remembered under `key` until the next decision (`decide` clears it,
        as `_solve_ik`): a path through the same waypoints [rad] (the same bytes) with the
        same limits and hold is the same trajectory, or the same TrajectoryError (toppra
        and the carry's bisection are deterministic). The decision times the carries and
        the routes the execution then takes, from the same configurations; `_static_carry`
        times the route `_departure` chose by timing it. Every caller gets the same
        Trajectory: nothing in the cell writes into one."""
        found = self._plan_memo.get(key)
        if found is None:
            try:
                found = plan()
            except TrajectoryError as exc:
                found = exc
            self._plan_memo[key] = found
        if isinstance(found, Exception):
            raise found
        return found

    def _stops(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[Any]:
        """The trajectories of a move that stops at each waypoint: a straight joint-space
        stretch each, which stays inside the joint limits' box."""
        out, q = [], q_from
        for w in waypoints:
            out.append(self._path(q, [w], carried))
            q = w
        return out

    def follow(self, traj: Any, q_end: np.ndarray, settle_s: float) -> float:
        """Step the scene along a joint trajectory ending at rest at q_end [rad], then
        `settle_s` [s] more; returns the time taken [s]."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        ts = np.arange(sc.dt_s, traj.duration + sc.dt_s, sc.dt_s)
        qs, _, _ = traj.sample_many(ts)
        for q in qs.tolist():  # each row as Python floats, the values `set_arm` sends
            sc.set_arm(q)
            sc.step()
        if settle_s > 0:
            sc.run_for(settle_s)
        self.q = np.asarray(q_end, float)
        self.on_moved()
        return float(traj.duration) + settle_s

    def _carry_path(
        self, waypoints: list[np.ndarray], carried: tuple[ObjectParams, float] | None = None
    ) -> Any:
        """The fastest path through the waypoints (the first: where the arm starts) that
        the grip holds the item along (`carried`: the item and its stroke [m]; default:
        the one in the grip).

        A mesh thrown at the probe's couple (`carry_hold`) is never carried slower than at
        GENTLE_SCALE, as it was without that couple: where its path at rest asks nearly
        all the bound allows, the fastest uniform carry within it crawls (three eggs on
        random layout 11, UR5: 29 s a cycle without this floor, 8.6 s with it, 6.1-6.9 s
        before the probe's couple)."""
        from cell.arm.grip_limits import carry_safety
        from cell.robot.carry import CARRY_MARGIN, plan_carry

        obj, stroke = carried or (self._carried[0], self._grip_stroke)
        hold = carry_hold(
            self.params, obj, stroke, probed=self._seated_as_probed(), placing=self._placing
        )
        tie = self._over_bound(obj)
        gentle = obj.shape == "mesh" and hold.torque_nm > 0.0 and not self._placing
        margin = carry_safety(obj, self.tuning) if obj.shape == "sphere" else CARRY_MARGIN
        key = ("carry", _joint_bytes(waypoints), hold, margin, self.speed_scale, tie, gentle)
        return self._planned(
            key,
            lambda: plan_carry(
                waypoints,
                self.robot,
                hold,
                margin=margin,
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
                tie=tie,
                gentle_floor=gentle,
            )[0],
        )

    def _straight(
        self,
        q_to: np.ndarray,
        duration_s: float,
        stop: Callable[[], bool] | None = None,
        *,
        smooth: bool = False,
    ) -> float:
        """A short move along the joint-space segment to q_to in `duration_s` [s] (nearby
        configurations: the grip moves on a near-straight line), at constant speed or with
        a smooth start and stop (3τ² − 2τ³); it ends early when `stop()` says so (a guarded
        move). Returns the fraction of the segment done (1.0: all of it)."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        q0 = self.q.copy()
        n = max(1, math.ceil(duration_s / sc.dt_s))
        done = 1.0
        for k in range(1, n + 1):
            tau = k / n
            done = tau * tau * (3 - 2 * tau) if smooth else tau
            self.q = q0 + (q_to - q0) * done
            sc.set_arm(self.q.tolist())
            sc.step()
            if stop is not None and stop():
                break
        return done

    def _wait_at_rest(self, item: Any, timeout_s: float = 1.0) -> None:
        """Step until the item rests (below 2 mm/s and 0.05 rad/s) or `timeout_s` [s]."""
        sc = self.scene
        t_end = sc.t + timeout_s
        while sc.t < t_end:
            v, w = sc.item_velocity(item)
            if np.linalg.norm(v) < 2e-3 and np.linalg.norm(w) < 0.05:
                return
            sc.step()

    def _time_floor(self, q_from: np.ndarray, t_from: float, settle_s: float = 0.0) -> None:
        """With `floor`, add to `floors` the move just made, from q_from [rad] at scene time
        t_from [s] to where the arm is: the time it took, and what one direct move would
        take (a jerk-limited rest-to-rest move at the arm's full limits, `move_time`;
        carrying, no faster than the grip holds the item along that joint-space line,
        as `_carry_path` times a carry; plus `settle_s` [s] after it). The direct move
        ignores what the routes are for (the clearance over the station, the level
        swing, the stop over the pick): a floor for these poses, not a plan."""
        if not self.floor:
            return
        from cell.robot.motion import move_time

        took = self.scene.t - t_from
        try:
            direct = move_time(q_from, self.q, self.robot)
            if self.ee.item is not None:
                direct = max(direct, float(self._carry_path([q_from, self.q]).duration))
        except TrajectoryError:
            direct = took - settle_s  # no direct move found: the one made
        spent, floor = self.floors.get(self._index, (0.0, 0.0))
        self.floors[self._index] = (spent + took, floor + min(took, direct + settle_s))

    def _run_for(self, seconds: float) -> None:
        """Let the plant run `seconds` [s] with the arm where it is (a settle, a wait)."""
        self.scene.run_for(seconds)

    def _release_on_the_move(self, motion: Any) -> np.ndarray:
        """Follow a release on the move's `motion` in the plant, the latch opening at its
        planned instant (`cell.sim.release.release_in_scene`); the item's centre at the
        latch [m, W]."""
        from cell.sim.release import release_in_scene

        rel = release_in_scene(self.scene, self.ee, motion)
        self.q = np.asarray(motion.q_end, float)
        self.on_moved()
        return np.asarray(rel.released_at, float)
