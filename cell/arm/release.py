"""The release's configuration and cycle: which IK branch and roll a throw is released at,
timed as the cell makes the cycle (the release on the move: `cell.arm.release_moving`).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import PickState, joint_gap, plan_time
from cell.errors import (
    IKFailed,
    TrajectoryError,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


class ReleaseChoice(ArmBase):
    """The release's configuration and cycle (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    # [s] the chosen release's cycle estimate less its lower bound (`_release_search`), set
    # by each `_release_q`; None where no candidate was timed (`Planner._plan_in` keeps it)
    _release_room_s: float | None = None
    # [rad] the chosen release's carry route from the lift (its twist-free swing's
    # waypoints, `_swing`) where the item is carried level (`_turns_if_rolled`): the route
    # its grip use held still is judged on (`_swing_holds`); None elsewhere, or where no
    # candidate was timed (`Planner._plan_in` keeps it, `cell.arm.steep` checks its twist)
    _release_route: tuple[np.ndarray, ...] | None = None

    def _release_q(
        self,
        tcp: np.ndarray,
        plan: Any,
        stroke: float,
        obj: ObjectParams,
        beat: float | None = None,
        lower: bool = False,
    ) -> tuple[np.ndarray, tuple[bool, float] | None]:
        """The release configuration for a throw's `plan` at `tcp` [m, W], and its cycle
        estimate (None where none was made; `_plan` compares facings by it): of the two rolls
        that put the item's weight on a pad (0 and π, `solve_release_ik`), the one whose
        cycle estimate is the shorter (`_release_costs`). The pick is
        gripped at the release's roll (`_pick_frame`), so the roll chooses the pick's,
        the lift's and the swing's configurations too. Each roll's release is solved from
        the lift and from where the arm is (IK keeps the solution nearest its seed: two
        branches, the second the one `solve_release_ik` gives; with `cycle_search` from
        the pick too). Where no item is
        presented, or no candidate's moves are found, the roll nearer where the arm is
        (`solve_release_ik`); so too with the physical pick, which grips the item as it
        lies, headed by the release's roll (`_carry_heading`), not in the frame timed
        here: on the UR5 copy of the demo the roll chosen so cost four grasps (19/24 in
        bin against 23/24). A release whose route would ask more of the grip than it must
        (`_release_costs`: a tall item's swing that rolls the grip) ranks after the others.
        With `cycle_search`, the candidates are timed as the cell makes the cycle, soonest
        bound first, and `beat` [s] is a cycle estimate another release bounds' plan has
        (`_release_search`; `lower`: in one of the lower release bounds). IKFailed when
        the pose has no configuration."""
        from cell.robot.ik import WEIGHT_ROLLS_RAD

        e, a = plan.elevation_rad, plan.azimuth_rad
        best: tuple[tuple[bool, float], np.ndarray] | None = None
        self._release_room_s = self._release_route = None
        if self._presented is not None and self.pick_mode != "physical" and abs(math.cos(e)) > 1e-6:
            kept = self._frame
            try:
                if self.cycle_search:
                    best = self._release_search(tcp, plan, stroke, obj, beat, lower)
                else:
                    for roll in WEIGHT_ROLLS_RAD:
                        self._frame = (float(a), roll)  # the pick is gripped at this roll
                        for cost, q_rel in self._release_costs(tcp, plan, roll, stroke, obj):
                            log.debug("release roll %.2f rad: (slips, estimate) %s", roll, cost)
                            if best is None or cost < best[0]:
                                best = (cost, q_rel)
            finally:
                self._frame = kept
        if best is not None:
            return best[1], best[0]
        return self._ik(tcp, e, a), None

    def _release_search(
        self,
        tcp: np.ndarray,
        plan: Any,
        stroke: float,
        obj: ObjectParams,
        beat: float | None,
        lower: bool = False,
    ) -> tuple[tuple[bool, float], np.ndarray] | None:
        """`_release_q` with `cycle_search`: ((asks more of the grip than it holds, cycle
        estimate [s]), release configuration) of the soonest release at either roll, or
        None where none is found. IK is seeded from the lift, from where the arm is and
        from the pick (the configuration a carry solved again from the pick would go to);
        the estimate is the item's pick-to-pick cycle as the cell makes it
        (`_static_cycle_s`) plus APPROACH_WEIGHT of the approach from where the arm is;
        a release whose route would ask more of the grip than it holds (`_swing_holds`)
        ranks after every one that does not, as in `_release_costs`.

        Every candidate (both rolls, each seed's IK) is bounded first (`_cycle_bound_s`
        plus APPROACH_WEIGHT of the approach) and timed in ascending order of that bound:
        the soonest found early, a candidate whose bound cannot beat it (nor `beat` [s], a
        cycle another release bounds' plan already has, `_plan_facing`) is not timed, nor
        is any after it. Where candidates were left out so and none timed is found, the
        first one's configuration with the estimate (False, ∞): it cannot be chosen
        (`_soonest_release`). Ties go to the candidate first in the rolls' order
        (WEIGHT_ROLLS_RAD) and then the seeds', so the choice is the one the search timing
        every candidate makes (tests/test_release_search_cost.py). The bound a candidate is
        ranked by (`_rank_bound_s`: with `release_rank_way`, the way back planned) is
        worked out only where the candidate might be ranked before those taken so far
        (`_Ranked`, by `_rank_floor_s`, a bound on that bound): the same order, fewer ways
        back planned (tests/test_release_rank_lazy.py). With `ArmTuning.release_budget`,
        once the decision has timed that many candidates (`_timed_n`, every search of it
        counted) and a release that holds is in hand (here or `beat`), no more are timed:
        the soonest timed is kept, or (False, ∞) where it is `beat`'s
        (tests/test_release_budget.py)."""
        level = self._turns_if_rolled(obj, stroke)
        a = float(plan.azimuth_rad)
        found = self._release_candidates(tcp, plan, stroke, obj)

        def rank(c: _Cand) -> float:
            self._frame = (a, c[2])  # the pick gripped at its roll, as it was found
            return self._rank_bound_s(c[3], c[4], (stroke, obj), c[5])

        ranked = _Ranked(found, rank)
        best: tuple[tuple[tuple[bool, float], int], np.ndarray, float, Any] | None = None
        soonest = math.inf if beat is None else beat
        pruned = False
        timed, most = 0, self.tuning.release_timed_max
        if lower and self.tuning.release_timed_max_lower is not None:
            most = self.tuning.release_timed_max_lower  # in the lower release bounds
        for low, order, roll, q_rel, over, t_approach in ranked:
            if low >= soonest:
                pruned = True
                break  # nor can any after it
            if most and timed >= most:
                break  # the soonest-bounded ones timed: the rest are not (`release_timed_max`)
            if soonest < math.inf and self._budget_spent():
                pruned = True  # a release that holds is in hand: no more are timed
                break  # (`release_budget`)
            self._frame = (a, roll)
            try:
                if best is not None and not best[0][0][0]:
                    back = self._approach_s(q_rel, over, stroke, obj)  # as `_static_cycle_s`
                    if self._way_bound_s(over[0], q_rel, back, t_approach) > best[0][0][1]:
                        timed += 1  # cannot beat the best: as if timed (`_way_bound_s`)
                        continue
                way = self._swing(over[1], q_rel, plan, (obj, stroke)) if level else []
                t_cycle = self._static_cycle_s(obj, plan, stroke, q_rel, over)
            except (IKFailed, TrajectoryError):
                continue
            t = t_cycle + self.tuning.approach_weight * t_approach
            timed += 1
            self._timed_n += 1
            slips = level and not self._swing_holds(
                [over[1], *way, q_rel], (obj, stroke), plan.elevation_rad
            )
            log.debug("release roll %.2f rad: (slips, cycle estimate) (%s, %.3f)", roll, slips, t)
            if best is None or ((slips, t), order) < best[0]:
                route = (over[1], *way, q_rel) if level else None
                best = (((slips, t), order), q_rel, t - low, route)
            if not slips:
                soonest = min(soonest, t)
        if best is not None:
            self._release_room_s, self._release_route = best[2], best[3]
            return best[0][0], best[1]
        if pruned:
            return (False, math.inf), ranked.first()[3]
        return None

    def _release_candidates(
        self, tcp: np.ndarray, plan: Any, stroke: float, obj: ObjectParams
    ) -> list[_Cand]:
        """`_release_search`'s candidates: at either roll, each distinct release IK finds
        from the lift, from where the arm is and from the pick, as (a floor under its rank
        bound [s] (`_rank_floor_s`), order, roll, release, (pick, lift), approach [s]); a
        roll whose pick or approach is not found has none."""
        from cell.robot.ik import WEIGHT_ROLLS_RAD, ReleasePose

        a = float(plan.azimuth_rad)
        found: list[_Cand] = []
        for roll in WEIGHT_ROLLS_RAD:
            self._frame = (a, roll)  # the pick is gripped at this roll
            try:
                over = self.over_item(self._presented, stroke, obj)
                t_approach = self._approach_s(self.q, over, stroke, obj)
            except (IKFailed, TrajectoryError):
                continue
            pose = ReleasePose.from_angles(tcp, plan.elevation_rad, a, roll)
            mine: list[np.ndarray] = []
            for seed in (over[1], self.q, over[0]):
                try:
                    q_rel = self._release_ik(self.robot, pose, seed).q
                except IKFailed:
                    continue
                if any(joint_gap(q_rel, q) < 1e-3 for q in mine):
                    continue
                mine.append(q_rel)
                floor = self._rank_floor_s(q_rel, over, t_approach)
                found.append((floor, len(found), roll, q_rel, over, t_approach))
        return found

    def _release_costs(
        self, tcp: np.ndarray, plan: Any, roll: float, stroke: float, obj: ObjectParams
    ) -> list[tuple[tuple[bool, float], np.ndarray]]:
        """((asks more of the grip than it holds, cycle estimate [s]), release
        configuration) of each release at `roll` [rad] (`_release_q` without
        `cycle_search`; with it, `_release_search`), with the pick in the frame
        `self._frame`; none when the pick, the approach, the release or the carry is not
        found. A carry whose route, held still anywhere, would ask more of the grip than
        the carry's bound (`_swing_holds`: a tall item on a swing that rolls the grip)
        ranks after every one that does not. IK is seeded from the lift and from where the
        arm is, and keeps the solution nearest its seed.

        The estimate: the empty arm to the pick of the presented item (as `_approach_s`
        times it), plus twice the carry from its lift along the twist-free swing to the
        release, timed as `_move_plan` times a carry of this item (the next approach
        comes back about as far; with `turn_release`, the empty arm's way back from the
        release to the same pick instead: a release turned toward the station winds the
        wrist round, and the way back unwinds it)."""
        from cell.robot.ik import ReleasePose

        try:
            q_pick, q_lift = self.over_item(self._presented, stroke, obj)
            t_approach = self._approach_s(self.q, (q_pick, q_lift), stroke, obj)
        except (IKFailed, TrajectoryError):
            return []
        pose = ReleasePose.from_angles(tcp, plan.elevation_rad, plan.azimuth_rad, roll)
        out: list[tuple[tuple[bool, float], np.ndarray]] = []
        level = self._turns_if_rolled(obj, stroke)
        for seed in (q_lift, self.q):
            try:
                q_rel = self._release_ik(self.robot, pose, seed).q
                if any(joint_gap(q_rel, q) < 1e-3 for _, q in out):
                    continue
                way = self._swing(q_lift, q_rel, plan, (obj, stroke))
                carry = self._move_plan(q_lift, [*way, q_rel], self.tuning.settle_s, (obj, stroke))
                t_carry = plan_time(carry, self.tuning.settle_s)
                t_back = t_carry
                if self.turn_release:
                    t_back = self._approach_s(q_rel, (q_pick, q_lift), stroke, obj)
                t = t_approach + t_carry + t_back
            except (IKFailed, TrajectoryError):
                continue
            slips = level and not self._swing_holds(
                [q_lift, *way, q_rel], (obj, stroke), plan.elevation_rad
            )
            out.append(((slips, t), q_rel))
        return out

    def _rank_bound_s(
        self,
        q_rel: np.ndarray,
        over: tuple[np.ndarray, np.ndarray],
        held: tuple[float, ObjectParams],
        approach_s: float,
    ) -> float:
        """The lower bound [s] `_release_search` ranks the release q_rel [rad] by, the pick
        and the lift `over` (the grip in the frame `self._frame`), the item `held` (stroke
        [m], object), the approach from where the arm is `approach_s` [s]: with
        `ArmTuning.release_rank_way`, `_way_bound_s` (the way back as the cycle times it:
        TrajectoryError or IKFailed where there is none, as `_static_cycle_s` would raise),
        else `_cycle_bound_s`, each plus APPROACH_WEIGHT of the approach."""
        if not self.tuning.release_rank_way:
            return self._cycle_bound_s(over[0], q_rel) + self.tuning.approach_weight * approach_s
        back = self._approach_s(q_rel, over, held[0], held[1])
        return self._way_bound_s(over[0], q_rel, back, approach_s)

    def _rank_floor_s(
        self, q_rel: np.ndarray, over: tuple[np.ndarray, np.ndarray], approach_s: float
    ) -> float:
        """A lower bound [s] on `_rank_bound_s` of the release q_rel [rad] (the pick and the
        lift `over`, the approach `approach_s` [s]) that plans nothing: with
        `ArmTuning.release_rank_way`, `_way_bound_s` with the way back's bang-bang time
        (`_one_way_bound_s` from q_rel to the pick) for the way back planned. That way is
        the empty arm from rest at q_rel to rest at the pick within the joint limits (a
        ruckig approach at `speed_scale` of them, or two jerk-limited moves at them, each
        no quicker than its bang-bang time, which is subadditive): each joint travels at
        least its gap at no more than its limits, so it takes no less; added in the same
        order, the floating-point sum is no larger either. Without it, `_rank_bound_s`
        itself (it plans nothing)."""
        if not self.tuning.release_rank_way:
            return self._cycle_bound_s(over[0], q_rel) + self.tuning.approach_weight * approach_s
        back = self._one_way_bound_s(q_rel, over[0])
        return self._way_bound_s(over[0], q_rel, back, approach_s)

    def _cycle_bound_s(self, q_pick: np.ndarray, q_rel: np.ndarray) -> float:
        """A lower bound [s] on `_static_cycle_s` for the release q_rel [rad] of the item
        picked at q_pick [rad]: each way, from rest to rest, no joint can be quicker than
        at its full velocity and acceleration limits along the straight line (the
        bang-bang time, `_one_way_bound_s`; the carry's and the approach's limits are
        these or a fraction of them, their routes no shorter), plus the settle at the
        release and the push."""
        from cell.robot.moving_release import COAST_S

        return 2.0 * self._one_way_bound_s(q_pick, q_rel) + self.tuning.settle_s + COAST_S

    def _one_way_bound_s(self, q_pick: np.ndarray, q_rel: np.ndarray) -> float:
        """The bang-bang time [s] from rest at q_pick to rest at q_rel [rad] of the
        slowest joint at its full velocity and acceleration limits (`_cycle_bound_s`)."""
        lim = self.robot.limits
        v, a = lim.velocity * (1 + 1e-3), lim.acceleration * (1 + 1e-3)
        d = np.abs(np.asarray(q_rel, float) - np.asarray(q_pick, float))
        t = np.where(d <= v * v / a, 2.0 * np.sqrt(d / a), d / v + v / a)
        return float(np.max(t))

    def _way_bound_s(
        self, q_pick: np.ndarray, q_rel: np.ndarray, back_s: float, approach_s: float
    ) -> float:
        """A lower bound [s] on `_release_search`'s estimate for the release q_rel [rad] of
        the item picked at q_pick [rad], tighter than `_cycle_bound_s`'s: the carry's
        bang-bang bound (`_one_way_bound_s`), the settle and the push, and the way back
        as `_static_cycle_s` times it (`back_s` [s], `_approach_s`, remembered through the
        decision), plus APPROACH_WEIGHT of the approach from where the arm is
        (`approach_s` [s]). A candidate whose bound is over the best estimate timed
        cannot be chosen, and is not timed (tests/test_release_search_cost.py)."""
        from cell.robot.moving_release import COAST_S

        carry = self._one_way_bound_s(q_pick, q_rel) + self.tuning.settle_s + COAST_S
        return carry + back_s + self.tuning.approach_weight * approach_s

    def _static_carry(
        self,
        at: PickState,
        q_lift: np.ndarray,
        q_rel: np.ndarray,
        plan: Any,
    ) -> tuple[list[np.ndarray], float]:
        """(the waypoints, how long [s] `_move` takes along them) of a static throw's carry
        from the pick `at` (as `_departure` takes it) to the release q_rel [rad]: the
        route `_departure` plans and `_move_plan`'s trajectories along it, with a settle
        at each stop and at the release (tests/test_moving_choice.py: the scene's clock
        agrees within 20 ms)."""
        way = self._departure(q_lift, q_rel, plan, at)
        trajs = self._move_plan(at[0], way, self.tuning.settle_s, (at[2], at[3]))
        return way, plan_time(trajs, self.tuning.settle_s) + self.tuning.settle_s

    def _static_cycle_s(
        self,
        obj: ObjectParams,
        plan: Any,
        stroke: float,
        q_rel: np.ndarray,
        over: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> float:
        """How long [s] the cell takes from the pick of the presented item, gripped at
        `stroke` [m] in the frame `self._frame`, to its static release at q_rel [rad] for
        `plan` and back to that pick: the carry along `_departure`'s route
        (`_static_carry`), the push (COAST_S) and the empty arm's way back
        (`_approach_s`). The next item of the same kind is picked where this one was, so
        this is its pick-to-pick cycle; on random layout 3, 11 of 15 such cycles were
        within 0.03 s of the scene's. `over`: the pick's and the lift's configurations
        (`_over_item`), where known. IKFailed or TrajectoryError where a move is not
        found."""
        from cell.robot.moving_release import COAST_S

        q_pick, q_lift = over or self.over_item(self._presented, stroke, obj)
        at = (q_pick, self.scene.item_position(self._presented), obj, stroke)
        _, t_carry = self._static_carry(at, q_lift, q_rel, plan)
        return t_carry + COAST_S + self._approach_s(q_rel, (q_pick, q_lift), stroke, obj)


_Cand = tuple[float, int, float, np.ndarray, Any, float]


class _Ranked:
    """`_release_search`'s candidates in ascending order of (their rank bound, their
    order), the rank bound (`exact`, which may raise IKFailed or TrajectoryError: such a
    candidate is left out) worked out lazily. Each candidate comes with a floor under its
    rank bound (its first element, `_rank_floor_s`); a candidate whose floor is above
    the next one ranked cannot come before it, so its bound is worked out only when it
    might. The order is the one sorting every candidate by its bound gives: a heap holds
    each candidate by its floor until its bound is known, then by its bound, and the
    least (key, order) is yielded once it is a bound."""

    def __init__(self, cands: list[_Cand], exact: Any) -> None:
        import heapq

        self._cands, self._exact = cands, exact
        self._bounds: dict[int, float | None] = {}  # order -> rank bound, None: raised
        self._heap = [(c[0], c[1], False) for c in cands]
        heapq.heapify(self._heap)
        self._at = {c[1]: c for c in cands}

    def _bound(self, order: int) -> float | None:
        """The candidate's rank bound, worked out once; None where it raised."""
        if order not in self._bounds:
            try:
                self._bounds[order] = float(self._exact(self._at[order]))
            except (IKFailed, TrajectoryError):
                self._bounds[order] = None  # no way back to the pick: not timed either
        return self._bounds[order]

    def __iter__(self) -> Any:
        import heapq

        heap = self._heap
        while heap:
            key, order, known = heapq.heappop(heap)
            if known:
                yield (key, *self._at[order][1:])
                continue
            low = self._bound(order)
            if low is not None:
                heapq.heappush(heap, (low, order, True))

    def first(self) -> _Cand:
        """The first candidate (in the search's order) whose rank bound is found, with it."""
        for c in self._cands:
            low = self._bound(c[1])
            if low is not None:
                return (low, *c[1:])
        raise AssertionError("a search that pruned a candidate had one ranked")
