"""What the pads hold an item with, measured in the scene.

The grip model gives the pads' friction force (the band's closing force and μ) and the
couple they resist a turn about their axis (ee x) with, for a box or a cylinder, from
the contact patch (`cell.orchestrator.carry_hold`). A mesh meets the flat pads wherever
its surface does: no closed form. This module measures the grip as a bench would: the
item is grasped at a stroke in a scene without an arm and without gravity, then loaded
until it slips, by a force along the pads' faces (ee y), a force out of the grip along
the throw axis (ee +z), and a torque about the pads' axis, each ramped up from zero.

Measured (2026-11-25): for boxes (cube30, cube50, cuboid_b, cuboid_c, o3_cuboid50 at
0.04 and 0.07 m) the pull is 1.04-1.12 of the model's force and the couple 0.80-1.07 of
its patch couple, which was fitted to boxes hanging in the pads: two independent figures
of one grip. The duck slides along the pads at 0.69 of the model's force; the teddy at
0.88. A mesh's contacts also creep without any load (the duck and rock_472 turn 1° in
1.5-1.9 s at rest): a turn counts as slipping from SLIP_RAD, above that creep.
"""

from __future__ import annotations

import contextlib
import functools
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams

__all__ = [
    "PROBE_STROKES_M",
    "GripProbe",
    "grasped_in_scene",
    "probe_grip",
    "probe_load",
    "turn_rad",
]

FORCE_RAMP_N_S = 2.0  # [N/s] the pull's ramp
SLIP_M = 2e-3  # [m] the slide that counts as slipping
COUPLE_RAMP_NM_S = 0.05  # [N·m/s] the torque's ramp (0.02-0.2 give the same couple for a box)
SLIP_RAD = math.radians(3.0)  # [rad] the turn that counts as slipping (creep is ~1°)
PROBE_MAX_S = 6.0  # [s] the longest ramp: a grip that holds more counts as holding that
PROBE_STROKES_M = (0.04, 0.08)  # [m] the strokes a mesh's grip is probed at


@dataclass(frozen=True)
class GripProbe:
    """What the pads held an item with in the scene.

    Attributes:
        slide_n: the force along the pads' faces (ee y) it slid SLIP_M at [N].
        pull_n: the force out of the grip along the throw axis (ee +z) it slid at [N].
        couple_nm: the torque about the pads' axis (ee x) it turned SLIP_RAD at [N·m].
    """

    slide_n: float
    pull_n: float
    couple_nm: float

    @property
    def force_n(self) -> float:
        """The smaller of the two forces [N]."""
        return min(self.slide_n, self.pull_n)


def probe_grip(obj: ObjectParams, stroke_m: float) -> GripProbe:
    """Grasp `obj` at stroke L_s [m] in a scene without an arm or gravity and load it
    until it slips: along the pads' faces, out of the grip, and about the pads' axis
    (cached per object and stroke)."""
    return _probe(obj, round(float(stroke_m), 4))


def probe_load(obj: ObjectParams, stroke_m: float, load: str, axis: str) -> float:
    """One load of the probe on its own: the force [N] (`load` "force", at the centre of
    mass) or torque [N·m] ("torque") along ee axis `axis` ("x": the pads' normal, "y":
    along their faces, "z": out of the grip along the throw axis) at which `obj`, held
    at stroke L_s [m], first slips (not cached)."""
    if load not in ("force", "torque") or axis not in ("x", "y", "z"):
        raise ValueError(f"probe_load: load {load!r} (force, torque), axis {axis!r} (x, y, z)")
    return _ramp(obj, round(float(stroke_m), 4), load, "xyz".index(axis))


@functools.lru_cache(maxsize=256)
def _probe(obj: ObjectParams, stroke_m: float) -> GripProbe:
    return GripProbe(
        slide_n=_ramp(obj, stroke_m, "force", 1),
        pull_n=_ramp(obj, stroke_m, "force", 2),
        couple_nm=_ramp(obj, stroke_m, "torque", 0),
    )


@contextlib.contextmanager
def grasped_in_scene(
    obj: ObjectParams, stroke_m: float, elevation_rad: float, roll_rad: float = 0.0
) -> Iterator[tuple[Any, Any, Callable[[], tuple[np.ndarray, tuple[float, ...]]], Any]]:
    """A scene without an arm whose end-effector, held still with its throw axis at
    `elevation_rad` (and `roll_rad` about it), grips `obj` at stroke L_s [m]: yields
    (the scene, the item, a function giving the item's pose in the end-effector's frame
    now: position [m] and quaternion x y z w, the end-effector)."""
    from cell.catalogue import mesh_turn
    from cell.endeffector.pybullet_backend import PyBulletEndEffector
    from cell.sim.frames import ee_pose_for_item_centre
    from cell.sim.scene import CellScene

    with CellScene(robot=None) as sc:
        ee = PyBulletEndEffector(sc)
        cl = sc.client
        pos, orn = ee_pose_for_item_centre(
            (0.0, 0.0, 0.7), elevation_rad, 0.0, stroke_m, obj, roll_rad
        )
        sc.hold_ee(pos, orn, teleport=True)
        # a mesh gripped a quarter turn round: its body as the catalogue has it, the grip
        # turned about its vertical (`cell.catalogue.mesh_turn`)
        body_obj, yaw = mesh_turn(obj)
        item = sc.spawn_item(body_obj)
        ee.grasp(stroke_m, item, yaw_rad=yaw)

        def relative() -> tuple[np.ndarray, tuple[float, ...]]:
            e_p, e_o = cl.getBasePositionAndOrientation(sc.ee_body)
            inv = cl.invertTransform(e_p, e_o)
            p, q = cl.multiplyTransforms(*inv, *cl.getBasePositionAndOrientation(item.body))
            return np.asarray(p), q

        yield sc, item, relative, ee


def turn_rad(client: Any, q0: Sequence[float], q1: Sequence[float]) -> float:
    """The angle [rad] between two orientations (quaternions x y z w)."""
    return 2.0 * math.acos(min(1.0, abs(client.getDifferenceQuaternion(q0, q1)[3])))


def _ramp(obj: ObjectParams, stroke_m: float, load: str, axis_col: int) -> float:
    """The load (force [N] or torque [N·m] along ee axis `axis_col`) at which the item,
    held at `stroke_m`, first slips, under a linear ramp; PROBE_MAX_S × the ramp if it
    never does."""
    rate = FORCE_RAMP_N_S if load == "force" else COUPLE_RAMP_NM_S
    # the throw axis up, as when the item is carried upright
    with grasped_in_scene(obj, stroke_m, math.pi / 2) as (sc, item, relative, _):
        cl = sc.client
        cl.setGravity(0.0, 0.0, 0.0)
        sc.run_for(0.1)
        e_o = cl.getBasePositionAndOrientation(sc.ee_body)[1]
        axis = np.array(cl.getMatrixFromQuaternion(e_o)).reshape(3, 3)[:, axis_col]
        p0, q0 = relative()
        steps = int(PROBE_MAX_S / sc.dt_s)
        for k in range(1, steps + 1):
            value = rate * k * sc.dt_s
            if load == "force":
                centre = cl.getBasePositionAndOrientation(item.body)[0]
                cl.applyExternalForce(
                    item.body, -1, (value * axis).tolist(), centre, cl.WORLD_FRAME
                )
            else:
                cl.applyExternalTorque(item.body, -1, (value * axis).tolist(), cl.WORLD_FRAME)
            sc.step()
            p, q = relative()
            # a torque turns the item about the patch: its centre moves with the turn
            slid = load == "force" and float(np.linalg.norm(p - p0)) > SLIP_M
            if slid or turn_rad(cl, q0, q) > SLIP_RAD:
                return value
        return rate * PROBE_MAX_S
