"""The carry's routes: waypoints between configurations (the departure from the pick, the
twist-free swing) and the checks a route must pass.
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
from cell.arm.joints import (
    GRIP_DOWN,
    PickState,
    joint_gap,
    plan_time,
    spline_within_limits,
    twist,
)
from cell.errors import (
    IKFailed,
    TrajectoryError,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


class Routes(ArmBase):
    """The carry's routes (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _swing(
        self,
        q_lift: np.ndarray,
        q_rel: np.ndarray,
        plan: Any,
        carried: tuple[ObjectParams, float] | None = None,
        usable: Callable[[list[np.ndarray]], bool] | None = None,
    ) -> list[np.ndarray]:
        """Waypoints between the lift and the release that keep the grip on the twist-free
        swing (`_pick_frame`): the throw axis turns up about one horizontal axis, the
        pads' y axis stays level. A joint-space spline between the two ends alone rolls
        the grip sideways on the way, and a tall item hanging from the pads turns in
        them (cell.robot.carry). Empty when the grip was not taken twist-free, or when
        no swing on the ends' IK branch is found (the spline between the ends is used).

        Each waypoint is solved from the previous one; when that chain leaves the ends'
        branch (a seed that does not converge falls back to home: a UR5 swing came out
        4.4 rad round in a joint between waypoints and flung the item), from the point
        on the joint-space line between the ends instead. A swing whose joints travel
        more than SWING_MAX_DETOUR × the ends' gap is not taken. Where the spline through
        SWING_WAYPOINTS of them rolls the grip more than the level swing must
        (`_swing_holds`), twice as many are tried, up to SWING_WAYPOINTS_MAX, and the
        one asking least of the grip at rest is kept (the fewer on a tie). `carried`:
        the item and its stroke [m] (default: the one in the grip). `usable`: where the
        caller takes the route only if `usable(waypoints)` (`_departure`), and neither
        the swing's waypoints nor none (the spline between the ends) are, the swing's
        are returned without weighing the spline between the ends against them
        (`_direct_is_better`, a sphere's): the caller takes neither. Where the first,
        sparsest swing is not usable either, no denser one is solved: it is returned as it
        is (tune layout 0's 200 mm bottle: its decision's 4 departures asked 16 swings,
        326 IK solves along their chains, 0.47 s of its 2.1 s of CPU in a profile)."""
        if (
            self._frame is None
            or self.tuning.swing_waypoints < 1
            or not self._turns_if_rolled(*carried or ())
        ):
            return []
        held = carried or self._carried
        n, best = self.tuning.swing_waypoints, None
        while n <= self.tuning.swing_waypoints_max:
            out = self._swing_waypoints(q_lift, q_rel, plan, n)
            if not out:  # none found with more: the sparser one (or none)
                break
            if best is None and usable is not None and not usable(out) and not usable([]):
                return out  # the sparsest passes not, nor the spline between the ends
            if (
                best is not None
                and spline_within_limits(self.robot, [q_lift, *out, q_rel], 400) is None
            ):
                break  # a denser one whose spline leaves the joint limits stops at each
            most, allowed = self._swing_static([q_lift, *out, q_rel], held, plan.elevation_rad)
            if best is None or most < best[0] - self.tuning.grip_use_tie:
                best = (most, allowed, out)
            if most <= allowed + self._over_bound(held[0]):
                break
            n *= 2
        if best is None:
            return []
        if best[0] > best[1] + self._over_bound(held[0]):
            log.info("the level swing asks more of the grip than it must, even at rest")
        if usable is not None and not usable(best[2]) and not usable([]):
            return best[2]  # neither is taken: which is better need not be found
        if self._direct_is_better([q_lift, *best[2], q_rel], best[0], held, plan):
            return []
        return best[2]

    def _direct_is_better(
        self, route: list[np.ndarray], most: float, held: tuple[ObjectParams, float], plan: Any
    ) -> bool:
        """For a sphere: does the spline between the swing's ends alone turn the grip no
        more off one rotation (`cell.arm.joints.twist`) than the swing's `route`, and ask
        no more of the grip at rest (than `most`, the route's)? Then it is taken, without
        planning the two carries to weigh which is sooner: over tune layout 0's 80 such
        comparisons the direct carry was the sooner in 76 (by 0.19-1.9 s; the route by
        0.03-0.33 s in the other 4), and the two carries planned were 2.2 s of its
        decisions' CPU, the tail of its planning time per item (docs/HISTORY.md,
        2026-12-02, branch plan68)."""
        if held[0].shape != "sphere":
            # only a sphere is the same turned about the throw axis: for other items
            # without a couple in the grip, over the 20 random layouts, 6 fewer landed
            return False
        direct = [route[0], route[-1]]
        if twist(self.robot, direct, self.tuning.swing_check_samples) > twist(
            self.robot, route, self.tuning.swing_check_samples
        ):
            return False
        if self._swing_static(direct, held, plan.elevation_rad)[0] > most:
            return False
        log.debug("the spline between the swing's ends turns the grip less: taken")
        return True

    def _swing_waypoints(
        self, q_lift: np.ndarray, q_rel: np.ndarray, plan: Any, n: int
    ) -> list[np.ndarray]:
        """n waypoints of the twist-free swing from q_lift to q_rel (`_swing`), evenly in
        position and elevation; none when it goes round or has no IK."""
        az, roll = self._frame or (0.0, 0.0)
        rb = self.robot
        p0, p1 = rb.tcp_pose(q_lift)[0], rb.tcp_pose(q_rel)[0]
        e0, e1 = -math.pi / 2, plan.elevation_rad
        fs = [k / (n + 1) for k in range(1, n + 1)]
        from cell.robot.ik import ReleasePose, solve_ik

        poses = [
            ReleasePose.from_angles(p0 + f * (p1 - p0), e0 + f * (e1 - e0), az, roll) for f in fs
        ]
        gap = joint_gap(q_lift, q_rel)
        for chained in (True, False):
            out: list[np.ndarray] = []
            try:
                for f, pose in zip(fs, poses, strict=True):
                    if chained:  # from the previous waypoint (the lift for the first)
                        seed = out[-1] if out else q_lift
                    else:  # from the joint line between the ends
                        seed = q_lift + f * (q_rel - q_lift)
                    out.append(solve_ik(rb, pose, seed, random_seeds=0, solutions=1).q)
            except IKFailed:
                continue
            path = [q_lift, *out, q_rel]
            travel = sum(joint_gap(a, b) for a, b in zip(path[:-1], path[1:], strict=True))
            if travel <= self.tuning.swing_max_detour * gap + 1e-9:
                return out
            log.info("the level swing goes round (%.1f rad in a joint for %.1f)", travel, gap)
        return []

    def _departure(
        self,
        q_lift: np.ndarray,
        q_end: np.ndarray,
        plan: Any = None,
        at: PickState | None = None,
    ) -> list[np.ndarray]:
        """Waypoints from the pick (where the arm is) to q_end (a throw's release
        configuration, for its `plan`, or over a bin): through the lowest of
        DEPARTURE_LIFTS_M over the pick (the first: none) whose spline lifts the item out
        of the station (`_rises_from_station`) and stays within the joint limits, then
        (a throw) along the twist-free swing (`_swing`), which must keep a tall item within
        the grip held still anywhere (`_swing_holds`: the swing solved from a lower lift
        can come out on another branch and roll the grip); else through the full lift
        q_lift (the route `_release_q` timed). A spline through a lift LIFT_M up turns back
        on itself: the demo's throws carried 0.3-0.4 s longer than a per-joint time-optimal
        move.

        For an item the swing keeps level and the pads hold with a couple (not at points),
        the route without the swing's waypoints is a candidate beside it at each lift, held
        to the same test: what the twist-free swing would ask of the grip held still is
        what any route may ask, and where both pass, the sooner is taken (`_soonest`). On
        random layout 1 (UR5), four 100 mm boxes (cuboid_c) whose swing routes had failed
        from the pick went straight from it: 0.73-0.77 s against 1.38-1.43 s through the
        lift and the swing (tests/test_departure.py).

        `at`: where the carry starts (`PickState`), to time a departure before the pick
        (`_moving_sooner`); default: where the arm is, with what the grip holds."""
        # the swing is the throw's item at its throw's stroke (`_swing`'s default); the
        # routes' tests are at the stroke it is held at (`_carry_stroke`)
        swing_of: tuple[ObjectParams, float] | None = None
        if at is None:
            p_held = self.scene.item_position(self.ee.item) if self.ee.item is not None else None
            at = (self.q, p_held, self._carried[0], self._grip_stroke)
        else:
            swing_of = (at[2], at[3])
        q_pick, p_pick, obj, stroke = at
        level = plan is not None and self._turns_if_rolled(*swing_of or ())
        # a route that leaves the swing out, where it holds the item as well (below)
        unswung = level and carry_hold(self.params, obj, stroke).torque_nm > 0.0

        def holds(way: list[np.ndarray]) -> bool:
            return not level or self._swing_holds([q_pick, *way], (obj, stroke), plan.elevation_rad)

        for up in self.tuning.departure_lifts_m:
            start: list[np.ndarray] = []
            if up > 0.0 and p_pick is not None:
                lift = p_pick + np.array([0.0, 0.0, up])
                try:
                    q_up = self.ik_frame(
                        self._tcp_for_item_centre(lift, *GRIP_DOWN, stroke, obj), q_pick
                    )
                except IKFailed:
                    continue
                if joint_gap(q_pick, q_up) > self.tuning.lift_max_dq_rad:
                    continue
                start = [q_up]
            elif up > 0.0:
                continue

            def usable(mid: list[np.ndarray], start: list[np.ndarray] = start) -> bool:
                w = [*start, *mid, q_end]
                return self._rises_from_station([q_pick, *w]) and holds(w)

            swung = self._swung(start[-1] if start else q_pick, q_end, plan, swing_of, usable)
            ways = [[*start, *swung, q_end]] + ([[*start, q_end]] if swung and unswung else [])
            ways = [w for w in ways if usable(w[len(start) : -1])]
            if ways:
                return self._soonest(ways, q_pick, (obj, stroke))
        swung = self._swung(q_lift, q_end, plan, swing_of)
        way = [q_lift, *swung, q_end]
        if swung and unswung and holds([q_lift, q_end]):
            return self._soonest([way, [q_lift, q_end]], q_pick, (obj, stroke))
        return way

    def _soonest(
        self,
        ways: list[list[np.ndarray]],
        q_from: np.ndarray,
        carried: tuple[ObjectParams, float],
    ) -> list[np.ndarray]:
        """Of routes from q_from [rad] carrying `carried` (the item and its stroke [m]: a
        carry's, `_departure`), the one `_move` takes soonest, its stops and settles
        counted; the first where none is timed."""
        if len(ways) == 1:
            return ways[0]
        best: tuple[float, list[np.ndarray]] | None = None
        for way in ways:
            try:
                trajs = self._move_plan(q_from, way, self.tuning.settle_s, carried)
            except TrajectoryError:
                continue
            took = plan_time(trajs, self.tuning.settle_s)
            if best is None or took < best[0]:
                best = (took, way)
        return ways[0] if best is None else best[1]

    def _swung(
        self,
        q_from: np.ndarray,
        q_end: np.ndarray,
        plan: Any,
        carried: tuple[ObjectParams, float] | None = None,
        usable: Callable[[list[np.ndarray]], bool] | None = None,
    ) -> list[np.ndarray]:
        """The twist-free swing's waypoints for a throw's `plan` (`_swing`, `carried` and
        `usable` as there); none for a place."""
        return [] if plan is None else self._swing(q_from, q_end, plan, carried, usable)

    def _rises_from_station(self, waypoints: list[np.ndarray], n: int = 400) -> bool:
        """Does the spline through `waypoints` (`cell.robot.motion.spline_path`, the path a
        carry follows whatever its timing) stay within the joint limits and leave the
        station upward (`_leaves_station_upward`)? Then the item leaves the station
        neither dragged across its top nor pushed into it."""
        qs = spline_within_limits(self.robot, waypoints, n)
        return qs is not None and self._leaves_station_upward(qs)

    def _moving_leaves_station(self, motion: Any, n: int = 200) -> bool:
        """Does a release on the move's `motion` (`plan_moving_release`, from the pick),
        at n instants up to the latch, leave the station upward (`_leaves_station_upward`)?
        The check `carry` makes before it takes that move."""
        ts = np.linspace(0.0, motion.t_release_s, n)
        return self._leaves_station_upward(np.array([motion.state(t)[0] for t in ts]))

    def _leaves_station_upward(self, qs: np.ndarray) -> bool:
        """Do the configurations `qs` [rad], a path from the pick in order, keep the grip,
        wherever it is over the pick station widened by the grip's reach, risen from the
        first at least as far as it has moved sideways (up to DEPARTURE_CLEAR_M; 1 mm
        tolerance)? The test of `_rises_from_station`, and of a release on the move's
        motion (`carry`)."""
        lo, hi = self.scene.pick_station_bounds()
        reach = self._grip_reach_m()
        p = self.robot.tcp_positions(qs)  # every configuration's at once, then the test
        near = np.all(p[:, :2] > lo[:2] - reach, axis=1) & np.all(p[:, :2] < hi[:2] + reach, axis=1)
        side = np.hypot(p[:, 0] - p[0, 0], p[:, 1] - p[0, 1])
        low = p[:, 2] - p[0, 2] < np.minimum(self.tuning.departure_clear_m, side) - 1e-3
        return not bool(np.any(near & low))

    def _grip_reach_m(self) -> float:
        """How far [m] the grip reaches out from its centre, horizontally: the carriage's
        half side, the open pads and their thickness."""
        geo = self.scene.geometry
        return float(geo.carriage_half_xy_m + geo.finger_open_m + geo.pad_thickness_m)

    def _keeps_over_station(self, traj: Any, z_min: float) -> bool:
        """Does the grip centre stay at least z_min [m] high (1 mm tolerance) wherever it
        passes over the pick station's top, widened by the grip's reach (the carriage's
        half side and the open pads), along `traj` (sampled every physics step)?"""
        sc = self.scene
        lo, hi = sc.pick_station_bounds()
        reach = self._grip_reach_m()
        ts = np.arange(0.0, traj.duration + sc.dt_s, sc.dt_s)
        p = self.robot.tcp_positions(traj.positions(ts))
        near = np.all(p[:, :2] > lo[:2] - reach, axis=1) & np.all(p[:, :2] < hi[:2] + reach, axis=1)
        return not bool(np.any(near & (p[:, 2] < z_min - 1e-3)))

    def _release_branch(
        self, q_lift: np.ndarray, q_rel: np.ndarray, chosen: Any, tcp: np.ndarray, plan: Any
    ) -> np.ndarray:
        """The release configuration a throw's carry goes to: q_rel (solved from where the
        pick left the arm), unless the item must be carried level (`_turns_if_rolled`),
        IK landed on another branch than the release `_release_q` chose and timed
        (`chosen`, [rad]), and the chosen one's swing asks clearly less of the grip at
        rest (`_swing_static`, by more than GRIP_USE_TIE). A UR5 carried a 200 mm bottle
        round on the other branch (1.33 against 1.00), its grip rolled 50°, and the
        bottle left the pads; a 70 mm, 60 g cylinder's re-solved branch asked 0.97
        against the chosen one's 0.746, so its carry went at the gentle scale (5.8 s
        against the 3.2 s the decision timed). This holds even where the level swing
        alone is within the carry's bound: the spline between its waypoints is not.

        With `cycle_search` the decision times each candidate along the route the carry
        takes, from the pick: the carry goes to the chosen configuration wherever it is
        one of the release pose (its TCP within IK's own tolerance, POSITION_TOL_M, of
        `tcp` [m, W]). IK from the pick can land on another branch than the one timed:
        on random layout 2, a 67 mm cube's re-solved release was 3.13 rad away in a
        wrist joint, and its carry took 2.11 s in the scene against the 1.06 s timed
        (tests/test_release_choice.py). Without it, the decision times the carry from
        the lift, not from the pick, and the branch found from the pick is often the
        sooner: carried to the chosen one, that job's 67 mm cube took 1.91 s a cycle
        instead of 2.96 s, but its three 57 mm, 165 g cubes 15.65 s instead of 10.80 s."""
        from cell.robot.ik import POSITION_TOL_M

        if chosen is None or self.pick_mode == "physical":
            return q_rel
        chosen = np.asarray(chosen, float)
        if chosen.shape != q_rel.shape:
            return q_rel
        off_m = float(np.linalg.norm(self.robot.tcp_pose(chosen)[0] - np.asarray(tcp)))
        if self.cycle_search:
            return chosen if off_m <= POSITION_TOL_M else q_rel
        if not self._turns_if_rolled() or joint_gap(chosen, q_rel) < 1e-3 or off_m > 1e-4:
            return q_rel

        def most(q: np.ndarray) -> float:
            way = [q_lift, *self._swing(q_lift, q, plan), q]
            return self._swing_static(way, self._carried, plan.elevation_rad)[0]

        m_chosen, m_rel = most(chosen), most(q_rel)
        log.debug(
            "release branches: chosen %.3f, re-solved %.3f (grip use at rest)", m_chosen, m_rel
        )
        if m_chosen >= m_rel - self.tuning.grip_use_tie:
            return q_rel
        log.info("the release on the branch chosen for it: the other rolls the grip more")
        return chosen
