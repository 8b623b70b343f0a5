"""The arm's kinematics: IK to grips and releases, the pick's and the lift's configurations."""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import GRIP_DOWN, joint_gap
from cell.errors import (
    IKFailed,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)

# the most release poses `Kinematics._solve_ik` keeps as out of reach across decisions
# (`ArmTuning.ik_reach_kept`); the record is cleared when full
OUT_OF_REACH_KEPT_MAX = 4096

# the most IK searches `Kinematics._solved` keeps across decisions; cleared when full
IK_SOLVED_KEPT_MAX = 4096


def roll_of(robot: Any, q: np.ndarray, elevation: float, azimuth: float) -> float:
    """The roll (0 or π) of `robot`'s release configuration q [rad] for a throw axis at
    (elevation, azimuth) [rad]: its pads' axis against roll 0's."""
    from cell.robot.ik import ReleasePose

    x0 = ReleasePose.from_angles(np.zeros(3), elevation, azimuth, 0.0).rotation()[:, 0]
    return 0.0 if float(robot.tcp_pose(q)[1][:, 0] @ x0) >= 0.0 else math.pi


class Kinematics(ArmBase):
    """The arm's kinematics (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _tcp_for_item_centre(
        self, centre: np.ndarray, elevation: float, azimuth: float, stroke: float, obj: ObjectParams
    ) -> np.ndarray:
        """TCP position [m, W] that puts the gripped item's centre at `centre`."""
        from cell.frames import tcp_for_item_centre

        return tcp_for_item_centre(centre, elevation, azimuth, stroke, obj)

    def _ik(self, tcp: np.ndarray, elevation: float, azimuth: float) -> np.ndarray:
        from cell.robot.ik import solve_release_ik

        return solve_release_ik(self.robot, tcp, elevation, azimuth, self.q, self._release_ik).q

    def _release_ik(self, robot: Any, pose: Any, seed: np.ndarray | None = None) -> Any:
        """`solve_ik(robot, pose, seed)` for a release pose, remembered while one decision
        is made (`decide` clears it): a plan is made in up to three release bounds, each
        steep and not, both rolls, from up to three seeds, and the lower bounds often come
        to the same release pose. The same pose from the same seed is the same solution
        (the search is deterministic), so by default nothing changes but the time. With
        `cycle_search`, a pose the search (the seed, home, 30 random seeds, the polish)
        missed by IK_OUT_OF_REACH_M or more is out of the arm's reach and is not searched
        again from another seed. On the demo, a release 0.42 m out and 0.61 m up (the
        lowest release bounds) was missed by 12.4 mm from every seed, again and again:
        207 searches failed in its 18 throws, 81 now, and nothing chosen changed."""
        from cell.robot.ik import solve_ik

        if robot is not self.robot:
            return solve_ik(robot, pose, seed)
        return self._solve_ik(pose, seed, reach=self.cycle_search)

    def _solve_ik(self, pose: Any, seed: np.ndarray | None = None, reach: bool = False) -> Any:
        """`solve_ik(self.robot, pose, seed)`, remembered until the next decision
        (`decide` clears it): the same pose from the same seed is the same solution, or
        the same IKNoSolution. Every caller gets the same IKResult: nothing in the cell
        writes into a configuration array. `reach`: a pose missed by IK_OUT_OF_REACH_M or
        more is not searched again from another seed either (`_release_ik`), and the
        search gives up early where its first seeds are all far off (`ArmTuning.ik_give_up`),
        with `ArmTuning.ik_solutions` and `ik_polish` for its solutions and polish.
        With `ArmTuning.ik_reach_kept`, such a pose is kept as out of reach across
        decisions too (`_out_of_reach`, the robot's: the same pose, exactly, is not
        searched again in a later item's plan, from any seed); with `ArmTuning.ik_warm`
        too, so is a pose within its distance and angle of one so kept, at the same roll
        (`_far_poses`, `cell.robot.ik_warm.FarPoses`: within 1 mm of a pose missed by 5 mm
        or more, it is missed by 4 mm or more). On the demo, 20 failed release searches
        (0.9 s) were of a pose within 1 mm of one failed earlier, and no solved one was
        within 10 mm and 3° of a failed one."""
        from cell.robot.ik import IKNoSolution

        where = (pose.position.tobytes(), pose.axis.tobytes(), repr(pose.roll).encode())
        key = (*where, b"" if seed is None else np.asarray(seed, float).tobytes())
        if self._ik_log is not None:  # a forked branch's record (`cell.arm.fork`)
            self._ik_log.append(("ask", key, where, pose if reach else None))
        found = self._ik_memo.get(key)
        kept = reach and self.tuning.ik_reach_kept
        # the verdict's terms: a search with other give-up, polish or reach constants is
        # another (`ik_solutions` changes no failure: the search fails from every seed)
        t = self.tuning
        rule = (*where, repr((t.ik_give_up, t.ik_out_of_reach_m, t.ik_polish)).encode())
        if found is None and reach:
            found = self._ik_memo.get(where)
            if found is None and kept:
                found = self._out_of_reach.get(rule)
            if found is None and kept and t.ik_warm:
                found = self._far_poses.near(pose, rule[-1].decode(), *t.ik_warm)
        if found is None:
            try:
                rule_of = (t.ik_give_up, t.ik_solutions, t.ik_polish) if reach else (None, 3, 3)
                found = self._solved(key, pose, seed, *rule_of, warm=reach and t.ik_warm)
            except IKNoSolution as exc:
                found = exc
                if reach and exc.position_error_m >= self.tuning.ik_out_of_reach_m:
                    self._ik_keep("memo", where, exc)
                    if kept:
                        self._ik_keep("reach", rule, exc)
                        if t.ik_warm:
                            self._ik_keep("far", pose, rule[-1].decode(), exc)
            self._ik_keep("memo", key, found)
        if isinstance(found, Exception):
            raise found
        return found

    def _solved(
        self,
        key: tuple[bytes, ...],
        pose: Any,
        seed: np.ndarray | None,
        give_up: tuple[int, float] | None,
        solutions: int = 3,
        polish: int = 3,
        warm: bool | tuple[float, float] | None = None,
    ) -> Any:
        """`solve_ik(self.robot, pose, seed, give_up=..., solutions=..., polish=...)`, kept
        across decisions (`_ik_solved`, at most IK_SOLVED_KEPT_MAX searches, cleared when
        full): the search is a function of the pose, the seed, the give-up rule,
        `solutions` and `polish` alone (its random seeds drawn from a fixed generator, the
        robot's model fixed), so the same pose from the same seed is the same IKResult, or
        the same IKNoSolution, in any decision. A
        release pose recurs where the same object is thrown to the same spot, from a
        seed that recurs too (the arm's configuration where a decision begins, a pick's
        lift). `key`: `_solve_ik`'s (the pose and the seed, bit for bit).

        `warm` (`ArmTuning.ik_warm`: (metres, radians), or False/None: none): the search
        starts from the solution of a pose solved before within that distance and angle
        at the same roll (`cell.robot.ik_warm.WarmStarts`, the one nearest the seed),
        after the seed and before the usual seeds (`solve_ik`'s `warm`); the warm start
        is part of the search's key, and every solution it returns (searched or kept) is a
        warm start for the decision's later searches (`decide` clears them): a decision is
        the same with the searches an earlier one kept or with none.
        Raises IKNoSolution as `solve_ik` does."""
        from cell.robot.ik import IKNoSolution, solve_ik

        start = None
        if warm:
            assert isinstance(warm, tuple)
            ref = self.robot.home if seed is None else np.asarray(seed, float)
            start = self._ik_warm.near(pose, ref, *warm)
        rule = (
            *key,
            b"" if start is None else start.tobytes(),
            repr((give_up, solutions, polish)).encode(),
        )
        found = self._ik_solved.get(rule)
        if found is None:
            try:
                found = solve_ik(
                    self.robot,
                    pose,
                    seed,
                    give_up=give_up,
                    solutions=solutions,
                    polish=polish,
                    warm=start,
                )
            except IKNoSolution as exc:
                found = exc.with_traceback(None)  # kept: not the frames it was raised in
            self._ik_keep("solved", rule, found)
        if isinstance(found, Exception):
            raise found.with_traceback(None)  # not a chain grown by every raise
        if warm:  # kept or not: the same warm starts for the decision's later searches
            self._ik_keep("warm", pose, found.q)
        return found

    def _ik_keep(self, kind: str, *what: Any) -> None:
        """Keep what an IK search found, recorded where a forked branch is searched
        (`_ik_log`, `cell.arm.fork`): "memo" (key, answer) until the next decision,
        "reach" (rule, error) and "far" (pose, rule, error) out of reach across decisions,
        "solved" (rule, answer) the search kept across decisions, "warm" (pose, solution)
        a warm start for the decision's later searches."""
        if self._ik_log is not None:
            self._ik_log.append((kind, *what))
        if kind == "memo":
            self._ik_memo[what[0]] = what[1]
        elif kind == "reach":
            if len(self._out_of_reach) >= OUT_OF_REACH_KEPT_MAX:
                self._out_of_reach.clear()  # bounded: a long job's poses
            self._out_of_reach[what[0]] = what[1]
        elif kind == "far":
            self._far_poses.add(*what)
        elif kind == "solved":
            if len(self._ik_solved) >= IK_SOLVED_KEPT_MAX:
                self._ik_solved.clear()  # bounded: a long job's poses
            self._ik_solved[what[0]] = what[1]
        else:
            self._ik_warm.add(*what)

    def _ik_replay(self, record: list[tuple[Any, ...]]) -> None:
        """Keep what a forked branch's IK searches found (its `_ik_log`), in their order,
        as if they had been made here (`cell.arm.fork`)."""
        for op in record:
            if op[0] != "ask":
                self._ik_keep(*op)

    def ik_frame(self, tcp: np.ndarray, seed: np.ndarray | None = None) -> np.ndarray:
        """IK for the grip pointing down at `tcp` [m, W], in the item's frame
        (`self._frame`: (azimuth, roll), else the roll is free), from `seed` (default:
        where the arm is)."""
        az = 0.0 if self._frame is None else self._frame[0]
        return self._ik_gripped(tcp, -math.pi / 2, az, seed)

    def _ik_gripped(
        self, tcp: np.ndarray, elevation: float, azimuth: float, seed: np.ndarray | None = None
    ) -> np.ndarray:
        """IK at the roll the item was gripped for (`self._frame`); without one, or when that
        roll has no solution, the roll `solve_release_ik` chooses. From `seed` (default:
        where the arm is)."""
        from cell.robot.ik import ReleasePose, solve_release_ik

        q0 = self.q if seed is None else seed
        if self._frame is not None:
            pose = ReleasePose.from_angles(tcp, elevation, azimuth, self._frame[1])
            try:
                return self._solve_ik(pose, q0).q
            except IKFailed:
                log.info("no IK at the gripped roll at %s: the roll is left to the solver", tcp)
        return solve_release_ik(self.robot, tcp, elevation, azimuth, q0, self._gripped_ik).q

    def _gripped_ik(self, robot: Any, pose: Any, seed: np.ndarray | None = None) -> Any:
        """`solve_ik(robot, pose, seed)` for `_ik_gripped`'s free roll, remembered until the
        next decision (`_solve_ik` without `reach`: every seed, as `solve_ik` searches). A
        release search asks for the same pick and lift once per release bounds and roll:
        on the UR3 demo, a lift out of reach was searched from every seed 336 times (26 s
        of its 58 s of release searches), the same poses from the same seeds."""
        from cell.robot.ik import solve_ik

        if robot is not self.robot:
            return solve_ik(robot, pose, seed)
        return self._solve_ik(pose, seed)

    def _pick_frame(self, plan: Any, q_release: Any) -> tuple[float, float] | None:
        """(azimuth, roll) [rad] of the grip pointing down that the release's frame (at the
        release configuration q_release [rad]) swings up from without a twist about the
        throw axis, or None (a place: any roll).

        axis_frame(e, a, roll) = Rz(a) Ry(π/2 − e) Rz(roll): with the same a and roll, the
        down frame (e = −π/2) turns into the release frame about one horizontal axis. A
        twist about the axis while the pads hold the item shifts its contacts and spoils
        the launch (measured in the scene: a cylinder carried through a half turn about
        the axis left at 0.25 m/s sideways and downward instead of 2.5 m/s forward).

        The grip pointing down is solved from `ReleasePose.from_angles`, which keeps the
        throw axis and the roll but not the azimuth of a vertical axis: it is gripped as
        at azimuth 0, and the swing's waypoints (at the release's azimuth) turn it about
        the axis on the way up, by as much as the release's azimuth. Measured on random
        layout 4: up to 80° off the one rotation between the swing's ends, to a bin
        behind the arm; solving the pick at the release's azimuth made that layout slower
        (81.5 → 92.2 s simulated), so it is kept as it is (README, Limits, Throughput).
        """
        if plan is None:
            return None
        roll = roll_of(self.robot, q_release, plan.elevation_rad, plan.azimuth_rad)
        return (float(plan.azimuth_rad), roll)

    def over_item(
        self, item: Any, stroke: float, obj: ObjectParams
    ) -> tuple[np.ndarray, np.ndarray]:
        """(pick, lift) configurations of the grip pointing down over the item where the
        plant has it, the pick putting the item's centre where the gripped item's will be."""
        p_item = self.scene.item_position(item)
        q_pick = self.ik_frame(self._tcp_for_item_centre(p_item, *GRIP_DOWN, stroke, obj))
        return q_pick, self._lift_q(p_item, stroke, obj, q_pick)

    def _lift_q(
        self, p_item: np.ndarray, stroke: float, obj: ObjectParams, q_pick: np.ndarray
    ) -> np.ndarray:
        """The configuration LIFT_M over the pick (IK from the pick's), or as high as the
        arm reaches on the pick's own IK branch (within LIFT_MAX_DQ_RAD of it in every
        joint): a tall item gripped at a long stroke puts the flange up to 0.3 m over the
        item, and 0.15 m more can be out of the arm's reach, or only reached on another
        branch, a swing of the whole arm away."""
        err: IKFailed | None = None
        refused: np.ndarray | None = None  # the first lift out of reach, its IK not run
        far: list[tuple[float, np.ndarray]] = []  # (joint gap from the pick, lift)
        for up in (self.tuning.lift_m, self.tuning.lift_m / 2, self.tuning.lift_m / 4):
            tcp = self._tcp_for_item_centre(p_item + np.array([0, 0, up]), *GRIP_DOWN, stroke, obj)
            if self._beyond_reach(tcp):  # IK would fail there: its error only if needed
                if err is None and refused is None:
                    refused = tcp
                continue
            try:
                q = self.ik_frame(tcp, q_pick)
            except IKFailed as exc:
                err = err or exc
                continue
            gap = joint_gap(q_pick, q)
            if gap <= self.tuning.lift_max_dq_rad:
                return q
            far.append((gap, q))
        if far:  # no lift on the pick's own branch: the nearest other (a long way round)
            log.info(
                "no lift over the pick within %.1f rad of its joints", self.tuning.lift_max_dq_rad
            )
            return min(far, key=lambda gq: gq[0])[1]
        if refused is not None:  # the error IK gives there, as if it had been searched first
            self.ik_frame(refused, q_pick)
        assert err is not None
        raise err

    def _beyond_reach(self, tcp: np.ndarray) -> bool:
        """Whether no configuration points the grip down at `tcp` [m, W] within IK's
        tolerances at any roll (`cell.robot.reach_bound`: sound, so `ik_frame` would fail
        there from every seed). On the UR3 demo the lift LIFT_M over the pick station is
        out of reach: searched in full at both rolls and then at a free roll, in every
        release search's pick (4 failed searches an item's release bounds and roll)."""
        from cell.robot.ik import AXIS_TOL_RAD, POSITION_TOL_M, ReleasePose
        from cell.robot.reach_bound import bound_of

        bound = bound_of(self.robot)
        if bound is None:
            return False
        az = 0.0 if self._frame is None else self._frame[0]
        axis = ReleasePose.from_angles(tcp, -math.pi / 2, az).axis
        return bound.refuses(tcp, axis, POSITION_TOL_M, AXIS_TOL_RAD)

    def _ik_grip(
        self, centre: np.ndarray, stroke: float, obj: ObjectParams, axes: tuple[float, float, float]
    ) -> np.ndarray:
        """IK of the grip with the item's centre at `centre` [m, W], seated on the carriage
        at `stroke`, the approach axis and roll `axes` (elevation, azimuth, roll [rad]).

        Solved to GRIP_IK_TOL (far tighter than a release's): pads a fraction of a degree
        off the item's sides close on its edges, whose contacts can hook it when the
        carriage hits its end stop; the release's tolerance if that does not converge."""
        from cell.robot.ik import ReleasePose, solve_ik

        tcp = self._tcp_for_item_centre(centre, axes[0], axes[1], stroke, obj)
        pose = ReleasePose.from_angles(tcp, *axes)
        try:
            return solve_ik(
                self.robot,
                pose,
                self.q,
                tol_position_m=self.tuning.grip_ik_tol[0],
                tol_axis_rad=self.tuning.grip_ik_tol[1],
            ).q
        except IKFailed:
            return solve_ik(self.robot, pose, self.q).q

    def _ik_grip_any(
        self,
        centre: np.ndarray,
        stroke: float,
        obj: ObjectParams,
        elevation: float,
        azimuth: float,
        rolls: list[float],
    ) -> tuple[np.ndarray, float]:
        """`_ik_grip` at whichever of the rolls gives the configuration nearest the current
        one, and that roll."""
        found: list[tuple[np.ndarray, float]] = []
        err: IKFailed | None = None
        for roll in rolls:
            try:
                found.append((self._ik_grip(centre, stroke, obj, (elevation, azimuth, roll)), roll))
            except IKFailed as exc:
                err = err or exc
        if not found:
            assert err is not None
            raise err
        return min(found, key=lambda f: float(np.linalg.norm(f[0] - self.q)))

    def _down_vertical(
        self, q_top: np.ndarray, p_bottom: np.ndarray, step_m: float = 0.04
    ) -> list[np.ndarray]:
        """Configurations, grip pointing down, on the vertical line from q_top's TCP
        [rad] down to p_bottom [m, W] (which shares its x and y), every `step_m` [m] or
        less, each solved from the one above: q_top's end excluded, p_bottom's the last.
        IKFailed where IK fails on the way."""
        p0 = self.robot.tcp_pose(q_top)[0]
        k = max(1, math.ceil(float(np.linalg.norm(p_bottom - p0)) / step_m))
        out: list[np.ndarray] = []
        seed = q_top
        for i in range(1, k + 1):
            seed = self.ik_frame(p0 + (p_bottom - p0) * i / k, seed)
            out.append(seed)
        return out

    def _vertical(
        self, q_top: np.ndarray, q_bottom: np.ndarray, step_m: float = 0.04
    ) -> list[np.ndarray]:
        """Configurations, grip pointing down, on the vertical line between the TCPs of
        q_top and q_bottom [rad] (which share x and y), every `step_m` [m] or less, ends
        excluded, each solved from the one above (`_down_vertical`); none where IK fails
        on the way (the line between the ends is then used)."""
        try:
            return self._down_vertical(q_top, self.robot.tcp_pose(q_bottom)[0], step_m)[:-1]
        except IKFailed:
            return []
