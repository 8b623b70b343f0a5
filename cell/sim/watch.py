"""Watching a released item in the scene: until its centre crosses a height, until it
rests, or whether it has settled yet; where it went (`Outcome`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cell.errors import NoLanding
from cell.sim.bins import which_bin
from cell.sim.items import Item
from cell.sim.settle import Outcome, Tracker, crossing

if TYPE_CHECKING:
    from cell.sim.scene import CellScene


def watch_until_crossing(
    scene: CellScene, item: Item, land_z: float, *, timeout_s: float = 4.0
) -> tuple[float, float, float]:
    """Step until the item's centre of mass crosses z = land_z going down.

    Returns:
        (x [m], y [m], t [s] since release) of the crossing (see Outcome.crossing).

    Raises:
        NoLanding: it touched down first, or the timeout passed.
    """
    scene.set_timestep(scene.dt_s)
    tr = scene._trackers.get(item.body) or scene.track(item)
    t_end = scene.t + timeout_s
    try:
        while scene.t < t_end:
            scene.step()
            z = tr.samples[-1][3]
            if z <= land_z and tr.samples[-2][3] > z:
                return crossing(np.asarray(tr.samples), land_z)
            if tr.touchdown is not None:
                break
    finally:
        scene._trackers.pop(item.body, None)
    raise NoLanding(
        f"item {item.obj.name or item.body} did not cross z = {land_z:.3f} m in free flight"
    )


def watch_until_rest(scene: CellScene, item: Item, *, timeout_s: float = 6.0) -> Outcome:
    """Step until the item rests (or the timeout) and report where it went.

    Tracking starts at the last `track` call (the end-effector's throw and
    place start it at release), else now.

    Raises:
        NoLanding: the item never touched anything but the end-effector.
    """
    scene.set_timestep(scene.dt_s)
    tr = scene._trackers.get(item.body) or scene.track(item)
    t_end = scene.t + timeout_s
    while not tr.at_rest and scene.t < t_end and not fell_out(tr):
        scene.step()
    return end_watch(scene, item, tr, timeout_s)


def outcome_if_settled(scene: CellScene, item: Item, *, timeout_s: float = 6.0) -> Outcome | None:
    """Where a tracked item went, once it rests or `timeout_s` after its release; None
    while it is still moving. Lets the loop go on with the next item while this one
    flies (the physics steps it with everything else); its track is the same as
    `watch_until_rest` would have recorded.

    Raises:
        InvalidInput: the item is not being tracked.
        NoLanding: it never touched anything but the end-effector.
    """
    tr = scene.tracker(item)
    if tr.at_rest or scene.t >= tr.t0 + timeout_s or fell_out(tr):
        return end_watch(scene, item, tr, timeout_s)
    return None


def fell_out(tr: Tracker) -> bool:
    """The item fell out of the world (below z = -1 m)."""
    return bool(tr.samples) and tr.samples[-1][3] < -1.0  # fell out of the world


def end_watch(scene: CellScene, item: Item, tr: Tracker, timeout_s: float) -> Outcome:
    """Stop tracking the item and report where it went (`Outcome`, its bin scored as
    `CellScene.in_bin` does)."""
    scene._trackers.pop(item.body, None)
    if tr.touchdown is None:
        raise NoLanding(f"item {item.obj.name or item.body} never touched down in {timeout_s} s")
    out = tr.outcome(None)
    return Outcome(
        touchdown_xyz=out.touchdown_xyz,
        touchdown_speed=out.touchdown_speed,
        touchdown_body=out.touchdown_body,
        rest_xyz=out.rest_xyz,
        bin_id=which_bin(out.rest_xyz, scene.bins, above_rim_m=max(item.obj.size) / 2),
        rested=out.rested,
        t_touchdown=out.t_touchdown,
        t_rest=out.t_rest,
        track=out.track,
    )


def sample_trackers(scene: CellScene) -> None:
    """Record a sample of every tracked item after a physics step: its position [m, W],
    velocity [m/s, W], spin [rad/s, W] and contacts at the scene time [s]. A tracker
    whose item rests records nothing more (`Tracker.sample`), so its item is not read; the
    contacts are read only until the touchdown, the one thing `Tracker.sample` uses them for."""
    cl = scene.client
    t = scene.t
    for body, tr in scene._trackers.items():
        if tr.rest_t is not None:
            continue
        pos, _ = cl.getBasePositionAndOrientation(body)
        vel, spin = cl.getBaseVelocity(body)
        contacts = cl.getContactPoints(bodyA=body) if tr.needs_contacts else []
        tr.sample(t, pos, np.array(vel, float), np.array(spin, float), contacts)
