"""The physical pick: the item rests on the station at a seeded random pose, the arm grips
it by contact (no teleport), and a grasp that fails is detected, retried once, recorded.

Independent checks: the plant's own contact points (both pads on the item, nothing
resetting its pose or tying it with a constraint), its height (lifted with the grip), and
its pose in the end-effector frame against where the throw model puts it (centre on the
throw axis, top on the carriage's face at L_s + size_z/2).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.arm.tuning import TUNING
from cell.catalogue import get_object
from cell.jobs import parse_job
from cell.model.objects import ObjectParams
from cell.orchestrator import Orchestrator
from cell.sim.band import FINGER_LEFT, FINGER_RIGHT

JOB = """\
cell: {robot: panda}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
%s
seed: 7
"""


@pytest.fixture
def orch(tmp_path: Path) -> Iterator[Orchestrator]:
    items = (
        "  - {object: cube50, count: 2, bin: far}\n"
        "  - {shape: cuboid, mass_kg: 0.04, size_m: [0.03, 0.05, 0.06], bin: near}"
    )
    job = parse_job(JOB % items, str(tmp_path / "job.yaml"))
    # the pick is checked, not the release search or the turn: both off, for speed
    o = Orchestrator(job, session="pick", pick="physical", cycle_search=False, turn_release=False)
    yield o
    o.close()


@contextmanager
def watch_item_teleports(client: Any, body: int) -> Iterator[list[str]]:
    """Record every client call that sets the item's pose or velocity, or ties it to
    another body with a constraint (a kinematic grasp does both)."""
    seen: list[str] = []
    names = ("resetBasePositionAndOrientation", "resetBaseVelocity", "createConstraint")
    originals = {n: getattr(client, n) for n in names}

    def wrap(name: str) -> Any:
        def call(*args: Any, **kw: Any) -> Any:
            bodies = [a for a in args if isinstance(a, int)]
            bodies += [
                kw.get(k) for k in ("objectUniqueId", "parentBodyUniqueId", "childBodyUniqueId")
            ]
            if body in bodies:
                seen.append(name)
            return originals[name](*args, **kw)

        return call

    for n in names:
        setattr(client, n, wrap(n))  # instance attributes win over BulletClient.__getattr__
    try:
        yield seen
    finally:
        for n in names:
            delattr(client, n)


def item_in_ee(o: Orchestrator, item: Any) -> tuple[np.ndarray, np.ndarray]:
    """The item's centre [m] and rotation in the end-effector frame E."""
    cl, sc = o.scene.client, o.scene
    inv = cl.invertTransform(*cl.getBasePositionAndOrientation(sc.ee_body))
    p, q = cl.multiplyTransforms(*inv, *cl.getBasePositionAndOrientation(item.body))
    return np.asarray(p), np.asarray(cl.getMatrixFromQuaternion(q)).reshape(3, 3)


def test_items_rest_at_a_seeded_random_spot_and_yaw(orch: Orchestrator, tmp_path: Path) -> None:
    sc = orch.scene
    obj = get_object("cube50")
    poses = []
    for index in (0, 1):
        item = orch._spawn_at_station(index, obj)
        p, rot = orch._item_pose(item)
        poses.append((p, math.atan2(rot[1, 0], rot[0, 0])))
        sc.remove_item(item)
    (p0, yaw0), (p1, yaw1) = poses
    x0, y0 = sc.pick_station_xy
    for p, _ in poses:  # within the scatter, resting on the station's top
        assert (
            abs(p[0] - x0) <= TUNING.pick_scatter_m + 1e-3
            and abs(p[1] - y0) <= TUNING.pick_scatter_m + 1e-3
        )
        assert p[2] == pytest.approx(sc.pick_station_height + obj.size[2] / 2, abs=1e-3)
    assert np.linalg.norm(p0[:2] - p1[:2]) > 1e-3 or abs(yaw0 - yaw1) > 1e-2  # items differ
    # the same job (seed) puts item 0 at the same pose in another scene
    again = Orchestrator(orch.job, session="again", pick="physical")
    try:
        p, rot = again._item_pose(again._spawn_at_station(0, obj))
        assert np.allclose(p, p0, atol=1e-6) and math.atan2(rot[1, 0], rot[0, 0]) == pytest.approx(
            yaw0
        )
    finally:
        again.close()


# a box of cuboid_a's section (30 x 50 mm) but 40 g: cuboid_a's 50 g is just over what the
# pads hold at 30 mm with the carrying margin (cell.model.grip), and the cell refuses it
BOX_30X50 = ObjectParams(shape="cuboid", mass=0.04, size=(0.03, 0.05, 0.06), name="box30x50")


@pytest.mark.parametrize("name", ["cube50", "box30x50"])
def test_pick_lifts_the_item_by_contact_without_teleport(orch: Orchestrator, name: str) -> None:
    """From its random pose: both pads on it, lifted with the grip, seated as the throw
    model assumes (box30x50: a 30 x 50 mm section, gripped across its 30 mm side, so the
    wrist must turn with its yaw)."""
    obj = BOX_30X50 if name == "box30x50" else get_object(name)
    sc, cl = orch.scene, orch.scene.client
    item = orch._spawn_at_station(1, obj)
    z_rest = orch._item_pose(item)[0][2]
    stroke = 0.06
    with watch_item_teleports(cl, item.body) as teleports:
        q_lift = orch._pick(obj, item, stroke, 0.0, True)
        orch.move([q_lift])  # up to the lift pose, as the carry starts
    assert teleports == []
    links = {c[3] for c in cl.getContactPoints(bodyA=sc.ee_body, bodyB=item.body)}
    assert {FINGER_LEFT, FINGER_RIGHT} <= links
    assert orch._item_pose(item)[0][2] - z_rest == pytest.approx(TUNING.lift_m, abs=0.01)
    # seated: centre on the throw axis, between the pads, top at the carriage's face
    p, rot = item_in_ee(orch, item)
    assert math.hypot(p[0], p[1]) < 1.5e-3
    assert 0.0 <= p[2] - (stroke + obj.size[2] / 2) < 1.5e-3
    assert abs(rot[2, 2]) > math.cos(math.radians(2.0))  # its z along the throw axis
    # gripped across its x (its width; a cube's y is as good)
    across = max(abs(rot[0, 0]), abs(rot[0, 1])) if obj.shape == "cube" else abs(rot[0, 0])
    assert across > math.cos(math.radians(2.0))
    assert orch.ee.band.width() == pytest.approx(obj.width, abs=1e-3)


def test_the_teleport_watch_sees_a_kinematic_grasp(orch: Orchestrator) -> None:
    """The watch of the test above catches what the old, kinematic grasp did."""
    item = orch._spawn_at_station(0, get_object("cube50"))
    with watch_item_teleports(orch.scene.client, item.body) as teleports:
        orch.ee.grasp(0.06, item)
    assert "resetBasePositionAndOrientation" in teleports and "createConstraint" in teleports


def count_attempts(o: Orchestrator, monkeypatch: pytest.MonkeyPatch) -> list[int]:
    calls: list[int] = []
    once = o._pick_once

    def counted(*args: Any, **kw: Any) -> Any:
        calls.append(1)
        return once(*args, **kw)

    monkeypatch.setattr(o, "_pick_once", counted)
    return calls


def test_a_too_slippery_grip_fails_after_one_retry_and_the_run_goes_on(
    orch: Orchestrator, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Pads greased for the first item: they close on it (both touch it) but cannot lift
    its weight; the slip shows on the lift, the pick is tried once more, then recorded."""
    cl, ee = orch.scene.client, orch.scene.ee_body
    for j in (FINGER_LEFT, FINGER_RIGHT):
        cl.changeDynamics(ee, j, lateralFriction=0.05)
    attempts = count_attempts(orch, monkeypatch)
    specs = orch.job.expanded_items()
    r = orch.run_item(0, specs[0])
    assert r.action == "failed" and r.failure == "grasp_failed"
    assert len(attempts) == TUNING.pick_attempts == 2
    assert (
        f"attempt {TUNING.pick_attempts} of {TUNING.pick_attempts}" in r.reason
        and "slipped" in r.reason
    )
    assert orch.ee.item is None
    for j in (FINGER_LEFT, FINGER_RIGHT):
        cl.changeDynamics(ee, j, lateralFriction=orch.scene.geometry.pad_friction)
    attempts.clear()
    r = orch.run_item(1, specs[1])  # the next item is picked at once and thrown
    assert r.action == "throw" and r.in_bin and len(attempts) == 1


def test_an_item_displaced_after_the_approach_is_missed_then_picked_on_the_retry(
    orch: Orchestrator, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The item is knocked 6 cm aside (a disturbance, outside the pick) once the grip has
    come down over it: the pads close on nothing, which the plant's contacts show, and the
    retry picks it where it now lies."""
    close_on = orch.ee.close_on
    knocked: list[int] = []

    def knock_then_close(item: Any, **kw: Any) -> None:
        if not knocked:
            knocked.append(1)
            cl = orch.scene.client
            p, o = cl.getBasePositionAndOrientation(item.body)
            cl.resetBasePositionAndOrientation(item.body, [p[0], p[1] + 0.06, p[2]], o)
        close_on(item, **kw)

    monkeypatch.setattr(orch.ee, "close_on", knock_then_close)
    attempts = count_attempts(orch, monkeypatch)
    r = orch.run_item(0, orch.job.expanded_items()[0])
    assert knocked and len(attempts) == 2
    assert r.action == "throw" and r.in_bin


def test_an_item_knocked_off_the_station_is_not_retried(
    orch: Orchestrator, monkeypatch: pytest.MonkeyPatch
) -> None:
    close_on = orch.ee.close_on

    def knock_off_then_close(item: Any, **kw: Any) -> None:
        cl = orch.scene.client
        _, o = cl.getBasePositionAndOrientation(item.body)
        cl.resetBasePositionAndOrientation(item.body, [0.45, -0.9, 0.05], o)  # on the floor
        close_on(item, **kw)

    monkeypatch.setattr(orch.ee, "close_on", knock_off_then_close)
    attempts = count_attempts(orch, monkeypatch)
    r = orch.run_item(0, orch.job.expanded_items()[0])
    assert r.failure == "grasp_failed" and "pads closed to" in r.reason
    assert len(attempts) == 1


def test_an_item_that_slips_out_while_carried_is_dropped_while_carried(
    orch: Orchestrator, monkeypatch: pytest.MonkeyPatch
) -> None:
    pick = orch._pick

    def pick_then_grease(obj: Any, item: Any, *args: Any, **kw: Any) -> Any:
        q = pick(obj, item, *args, **kw)
        orch.scene.client.changeDynamics(item.body, -1, lateralFriction=0.01)
        return q

    monkeypatch.setattr(orch, "_pick", pick_then_grease)
    r = orch.run_item(0, orch.job.expanded_items()[0])
    assert r.action == "failed" and r.failure == "dropped_while_carried"


def test_an_unknown_pick_mode_is_refused(tmp_path: Path) -> None:
    from cell.errors import InvalidInput

    job = parse_job(JOB % "  - {object: cube50, count: 1, bin: far}", str(tmp_path / "j.yaml"))
    with pytest.raises(InvalidInput, match="pick 'magic'"):
        Orchestrator(job, pick="magic")
