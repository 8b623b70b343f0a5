"""How an item rests on the pick station, measured in the scene.

The throw model and the grip probe have an item seated in the grip in its catalogue
frame (its z along the throw axis, the carriage's face under it), and the kinematic pick
seats it so. That is how a real pick holds it only where the item rests on the station
as its catalogue frame has it: the physical pick (`cell.arm.pick.Pick._grip_plan`)
comes down over it as it lies. A mesh's catalogue frame need not be how it rests:
`shard_661` stands on its 40 mm edge in it and tips over 22° on the station.

`rest_shift` drops the item on the station of a scene without an arm as the cell sets
it down (1 mm over it, its catalogue frame turned about the vertical), at each of
REST_YAWS_RAD, steps until it rests (`cell.sim.settle.Tracker`) or REST_MAX_S,
and reads how far its surface moved from its catalogue frame: the tilt (its z axis
from the vertical) and the largest displacement of a vertex of its hull under that tilt
about its centre of mass (the turn about the vertical left out: the pick turns with the
item). Measured (2026-11-29): rock_000 0.0° (0.0 mm), rock_472 0.6° (0.3 mm), the egg
0.0°, shard_661 22.5° (13.2 mm), the duck 12-24°, the teddy 25.5° (14.4 mm).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from cell.model.objects import ObjectParams

__all__ = ["REST_YAWS_RAD", "RestPose", "rest_shift"]

REST_YAWS_RAD = (0.0, 1.0, 2.0, 3.0)  # [rad] the turns about the vertical it is dropped at
REST_MAX_S = 1.5  # [s] the longest it is left to settle (a mesh rests within 0.3 s)


@dataclass(frozen=True)
class RestPose:
    """How an item rests on the station against its catalogue frame (the worst of the
    drops at REST_YAWS_RAD).

    Attributes:
        tilt_rad: [rad] its z axis from the vertical.
        shift_m: [m] the largest displacement of its surface (its hull's vertices) by
            that tilt about its centre of mass.
    """

    tilt_rad: float
    shift_m: float


@functools.lru_cache(maxsize=64)
def rest_shift(obj: ObjectParams) -> RestPose:
    """How `obj` (its catalogue frame) rests on the pick station, measured in the scene
    (cached per object)."""
    v = _surface(obj)
    worst = RestPose(0.0, 0.0)
    for yaw in REST_YAWS_RAD:
        rot = _rested(obj, yaw)
        z_body = rot[:, 2]
        tilt = math.acos(max(-1.0, min(1.0, float(z_body[2]))))
        axis = np.cross(z_body, (0.0, 0.0, 1.0))
        norm = float(np.linalg.norm(axis))
        if norm < 1e-12:
            continue
        axis /= norm
        p = v @ rot.T  # the surface as it rests, about its centre of mass [m, W]
        off_axis = p - np.outer(p @ axis, axis)
        shift = 2 * math.sin(tilt / 2) * float(np.linalg.norm(off_axis, axis=1).max())
        if shift > worst.shift_m:
            worst = RestPose(tilt, shift)
    return worst


def _surface(obj: ObjectParams) -> np.ndarray:
    """Points of the item's surface [m] in its catalogue frame about its centre of mass
    (its box's centre), shape (n, 3): a catalogue mesh's vertices; else its box's corners."""
    from cell.catalogue import catalogue, mesh_vertices

    entry = catalogue().get(obj.name or "")
    if obj.shape == "mesh" and entry is not None and obj.mesh:
        return np.asarray(mesh_vertices(obj.mesh, entry.mesh_scale), float)
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    return np.asarray(corners, float) * np.asarray(obj.size) / 2


def _rested(obj: ObjectParams, yaw: float) -> np.ndarray:
    """The item's rotation matrix [W] once it rests (`cell.sim.settle.Tracker.at_rest`: the
    thresholds a landing is scored by), dropped as the cell sets it down."""
    from cell.sim.scene import CellScene

    with CellScene(robot=None) as sc:
        item = sc.spawn_item(obj.name if obj.shape == "mesh" else obj, yaw=yaw)
        tracker, t_end = sc.track(item), sc.t + REST_MAX_S
        while not tracker.at_rest and sc.t < t_end:
            sc.step()
        return sc.item_pose(item)[1]
