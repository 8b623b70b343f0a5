"""The release on the move (a part of the arm): whether the cell considers one, the one the
planner prefers by cycle time, and whether it is sooner than the static release as the cell
makes both from the pick (`cell.arm.release` times the static one).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.grip_limits import carry_hold, grip_bounds
from cell.arm.joints import plan_time
from cell.decision import Decision
from cell.errors import IKFailed, TrajectoryError
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)

MOVING_KEPT_MAX = 256  # release-on-the-move searches kept across decisions (`_moving_kept`)


class MovingRelease(ArmBase):
    """The release on the move (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _may_release_moving(self, obj: ObjectParams, d: Decision) -> bool:
        """A release on the move is considered (`release="auto"`) unless a hardware
        end-effector rides along (its latch's timing is not modelled), a residual model
        corrects the stroke (it learned on static releases), or the item would turn in
        the pads on the way (the moving approach has no level swing)."""
        return (
            self.release_mode == "auto"
            and self.effector.hardware is None
            and self.residual is None
            and not self._turns_if_rolled(obj, d.stroke_m)
        )

    def _moving_choice(self, obj: ObjectParams, throw: Any, stroke_max_m: float) -> Any:
        """The release on the move that the planner prefers to the static one by cycle
        time, landing in the bin by the model (`cell.robot.moving_release.choose_release`,
        from where the lift over the presented item will be, its stroke at most
        `stroke_max_m`: what the grip holds), and that is sooner than the static one as
        the cell makes them from the pick (`_moving_sooner`); or None. `throw`: the static
        throw the planner chose (`cell.arm.planner.ThrowChoice`)."""
        plan, delta = throw.plan, throw.delta
        stroke = plan.stroke_m + delta
        self._frame = self._pick_frame(plan, throw.q_release)
        try:
            _, q_lift = self.over_item(self._presented, stroke, obj)
            args = (
                self.robot,
                throw.model_obj,
                plan,
                q_lift,
                self.params.ee,
            )
            kw = dict(
                bounds=grip_bounds(throw.bounds, self.params, stroke_max_m),
                hold=carry_hold(self.params, obj, stroke),
                criterion="cycle",
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )
            choice = self._choose_release(
                args, kw, lambda t, e, a: self._ik_gripped(t, e, a, q_lift)
            )
            if choice.moving is not None and not self._moving_sooner(
                obj, plan, stroke, choice.moving, delta, throw.q_release
            ):
                return None
        except (IKFailed, TrajectoryError) as exc:
            log.info("no release on the move for %s: %s", obj.name or obj.shape, exc)
            return None
        finally:
            self._frame = None
        if choice.moving is not None:
            log.info("%s: release on the move saves %.2f s", obj.name or obj.shape, choice.saved_s)
        return choice.moving

    def _choose_release(self, args: tuple[Any, ...], kw: dict[str, Any], ik: Any) -> Any:
        """`choose_release(*args, ik=ik, **kw)`, kept across decisions (`_moving_kept`,
        at most MOVING_KEPT_MAX, cleared when full): the same item thrown from the same
        lift by the same static plan is the same search. The search is a function of its
        arguments and of the answers `ik` gives (the robot's model, the landing model and
        ruckig are fixed); `ik` (`_ik_gripped`, remembered within a decision, `_solve_ik`)
        may answer a pose from what an earlier search of the decision found, so a kept
        choice is taken only where `ik` gives every answer it gave (the same
        configuration, bit for bit, or the same failure) again: then the search would make
        every step it made, and the same choice. On the demo, 2 of its 8 searches were
        the same as one before (tests/test_moving_kept.py)."""
        from cell.robot.moving_release import choose_release

        key = _exact((args, kw, self._frame))
        kept = self._moving_kept.get(key)
        if kept is not None:
            asked, choice = kept
            if all(_answer(ik, q) == a for q, a in asked):
                return choice
        asked = []

        def asking(t: np.ndarray, e: float, a: float) -> np.ndarray:
            q = (np.array(t, float), float(e), float(a))
            try:
                out = ik(*q)
            except IKFailed as exc:
                asked.append((q, _failed(exc)))
                raise
            asked.append((q, np.asarray(out, float).tobytes()))
            return out

        choice = choose_release(*args, ik=asking, **kw)
        if len(self._moving_kept) >= MOVING_KEPT_MAX:
            self._moving_kept.clear()  # bounded: a long job's searches
        self._moving_kept[key] = (asked, choice)
        return choice

    def _moving_sooner(
        self,
        obj: ObjectParams,
        plan: Any,
        stroke: float,
        mt: Any,
        delta: float,
        q_release: np.ndarray,
    ) -> bool:
        """Is the release on the move `mt` sooner than the static release of `plan` at
        `stroke` [m], each from the pick of the presented item to the release and back
        to that pick, as the cell makes them? The static: `_static_cycle_s`; the
        moving: its motion from the pick, or the move up to the lift, its settle and its
        motion from there (`_moving_route`), and the way back from where it stops. The
        moving plan's stroke is its own plus `delta`; the static one's release is at
        q_release [rad].

        `choose_release` times both from rest at the lift and back to it; the cell's
        static carry leaves the pick without stopping, and a moving release whose move
        from the pick does not rise from the station stops at the lift first. On random
        layouts 6 and 11, 13 of the 17 releases on the move it had chosen took 0.36-1.45 s
        longer a cycle than the static release of the same item (layout 11's three 51 mm
        cubes stopped at the lift); four 50 mm cubes' were 0.28-0.45 s sooner
        (tests/test_moving_choice.py). Where the static route is not found, the moving
        one is kept; where the moving one is not, IKFailed or TrajectoryError (then
        `_moving_choice` takes none)."""
        item = self._presented
        if item is None or self.pick_mode == "physical":
            return True  # no pick to time from (`choose_release`'s choice stands)
        s_moving = mt.plan.stroke_m + delta
        q_pick, q_lift = self.over_item(item, s_moving, obj)
        lifted, motion = self._moving_route(mt, obj, s_moving, q_pick, q_lift)
        t_moving = motion.duration_s + self._approach_s(
            motion.q_end, (q_pick, q_lift), s_moving, obj
        )
        if lifted:  # `_move` to the lift, its settle there
            held = (obj, s_moving)
            lift = self._move_plan(q_pick, [q_lift], self.tuning.settle_s, held)
            t_moving += plan_time(lift, self.tuning.settle_s) + self.tuning.settle_s
        try:
            t_static = self._static_cycle_s(obj, plan, stroke, q_release)
        except (IKFailed, TrajectoryError):
            return True
        log.info(
            "%s: release on the move %.2f s, static %.2f s, pick to pick",
            obj.name or obj.shape,
            t_moving,
            t_static,
        )
        return t_moving < t_static

    def _moving_route(
        self, mt: Any, obj: ObjectParams, stroke: float, q_pick: np.ndarray, q_lift: np.ndarray
    ) -> tuple[bool, Any]:
        """(up to the lift first?, the motion) of the release on the move `mt` carrying
        `obj` at `stroke` [m] (`carry`): the release's own move from the pick q_pick
        [rad] where it leaves the station upward (`_moving_leaves_station`), else from
        rest at the lift q_lift. TrajectoryError when there is none from the lift."""
        from cell.robot.moving_release import plan_moving_release

        def motion_from(q: np.ndarray) -> Any:
            return plan_moving_release(
                self.robot,
                q,
                mt.motion.q_release,
                mt.motion.v_release,
                hold=carry_hold(self.params, obj, stroke),
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )

        try:
            motion = motion_from(q_pick)
            if self._moving_leaves_station(motion):
                return False, motion
        except TrajectoryError:
            pass
        return True, motion_from(q_lift)


def _exact(x: Any) -> bytes:
    """`x` (numbers, strings, None, arrays, dataclasses, tuples, lists and dicts of them,
    a `Robot`) as bytes that differ wherever a value differs, bit for bit: floats by
    `float.hex`, arrays by dtype, shape and bytes, a robot by its name and identity."""
    import dataclasses

    if x is None or isinstance(x, (bool, int, str)):
        return repr(x).encode()
    if isinstance(x, (float, np.floating)):
        return float(x).hex().encode()
    if isinstance(x, np.ndarray):
        return repr((x.dtype.str, x.shape)).encode() + x.tobytes()
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        fields = [(f.name, getattr(x, f.name)) for f in dataclasses.fields(x)]
        return type(x).__qualname__.encode() + _exact(fields)
    if isinstance(x, (tuple, list)):
        return b"(" + b",".join(_exact(v) for v in x) + b")"
    if isinstance(x, dict):
        return _exact(sorted(x.items()))
    from cell.robot.model import Robot

    if isinstance(x, Robot):
        return f"robot {x.name} {id(x)}".encode()
    raise TypeError(f"no exact key for a {type(x).__name__}")


def _failed(exc: IKFailed) -> bytes:
    """An IK failure as an answer (`_choose_release`): its type and message."""
    return f"{type(exc).__name__}: {exc}".encode()


def _answer(ik: Any, q: tuple[np.ndarray, float, float]) -> bytes:
    """What `ik` answers to (tcp, elevation, azimuth) `q`, as `_choose_release` keeps it."""
    try:
        return np.asarray(ik(*q), float).tobytes()
    except IKFailed as exc:
        return _failed(exc)
