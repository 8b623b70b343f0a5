"""The throw planner: the plan to a bin in the cell's release bounds and the fallbacks, the
turn toward the station, the learned aim.
"""

from __future__ import annotations

import logging
import math
from dataclasses import replace as dc_replace
from functools import partial
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.choice import ThrowChoice, grip_short, soonest_of
from cell.arm.grip_limits import (
    grip_bounds,
    release_elevation_min,
    release_grip_use,
)
from cell.arm.joints import clip
from cell.arm.launch import (
    plan_clean,
)
from cell.arm.spots import throw_spot
from cell.arm.steep import steep_tiers
from cell.errors import (
    CellError,
    IKFailed,
    UnreachableTarget,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)

# The most of the grip a release may ask held still, the tilt counted (`release_grip_use`;
# `Planner._held_at_release`): what the pads hold at rest. Boxes and cylinders turn in the
# pads at 1.02-1.23 of what the grip model says they resist (tests/test_grip_probe.py).
RELEASE_HELD_MAX = 1.0


class Planner(ArmBase):
    """The throw planner (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _plan(
        self,
        obj: ObjectParams,
        target: Any,
        index: int,
        stroke_max_m: float = math.inf,
        beat: float | None = None,
    ) -> ThrowChoice:
        """The throw to a bin whose release pose the arm reaches: its plan, the learned
        ΔL_s, the release configuration and the goal; or UnreachableTarget / IKFailed.

        With `turn_release`, planned twice (`_plan_facing`): with the arm facing the bin at
        the release, and turned from it toward the pick station (`_facing_toward_station`),
        the throw axis still on the bin; the one whose cycle estimate (`_release_q`) is the
        shorter is kept, the first where there is no estimate to compare. `beat` [s]: a
        cycle estimate the caller already has (another grip side's throw,
        `GripSideChoice._throw_side`): a release that cannot beat it is not timed, and
        where none can, the plan's estimate is (False, ∞).
        """
        # the bin's centre, or a point of it clear of what the bin holds: the same for
        # every bounds tried (the scene does not move meanwhile). A point moved off the
        # centre may lie beyond the reach the job's check proved (it planned onto the
        # centre, `check_sortable`): then the centre (test layout 1002, Panda: a cuboid's
        # spot 21 mm beyond it failed `unreachable`)
        spot = throw_spot(self.scene, target.id, obj)
        centre = (float(target.position[0]), float(target.position[1]))
        try:
            return self._plan_to((*spot, target.rim_height), obj, target, index, stroke_max_m, beat)
        except UnreachableTarget as exc:
            if np.allclose(spot, centre, atol=1e-9):
                raise
            log.info("the throw spot in %s is out of reach (%s): the bin's centre", target.id, exc)
        goal = (*centre, target.rim_height)
        return self._plan_to(goal, obj, target, index, stroke_max_m, beat)

    def _plan_to(
        self,
        goal: tuple[float, float, float],
        obj: ObjectParams,
        target: Any,
        index: int,
        stroke_max_m: float,
        beat: float | None,
    ) -> ThrowChoice:
        """`_plan` to the point `goal` [m, W] of the bin's rim plane: in the steep tiers
        (`steep_tiers`, a low-rimmed bin) at each facing, a plan there kept only where it
        passes what an ordinary plan is held to (`steep_kept`); where none is kept,
        in the ordinary release bounds at each facing (`_release_bounds`)."""
        err: CellError | None = None
        ordinary, shrunk = self._release_bounds(target)
        steep = steep_tiers(self.tuning, target.rim_height, ordinary, shrunk)
        turned = self._facing_toward_station(target)
        for tiers in (steep, ((ordinary, False), (shrunk, True))):
            facings = () if not tiers else (None,) if turned is None else (None, turned)
            plan = partial(self._plan_facing, obj, goal, (index, stroke_max_m), tiers)
            best, err = self._best_facing(plan, facings, beat, err, tiers is steep, obj)
            if best is not None:
                # where it should cross the rim plane
                return dc_replace(best, goal=np.asarray(goal, float))
        assert err is not None
        raise _no_release(err, self.bounds) if isinstance(err, IKFailed) else err

    @staticmethod
    def _to_beat(best: ThrowChoice | None) -> float | None:
        """The cycle estimate [s] the next facing's plan must beat to be kept (`_plan`
        keeps it only where its cost is below `best`'s), or None: nothing planned yet, no
        estimate, or `best` asks more of the grip than it holds (then any release that
        does not wins, whatever its time). `_release_search` need not time a candidate
        that cannot beat it: the same choice, found sooner."""
        if best is None or best.cost is None or best.cost[0]:
            return None
        return best.cost[1]

    def _facing_toward_station(self, target: Any) -> float | None:
        """The azimuth [rad, W] the arm faces at a throw's release if it turns from the
        bin toward the pick station (both the carry and the next approach then turn the
        arm that much less), or None: without `turn_release`, or for a bin less than
        FACE_MIN_OFF_RAD round from the station. From 70° while the turn was compared by
        the cycle estimate without `cycle_search`: that erred by more than a small turn
        saves (the demo's bins, 28–64° round, went from 1,529 to 1,490 items per hour with
        it). With the search timing both as the cell makes them, from 30° (README, "The
        defaults": over the 20 random layouts 1,474 -> 1,507 items per hour with the rise
        out of the station to 2 cm as well).

        The release point is `release_radius` r from the base along the azimuth faced,
        so turning it by Δ from the bin at distance d lengthens the throw from d − r to
        √(r² + d² − 2rd·cos Δ). A longer throw lands faster and bounces out of a low rim
        more: turned up to 90°, items that landed within 0.02 m of their aim came to
        rest outside (random layout 16: six 60 mm cylinders out of a 55 mm rim bin 1.4 m
        away, the throw 46 % longer). So Δ is at most FACE_TURN_MAX_RAD and what keeps
        the throw within FACE_THROW_STRETCH of the bin-facing one's: small for a bin near
        the base, large for one far out."""
        if not self.turn_release:
            return None
        sx, sy = self.scene.pick_station_xy
        tx, ty = (float(v) for v in target.position[:2])
        phi = math.atan2(ty, tx)
        off = math.atan2(sy, sx) - phi
        lim = self.robot.limits
        if lim.upper[0] - lim.lower[0] >= 2.0 * math.pi:  # the UR5's: the shorter way round
            off = math.remainder(off, 2.0 * math.pi)
        # else not across ±180°: the Panda's first joint stops at ±166°, so from a bin at
        # 150° the way to a station at -42° is down through 0°
        r, d = self.bounds.release_radius, math.hypot(tx, ty)
        if abs(off) < self.tuning.face_min_off_rad or d <= r:
            return None
        longest = self.tuning.face_throw_stretch * (d - r)
        turn = math.acos(max(-1.0, min(1.0, (r * r + d * d - longest**2) / (2.0 * r * d))))
        turn = min(turn, self.tuning.face_turn_max_rad)
        if turn < 1e-3:
            return None
        return phi + clip(off, turn)

    def _plan_facing(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        item: tuple[int, float],
        tiers: Any,
        facing: float | None,
        beat: float | None = None,
    ) -> ThrowChoice:
        """`_plan` in the release bounds `tiers` ((bounds, the first reached kept), in
        turn: `_plan_to`) with the arm facing `facing` [rad, W] at the release (None: the
        bin), with the release's cycle estimate (`_release_q`; None where none was made);
        `item`: (its index, the most stroke the grip holds it at [m]).

        The plan is made in the cell's release bounds; where IK finds no configuration for
        its release pose, again with the release lower and the throw axis flatter
        (RELEASE_FALLBACKS): the arm cannot point steeply up at shoulder height close to
        its base. With `cycle_search`, in all of these, the sooner kept
        (`_soonest_release`): a lower release can be nearer the pick. Random layout 11's
        three eggs took up to 8.6 s a cycle released in the cell's bounds, 2.48 s each
        released lower, where the carry's grip bound is far less tight. Where none of these
        is reached, the plan is made in a smaller release box (RELEASE_BOX_SHRINKS), the
        first reached kept. `beat` [s]: a cycle estimate the caller already has (`_plan`'s
        other facing, `_to_beat`): a candidate that cannot beat it is not timed, in any of
        the release bounds (their own `_beat` too), where the cycle is searched.
        """
        err: CellError | None = None
        for tier, first_kept in tiers:
            found, err = self._plan_tier(obj, goal, item, tier, first_kept, facing, beat, err)
            if found:
                return self._soonest_release(obj, found)
        assert err is not None
        raise err

    def _lower_bounds_wanted(self, first: ThrowChoice) -> bool:
        """Are the lower release bounds (RELEASE_FALLBACKS) searched after `first`, the
        plan in the cell's bounds (`_plan_facing`)? Only with `cycle_search`, and with
        `ArmTuning.release_lower_room_s` only where `first` leaves room for a lower
        release to be sooner: its carry at least that much slower than the arm's limits
        let it be (`ThrowChoice.room_s`, a carry the grip holds back, as random layout
        11's eggs: 8.6 s a cycle in the cell's bounds, 2.48 s released lower), or no
        estimate that holds to compare with. On the demo the lower bounds took 72 % of
        the release searches' CPU and were sooner in 1 of 18 throws, by 0.06 s
        (docs/HISTORY.md, 2026-11-29, fifth round)."""
        if not self.cycle_search:
            return False
        most = self.tuning.release_lower_room_s
        if most is None or first.room_s is None or first.cost is None:
            return True
        t = first.cost[1]
        short = grip_short(first) is not None
        return short or not math.isfinite(t) or first.room_s >= most

    def _plan_in(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        index: int,
        stroke_max_m: float,
        bounds: Any,
        beat: float | None = None,
        lower: bool = False,
    ) -> ThrowChoice:
        """The throw's plan in release `bounds` and its release (`_release_q`, which need
        not time a release whose cycle cannot beat `beat` [s]): steep enough for the grip
        to hold the item at its release first; where the arm reaches no such release, as
        the bounds are (`_steep_enough`). `lower`: `bounds` are one of the lower release
        bounds (RELEASE_FALLBACKS; `ArmTuning.release_timed_max_lower`). UnreachableTarget
        or IKFailed."""
        err: IKFailed | None = None
        for steep in (True, False):
            plan, delta, aim, model_obj, steepened = self._plan_once(
                obj, goal, index, stroke_max_m, bounds, steep
            )
            stroke = plan.stroke_m + delta
            centre = np.array([plan.x_m, plan.y_m, plan.z_m])
            try:
                q_release, cost = self._release_q(
                    self._tcp_for_item_centre(
                        centre, plan.elevation_rad, plan.azimuth_rad, stroke, obj
                    ),
                    plan,
                    stroke,
                    obj,
                    beat,
                    lower=lower,
                )
            except IKFailed as exc:
                err = err or exc
                if not steepened:
                    break
                continue
            held = self._held_at_release(obj, stroke, plan.elevation_rad)
            kept = {"held": held, "room_s": self._release_room_s, "route": self._release_route}
            return ThrowChoice(cost, plan, delta, q_release, bounds, aim, model_obj, **kept)
        assert err is not None
        raise err

    def _held_at_release(self, obj: ObjectParams, stroke_m: float, elevation_rad: float) -> bool:
        """Do the pads at stroke L_s [m] hold `obj` still at a release `elevation_rad` [rad]
        (`release_grip_use`, the tilt about y counted, at most RELEASE_HELD_MAX)? A plan in
        release bounds too flat for `_steep_enough` to raise (its elevation_max below the
        least elevation that holds) may release where the grip cannot hold the item still:
        it is not kept over a first plan that holds (`soonest_of`). On random layout 3
        (UR5) a 150 g, 200 mm bottle, carried at the short stroke, was wound back to its
        86 mm throw stroke at a release 3° up, where held still it asks 1.19 of the grip;
        it tipped out of the pads (two more, at 30°, asked 0.97 and held).

        Held to the carry's bound instead (1/1.35, a box's GRIP_USE_TIE over it), the test
        was stricter than the item held still needs: the bound is for a carry's
        accelerations, and the release is held at rest."""
        use = float(release_grip_use(self.params, obj, stroke_m, [elevation_rad])[0])
        return use <= RELEASE_HELD_MAX

    def _beat(self, found: list[ThrowChoice]) -> float | None:
        """The cycle estimate [s] a plan in the next release bounds must beat to be kept
        (`soonest_of` of the plans `found` so far), where one that asks no more of the
        grip than it holds has it; None (nothing to beat: every release is timed) without
        `cycle_search`, or where there is none."""
        if not self.cycle_search or not found or found[0].cost is None:
            return None
        cost = soonest_of(found).cost
        return None if cost is None or cost[0] else cost[1]

    @staticmethod
    def _soonest_release(obj: ObjectParams, found: list[ThrowChoice]) -> ThrowChoice:
        """`soonest_of` the plans `found`, logged where it is not the first."""
        first, best = found[0], soonest_of(found)
        if best is not first:
            log.info(
                "%s: released %.2f m high, %.2f s sooner a cycle than in the cell's bounds",
                obj.name or obj.shape,
                best.plan.z_m,
                first.cost[1] - best.cost[1],  # type: ignore[index]
            )
        return best

    def _release_bounds(self, target: Any) -> tuple[list[Any], list[Any]]:
        """The release bounds a plan is made in (`_plan_facing`): the cell's, then lower
        and flatter (RELEASE_FALLBACKS); and each of those in a release box shrunk about
        its centre (each of RELEASE_BOX_SHRINKS in turn), tried where none of the first is
        reached. One that would leave no elevation range is skipped.

        Tried and left out: into a bin with a low rim (0.05 m), steep throws first
        (elevation ≥ 50°): of 10 throws of 5 objects, 4 landed against 8 with the least
        energy throw (a cube slides out either way, coming down at 49° or at 52°); from
        60°, coming down at 69-74°, they stay (`cell.arm.steep.steep_tiers`). Nor
        does aiming short of the centre help: with the aim half-way to the near wall, 138
        of 168 throws into 0.05 and 0.08 m rims 1.3-2.7 m out stayed in, against 139
        aimed at the centre (a 50 mm cube slides out of half of them either way)."""
        b = self.bounds
        ordinary = [b] + [
            dc_replace(b, elevation_max=min(b.elevation_max, e_max), release_height=h)
            for e_max, h in self.tuning.release_fallbacks
        ]
        lo, hi = np.asarray(b.position_min, float), np.asarray(b.position_max, float)
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        inner = [
            dc_replace(x, position_min=tuple(mid - k * half), position_max=tuple(mid + k * half))
            for k in self.tuning.release_box_shrinks
            for x in ordinary
        ]
        return (
            [x for x in ordinary if x.elevation_min <= x.elevation_max],
            [x for x in inner if x.elevation_min <= x.elevation_max],
        )

    def _plan_once(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        index: int,
        stroke_max_m: float,
        bounds: Any,
        steep: bool = True,
    ) -> tuple[Any, float, np.ndarray, ObjectParams, bool]:
        """(the plan, the learned ΔL_s [m], the aim [m, W], the object as the plan models
        it, whether it was steepened for the grip) of a throw to `goal` in release `bounds`,
        its stroke within `stroke_max_m` [m]."""
        # Identified η_o where the parameter file has them (seen objects), else the
        # catalogue's; with a residual, only those the residual was trained with, so
        # that L_s + ΔL_s means what it meant in training.
        use_identified = self.residual is None or obj.name in self.residual.identified_objects
        model_obj = self.params.model_object(obj) if use_identified else obj
        plan = plan_clean(self.params, obj, model_obj, goal, bounds)
        if plan.stroke_m > stroke_max_m:  # the grip would not hold it there: plan within it
            bounds = grip_bounds(bounds, self.params, stroke_max_m, obj.name or obj.shape)
            plan = plan_clean(self.params, obj, model_obj, goal, bounds)
        steepened = False
        if steep:
            plan, bounds, steepened = self._steep_enough(obj, model_obj, goal, plan, bounds)
        aimed = np.asarray(goal, float)
        if self.learn:
            aim = self._corrected_aim(obj, plan, np.asarray(goal, float))
            if aim is not None:
                try:
                    plan = plan_clean(self.params, obj, model_obj, tuple(aim), bounds)
                    aimed = aim
                except UnreachableTarget:
                    log.info(
                        "learned aim for %s is out of reach: the model's aim is kept", obj.name
                    )
        if self.residual is None:
            return plan, 0.0, aimed, model_obj, steepened
        from cell.residual.model import residual_for_plan

        corrected = residual_for_plan(self.residual, obj, plan)  # clipping is logged there
        return plan, corrected.stroke_m - plan.stroke_m, aimed, model_obj, steepened

    def _steep_enough(
        self, obj: ObjectParams, model_obj: ObjectParams, goal: Any, plan: Any, bounds: Any
    ) -> tuple[Any, Any, bool]:
        """The plan, re-planned with its elevation raised where holding the item still at
        its release would ask more of the grip than a carry may (`release_elevation_min`:
        a tall item whose weight on a pad tilts it out, a 200 mm bottle below 37° at a
        58 mm stroke), and the bounds it was planned in. Up to three times, as the stroke
        of the steeper plan changes the grip; the plan kept when no steeper one reaches
        the goal; and whether it was raised."""
        steepened = False
        for _ in range(3):
            e_min = release_elevation_min(
                self.params, obj, plan.stroke_m, plan.elevation_rad, bounds.elevation_max
            )
            if e_min is None:
                break
            steep = dc_replace(bounds, elevation_min=max(bounds.elevation_min, e_min))
            try:
                plan, bounds = plan_clean(self.params, obj, model_obj, goal, steep), steep
                steepened = True
            except UnreachableTarget:
                log.info("%s: no release steep enough for the grip reaches the goal", obj.name)
                break
            log.info(
                "%s: released at %.0f° or steeper so the grip holds it still there",
                obj.name or obj.shape,
                math.degrees(e_min),
            )
        return plan, bounds, steepened


def _no_release(err: IKFailed, bounds: Any) -> IKFailed:
    """`err` (the first release IK missed), saying that none in the release box of
    `bounds` and its fallbacks was reached: on an arm that reaches none (the
    SO-ARM100's), the pose named alone read as if that one were the cell's release. A new
    exception of the same kind (a failure kept for reuse, `cell.arm.kinematics`, is not
    changed)."""
    from cell.robot.ik_pose import IKNoSolution

    lo, hi = bounds.position_min, bounds.position_max
    box = ", ".join(f"{a} {lo[k]:g} to {hi[k]:g}" for k, a in enumerate("xyz"))
    msg = (
        f"{err} (the first release tried; no release with the grip in the cell's release "
        f"box, {box} m, nor in its lower and smaller fallbacks, was reached by the arm)"
    )
    if isinstance(err, IKNoSolution):
        return IKNoSolution(msg, err.position_error_m, err.axis_error_rad, err.q_best)
    return IKFailed(msg)
