"""The place: the carry over a bin and down onto a spot clear of what it holds
(`cell.arm.spots`).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import GRIP_DOWN, spline_within_limits
from cell.arm.spots import (
    footprint_radius,
    housing_below_rim,
    kept_circles,
    place_spots,
    place_wall_margin_m,
)
from cell.decision import Decision
from cell.errors import (
    IKFailed,
)
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


class Place(ArmBase):
    """The place (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _carry_to_place(self, d: Decision, obj: ObjectParams, q_lift: np.ndarray) -> None:
        """Over the bin, then down into it on a short move of its own (a spline through
        both would cut the corner and sweep the item through the bin's wall)."""
        self._placing = True
        try:
            self._carry_to_spot(d, obj, q_lift)
        finally:
            self._placing = False

    def _carry_to_spot(self, d: Decision, obj: ObjectParams, q_lift: np.ndarray) -> None:
        sc = self.scene
        target = d.state.target
        # a spot on the bin's floor clear of what it holds (its centre while it is empty),
        # and of the walls by the pads (and the housing, where it goes down below the rim):
        # `place_wall_margin_m`, which the job check reads as well (`cell.jobcheck`)
        floor = sc.bin_spec(target.id).wall + obj.size[2] / 2 + self.tuning.place_clearance_m
        at_floor = self._tcp_for_item_centre(np.array([0, 0, floor]), *GRIP_DOWN, d.stroke_m, obj)
        housing_low = self._housing_below_rim(at_floor[2], target)
        pads = place_wall_margin_m(sc.geometry, obj, housing_low)

        # the best spot the arm reaches over and down to, on one IK branch: the down pose
        # solved down the vertical from over the spot, each step from the one above
        # (`_down_vertical`; solved from where the arm is, the two came out 3.5 rad apart
        # on a UR5, random layout 11, and the line between them swept the grip through the
        # bin; solved from over the spot in one step, the demo's last teddy went down onto
        # a Panda branch 1.4-1.7 rad away in four joints: 1.2 s down, 2.0 s back up); the
        # next spot where the arm reaches none there
        def poses(spot: tuple[float, float, float], on_branch: bool) -> tuple[Any, ...]:
            sx, sy, surface_z = spot
            centre = np.array([sx, sy, obj.size[2] / 2 + self.tuning.place_clearance_m + surface_z])
            above = centre + np.array([0, 0, max(self.tuning.lift_m, target.rim_height + 0.05)])
            q_above = self.ik_frame(self._tcp_for_item_centre(above, *GRIP_DOWN, d.stroke_m, obj))
            tcp_down = self._tcp_for_item_centre(centre, *GRIP_DOWN, d.stroke_m, obj)
            if not on_branch:
                return centre, q_above, self.ik_frame(tcp_down)
            return centre, q_above, self._down_vertical(q_above, tcp_down)[-1]

        spots = place_spots(sc, target.id, obj, wall_margin_m=pads)
        for spot in self.spots_to_try(spots, sc.bin_spec(target.id).wall):
            try:
                centre, q_above, q_down = poses(spot, on_branch=True)
                break
            except IKFailed:
                log.info("place: no IK at the spot (%.3f, %.3f) m: the next spot", *spot[:2])
        else:  # none on one branch: the first spot, each pose from where the arm is
            centre, q_above, q_down = poses(spots[0], on_branch=False)
        # where the housing goes below the rim, the vertical between them, through
        # configurations on it: a joint-space line between the two strays sideways, and
        # the housing met the bin's wall
        inner = self._vertical(q_above, q_down) if housing_low else []
        d.state.rise = [*inner[::-1], q_above]
        way = self._departure(q_lift, q_above)
        bottom = centre[2] - obj.size[2] / 2  # the item's lowest point at the spot [m]
        # over the spot without stopping there, straight, or through the point where the
        # item's lowest point is DEPARTURE_CLEAR_M over the rim (the bins stand on the floor)
        mid = centre + np.array(
            [0.0, 0.0, target.rim_height + self.tuning.departure_clear_m - bottom]
        )
        for via in ([], [mid]):
            try:
                qs = [
                    self.ik_frame(
                        self._tcp_for_item_centre(v, *GRIP_DOWN, d.stroke_m, obj), q_above
                    )
                    for v in via
                ]
            except IKFailed:
                continue
            if self.descends_straight([self.q, *way, *qs, q_down], bottom, target, obj):
                log.debug("place: over the spot without stopping (%d via)", len(via))
                self.move([*way, *qs, q_down])
                break
        else:
            log.debug("place: stopping over the spot")
            self.move(way)
            self.move([*inner, q_down])
        d.state.q_above = q_above

    def spots_to_try(
        self, spots: list[tuple[float, float, float]], floor_z: float
    ) -> list[tuple[float, float, float]]:
        """The place spots tried, in order: the best PLACE_SPOTS_TRIED (`place_spots`),
        then as many of the rest nearest the robot's base, those on the bin's floor
        first: a bin whose middle is beyond the arm's reach may have its near side within
        it (random layout 3's bin, 0.87 m from a UR5, whose TCP over it with a 200 mm bottle
        held down misses the centre by 40 mm; a Panda's 0.92 m out in layout 18 it does
        not reach anywhere: a place there still fails with IK)."""
        first = spots[: self.tuning.place_spots_tried]
        rest = sorted(
            spots[self.tuning.place_spots_tried :],
            key=lambda s: (s[2] > floor_z + 1e-6, math.hypot(s[0], s[1])),
        )
        return first + rest[: self.tuning.place_spots_tried]

    def _housing_below_rim(self, tcp_z: float, target: Any) -> bool:
        """Is the housing below the `target` bin's rim + 1 cm with the grip pointing down
        and the TCP at height tcp_z [m]?"""
        return housing_below_rim(self.scene.geometry, tcp_z, target.rim_height)

    def descends_straight(
        self,
        waypoints: list[np.ndarray],
        bottom_z: float,
        target: Any,
        obj: ObjectParams,
        n: int = 400,
    ) -> bool:
        """May a place's carry pass over its spot without stopping? The spline through
        `waypoints` (ending at the spot, the item's lowest point then at bottom_z [m]) must
        stay within the joint limits, never dip below its end, and, wherever the item's
        lowest point is below DEPARTURE_CLEAR_M over the rim of the `target` bin, keep the
        grip (the item's footprint, and the open pads' reach) as far from the bin's walls,
        and the item as far from what the bin already holds, as the spot does (or 1 cm),
        though it cuts the corner the stop over the spot makes."""
        sc = self.scene
        spec = sc.bin_spec(target.id)
        r_item = max(obj.size[0], obj.size[1]) / 2
        r_grip = max(r_item, self._grip_reach_m())
        # footprints as the circles that hold them (`place_spots`)
        held = [(c[:2], r) for c, r, _ in kept_circles(sc, target.id)]
        r_foot = footprint_radius(obj)

        r_housing = sc.geometry.housing_radius_m

        def clearance(p: np.ndarray) -> float:
            x, y = np.abs(spec.to_local(p[:2].tolist()))
            r = r_grip
            if self._housing_below_rim(p[2], target):  # the housing too
                r = max(r, r_housing)
            walls = min(spec.size_xy[0] / 2 - x, spec.size_xy[1] / 2 - y) - r
            items = min(
                (float(np.linalg.norm(p[:2] - c)) - rc - r_foot for c, rc in held), default=1.0
            )
            return float(min(walls, items))

        qs = spline_within_limits(self.robot, waypoints, n)
        if qs is None:
            return False
        end = self.robot.tcp_pose(qs[-1])[0]
        need = min(clearance(end), 0.01) - 1e-3
        for q in qs:
            p = self.robot.tcp_pose(q)[0]
            dz = p[2] - end[2]
            if dz < -1e-3:
                return False
            if (
                bottom_z + dz < target.rim_height + self.tuning.departure_clear_m
                and clearance(p) < need
            ):
                return False
        return True
