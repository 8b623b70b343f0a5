"""Throw campaigns in the scene and the calibration that identifies the scene's η_ee.

`throw_once` makes one throw through the cell's item loop (`cell.loop`, with the
`ReleasePose` platform) the way the cell would (grasp at the pick station, the
gripped item's centre of mass at the release point p0 as MODEL.md defines it, +z of
the end-effector along the throw axis, latch released) and returns its docs/throw_log.md
record; the landing is where the item's centre of mass crosses the plane z = land_z
while descending (MODEL.md), taken from the simulated track. The campaign holds the end-effector kinematically at each release pose
without the arm (the arm does not touch the launch: the release is from rest),
which keeps a throw to a few hundredths of a second of wall time.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.endeffector.factory import make_end_effector
from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.errors import InvalidParameter
from cell.log.records import throw_record
from cell.log.table import ThrowTable
from cell.loop import Decision, ItemLoop
from cell.model.objects import ObjectParams
from cell.sim.frames import ee_pose_for_item_centre
from cell.sim.items import resolve_object
from cell.sim.scene import CellScene

__all__ = ["CAMPAIGN_LAND_Z_M", "throw_once", "campaign_plan", "adhoc_plan", "run_campaign"]

CAMPAIGN_LAND_Z_M = 0.1  # [m] landing plane of the campaign (above any item's half-diagonal)


@dataclass
class ReleasePose:
    """The campaign's platform of the item loop (`cell.loop.Platform`): the end-effector
    held kinematically at one release pose, without an arm (the arm does not touch a
    launch from rest); the item is put into the grip there.

    Attributes:
        scene: a CellScene (robot=None).
        ee: its end-effector.
        what: catalogue id or object parameters of the item.
        stroke: L_s [m].
        position: release point p0 [m, W]: the gripped item's centre of mass (MODEL.md).
        elevation, azimuth, roll: throw axis and roll [rad].
    """

    scene: CellScene
    ee: PyBulletEndEffector
    what: str | ObjectParams
    stroke: float
    position: Sequence[float]
    elevation: float
    azimuth: float = 0.0
    roll: float = 0.0
    name = "arm"  # the release pose of an arm, without the arm
    overlaps = False
    rotor_rpm = 0.0

    def present(self, index: int, obj: ObjectParams) -> Any:
        return self.scene.spawn_item(self.what)

    def decide(self, index: int, obj: ObjectParams, target: Any) -> Decision:
        return Decision("throw", self.stroke)

    def pick(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        pose = ee_pose_for_item_centre(
            self.position, self.elevation, self.azimuth, self.stroke, obj, self.roll
        )
        self.scene.hold_ee(*pose, teleport=True)
        self.ee.grasp(self.stroke, item)

    def carry(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """Held at the release pose already."""

    def release(self, d: Decision) -> None:
        self.ee.throw()

    def finish(self, d: Decision | None) -> None:
        self.ee.item = None


def throw_once(
    scene: CellScene,
    ee: PyBulletEndEffector,
    what: str | ObjectParams,
    *,
    stroke: float,
    position: Sequence[float],
    elevation: float,
    azimuth: float = 0.0,
    roll: float = 0.0,
    land_z: float = CAMPAIGN_LAND_Z_M,
    throw_id: str = "sim",
    track: list[np.ndarray] | None = None,
) -> dict[str, Any]:
    """One throw in a scene without an arm, through the item loop (`ReleasePose`, then
    `cell.loop.ItemLoop.throw_to_plane`); returns its docs/throw_log.md record.

    Args:
        scene: a CellScene with robot=None.
        ee: its end-effector.
        what: catalogue id or object parameters.
        stroke: L_s [m].
        position: release point p0 [m, W]: the gripped item's centre of mass (MODEL.md).
        elevation, azimuth, roll: throw axis and roll [rad].
        land_z: landing plane [m].
        throw_id: the record's id.
        track: if given, the (k, 4) track t, x, y, z up to the crossing is appended to it.

    Raises:
        NoLanding: the item did not cross the plane in free flight.
    """
    obj, _ = resolve_object(what)
    pf = ReleasePose(scene, ee, what, stroke, position, elevation, azimuth, roll)
    _, (x, y, t), samples = ItemLoop(None, pf, scene).throw_to_plane(0, obj, land_z)
    if track is not None:
        track.append(samples)
    return throw_record(
        throw_id,
        obj,
        stroke_m=stroke,
        position_m=position,
        elevation_rad=elevation,
        azimuth_rad=azimuth,
        roll_rad=roll,
        land_z_m=land_z,
        landed_xy_m=(x, y),
        t_flight_s=t,
        session="sim-calibrate",
    )


VALIDATION_STREAM = 0x7A1  # the held-out throws' random stream (`campaign_plan(held_out=True)`)


def campaign_plan(
    n: int, *, seed: int = 0, objects: Sequence[str] | None = None, held_out: bool = False
) -> list[dict[str, Any]]:
    """n throw settings spread over objects, strokes, heights and elevations.

    Objects cycle through `objects` (default: the catalogue's thesis14 set);
    stroke, release height, elevation and azimuth are drawn uniformly in the
    end-effector's range, 0.5-0.9 m, 15-50° and ±30°. `held_out`: the same kind of
    throws from a random stream of their own (`VALIDATION_STREAM`, throw ids `val…`),
    never the campaign's of the same seed: the throws an identified model is validated on.

    Raises:
        InvalidParameter: n < 1 or an empty object list.
    """
    if n < 1:
        raise InvalidParameter(f"campaign size n={n} must be ≥ 1")
    ids = (
        list(objects)
        if objects is not None
        else [k for k, e in catalogue().items() if e.set == "thesis14"]
    )
    if not ids:
        raise InvalidParameter("campaign: no objects to throw")
    rng = np.random.default_rng([seed, VALIDATION_STREAM] if held_out else seed)
    tag = "val" if held_out else "cal"
    plan = []
    for i in range(n):
        plan.append(
            {
                "object": ids[i % len(ids)],
                "stroke": float(rng.uniform(0.035, 0.105)),
                "position": (0.0, 0.0, float(rng.uniform(0.5, 0.9))),
                "elevation": math.radians(float(rng.uniform(15, 50))),
                "azimuth": math.radians(float(rng.uniform(-30, 30))),
                "throw_id": f"{tag}{seed:03d}-{i:04d}",
            }
        )
    return plan


ADHOC_STREAM = 0xCA1  # the ad-hoc campaign's random stream (the bench draws from 0x5C)


def adhoc_plan(n: int, *, seed: int = 0) -> list[dict[str, Any]]:
    """n throws of ad-hoc items (one new item each) over the cell's whole envelope.

    Items are drawn as `cell.jobgen` draws a job's ad-hoc primitives (every shape,
    20–250 g at plausible densities, 25–90 mm), from a random stream of their own; an item
    the pads cannot hold is drawn again. Strokes run from the end-effector's shortest to
    the longest the grip holds the item at (`cell.orchestrator.grip_stroke_limit` with the
    scene's band), elevations 0–65°, release heights 0.5–0.9 m, azimuths ±30°.

    Raises:
        InvalidParameter: n < 1.
    """
    from cell.arm.grip_limits import grip_stroke_limit
    from cell.errors import CellError
    from cell.jobgen import _adhoc_item
    from cell.params import ModelParams

    if n < 1:
        raise InvalidParameter(f"ad-hoc campaign size n={n} must be ≥ 1")
    band = ModelParams()  # the scene's band obeys the reference law
    rng = np.random.default_rng([seed, ADHOC_STREAM])
    plan: list[dict[str, Any]] = []
    while len(plan) < n:
        d = _adhoc_item(rng)
        obj = ObjectParams(shape=d["shape"], mass=d["mass_kg"], size=tuple(d["size_m"]))
        try:
            s_max = grip_stroke_limit(band, obj)
        except CellError:
            continue
        i = len(plan)
        plan.append(
            {
                "object": obj,
                "stroke": float(rng.uniform(band.ee.stroke_min, s_max)),
                "position": (0.0, 0.0, float(rng.uniform(0.5, 0.9))),
                "elevation": math.radians(float(rng.uniform(0.0, 65.0))),
                "azimuth": math.radians(float(rng.uniform(-30, 30))),
                "throw_id": f"adhoc{seed:03d}-{i:04d}",
            }
        )
    return plan


CHUNK = 8  # throws per unit of a campaign (one fresh scene each)


def throw_chunk(chunk: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Throw planned throws in a fresh scene of their own; their records (a unit of a
    campaign on Ray: every throw teleports the end-effector and grasps a fresh item, so
    a throw's record does not depend on the throws before it)."""
    return campaign_records(chunk)


def run_campaign(
    plan: Sequence[dict[str, Any]],
    *,
    scene: CellScene | None = None,
    progress: Callable[[int], None] | None = None,
    workers: int = 1,
    address: str | None = None,
    on_records: Callable[[list[dict[str, Any]]], None] | None = None,
) -> ThrowTable:
    """Throw every planned throw in a scene (a fresh one without arm or bins by default).

    Args:
        plan: throw settings as from `campaign_plan`.
        scene: the scene to throw in (robot=None).
        progress: called with the number of throws done.
        workers, address: split the plan into chunks thrown on Ray (cell.parallel),
            each in its own scene; the same records as the serial run.
        on_records: called in this process with each chunk's records as they arrive
            (in completion order; with `scene`, once with all of them): where a caller
            appends them to its throw store, the driver being the only writer.

    Returns:
        The throw log of the campaign (docs/throw_log.md columns plus t_flight_s, session).
    """
    if scene is None:
        from cell.parallel import run_campaign as on_ray

        # Chunks of a fixed size, each thrown in a fresh scene: the records are the same
        # on one process or many (a scene's contact caches carry over between throws at
        # the 1e-13 m level, so the chunking must not depend on the worker count).
        chunks = [list(plan[i : i + CHUNK]) for i in range(0, len(plan), CHUNK)]
        done = [0]

        def tick(i: int, recs: list[dict[str, Any]]) -> None:
            done[0] += len(recs)
            if on_records is not None:
                on_records(recs)
            if progress is not None:
                progress(done[0])

        parts = on_ray(
            throw_chunk,
            chunks,
            workers=max(1, workers),
            address=address,
            desc="throws",
            on_result=tick,
            progress=False,
        )
        return ThrowTable.from_records([r for part in parts for r in part])
    records = campaign_records(plan, scene=scene, progress=progress)
    if on_records is not None:
        on_records(records)
    return ThrowTable.from_records(records)


def campaign_records(
    plan: Sequence[dict[str, Any]],
    *,
    scene: CellScene | None = None,
    progress: Callable[[int], None] | None = None,
) -> list[dict[str, Any]]:
    """The docs/throw_log.md records of the planned throws, thrown one after the other."""
    own = scene is None
    # the pick station stands behind the thrower, out of every flight path
    sc = (
        scene if scene is not None else CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0))
    )
    try:
        ee = make_end_effector("pybullet", plant=sc)
        records = []
        for k, p in enumerate(plan):
            records.append(
                throw_once(
                    sc,
                    ee,
                    p["object"],
                    stroke=p["stroke"],
                    position=p["position"],
                    elevation=p["elevation"],
                    azimuth=p["azimuth"],
                    throw_id=p["throw_id"],
                )
            )
            if progress is not None:
                progress(k + 1)
    finally:
        if own:
            sc.close()
    return records
