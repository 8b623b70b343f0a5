"""Items on the pick station and in the bins: where a new item is set on the station
(over any item resting there), and an item left resting in a bin (`keep`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from cell.model.objects import ObjectParams
from cell.sim.items import Item

if TYPE_CHECKING:
    from cell.sim.scene import CellScene


def station_top(scene: CellScene) -> float:
    """Height above which a new item fits on the pick station (over any item resting
    there; not over one flying past, which is still being tracked) [m]."""
    top = scene.pick_station_height
    x0, y0 = scene.pick_station_xy
    for it in scene.items:
        if it.body in scene._trackers or it.body in scene._kept:
            continue
        p, _ = scene.client.getBasePositionAndOrientation(it.body)
        if abs(p[0] - x0) < 0.15 and abs(p[1] - y0) < 0.15 and p[2] > top - 0.05:
            top = max(top, p[2] + float(np.linalg.norm(it.obj.size)) / 2)
    return top


def drop_pose(
    scene: CellScene, obj: ObjectParams, offset_xy: Sequence[float], yaw: float, gap_m: float
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """Where a new item is set on the pick station: its centre of mass [m, W] `offset_xy`
    from the station's centre, its box `gap_m` over the station's top (over any item
    resting there), and its orientation (quaternion x y z w, turned `yaw` [rad] about the
    vertical)."""
    position = (
        scene.pick_station_xy[0] + float(offset_xy[0]),
        scene.pick_station_xy[1] + float(offset_xy[1]),
        station_top(scene) + obj.size[2] / 2 + gap_m,
    )
    return position, (0.0, 0.0, float(np.sin(yaw / 2)), float(np.cos(yaw / 2)))


def keep(scene: CellScene, item: Item) -> None:
    """Leave an item resting where it is: a bin keeps what lands in it.

    It stays a body of the scene (later items land on it and may knock it about),
    but is no longer tracked nor given the drag law (a resting or nudged item moves
    at well under 1 m/s, where drag is below 0.1 % of its weight), and Bullet puts it
    to sleep until something touches it: piles of items awake in the bins would
    make every physics step several times slower (their contacts are solved at
    every step with 60 solver iterations).
    """
    cl = scene.client
    scene._trackers.pop(item.body, None)
    scene._kept.add(item.body)
    cl.changeDynamics(item.body, -1, activationState=cl.ACTIVATION_STATE_ENABLE_SLEEPING)
    cl.changeDynamics(item.body, -1, activationState=cl.ACTIVATION_STATE_SLEEP)
