"""The drone platform in PyBullet: the end-effector under a hovering quadrotor.

The quadrotor is example-robot-data's `iris` (four 0.128 m rotors at
(±0.13, ±0.21) m, rotor plane 0.023 m above its base frame), loaded with a
fixed base: it hovers kinematically at `hover_height_m` (the height of its
base frame [m, W]). The end-effector hangs beneath it: the gripped item's
centre of mass is released `release_depth_m` below the drone's base frame,
on its vertical axis.

Its rotors push air down (cell.platforms.downwash). PyBullet has no air, so
the downwash acts as a force field on the free items in the column: the
scene applies still-air drag −c |v| v to every item (cell.sim.drag), and the
drone adds the difference to the drag on the air-relative velocity,

    F = −c |v − w| (v − w) + c |v| v,     c = ½ ρ C_d A  [kg/m],

so an item feels exactly the model's drag −c |v − w| (v − w). Items held by
the end-effector feel none (the model's push phase has no downwash either).

`DroneScene` is a `CellScene` without an arm whose every step applies the
downwash: it is what a sort job with `platform: drone` runs in.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidParameter, MissingDependency
from cell.model.objects import ObjectParams
from cell.platforms.downwash import DownwashLaw, air_velocity
from cell.sim.frames import ee_pose_for_item_centre
from cell.sim.mechanism import DEFAULT_GEOMETRY, EEGeometry
from cell.sim.scene import CellScene

__all__ = [
    "DEFAULT_RELEASE_DEPTH_M",
    "ROTOR_PLANE_ABOVE_BASE_M",
    "DronePlatform",
    "DroneScene",
    "iris_urdf",
    "scene_exit_distance_m",
]

ROTOR_PLANE_ABOVE_BASE_M = 0.023  # [m] iris rotor joints sit this far above its base frame
DEFAULT_RELEASE_DEPTH_M = 0.25  # [m] item centre below the drone's base frame at release


def iris_urdf() -> Path:
    """The iris quadrotor's URDF from example-robot-data.

    Raises:
        MissingDependency: example-robot-data (or its iris) is not installed.
    """
    from cell.robot.paths import example_robot_data_dir

    p = example_robot_data_dir() / "iris_description" / "robots" / "iris_simple.urdf"
    if not p.is_file():
        raise MissingDependency(
            f"no iris quadrotor at {p}: the drone platform needs example-robot-data ≥ 4"
        )
    return p


def scene_exit_distance_m(
    stroke_m: float | np.ndarray, geometry: EEGeometry = DEFAULT_GEOMETRY
) -> np.ndarray:
    """Where the PyBullet mechanism lets go of the item, along the throw axis [m].

    The carriage runs from the stroke L_s to its end stop and the item slides
    off the pads' length beyond it: (end_stop − L_s) + pad length from the
    release point. Use it as `predict_drone_landing(exit_distance_m=...)` for
    throws in the scene.
    """
    return geometry.end_stop_m - np.asarray(stroke_m, float) + geometry.pad_length_m


class DronePlatform:
    """A quadrotor hovering kinematically, with its downwash as a force field.

    Args:
        client: a pybullet BulletClient (the scene's).
        hover_height_m: height of the drone's base frame [m, W].
        rotor_rpm: rotor speed [rpm].
        law: the downwash law.
        xy: horizontal position of the drone [m, W].
        yaw_rad: heading of the drone [rad] (the merged wake is axisymmetric).
        release_depth_m: item centre below the base frame at release [m].

    Raises:
        InvalidParameter: a height, speed or depth out of range.
        MissingDependency: no iris description.
    """

    def __init__(
        self,
        client: Any,
        hover_height_m: float,
        rotor_rpm: float,
        law: DownwashLaw,
        *,
        xy: tuple[float, float] = (0.0, 0.0),
        yaw_rad: float = 0.0,
        release_depth_m: float = DEFAULT_RELEASE_DEPTH_M,
    ) -> None:
        if not (math.isfinite(hover_height_m) and 0.5 <= hover_height_m <= 10.0):
            raise InvalidParameter(f"hover_height_m={hover_height_m}: must be in [0.5, 10] m")
        if not (math.isfinite(rotor_rpm) and 0.0 <= rotor_rpm <= 30000.0):
            raise InvalidParameter(f"rotor_rpm={rotor_rpm}: must be in [0, 30000] rpm")
        if not (0.1 <= release_depth_m < hover_height_m - 0.1):
            raise InvalidParameter(
                f"release_depth_m={release_depth_m}: must be ≥ 0.1 m and leave the item "
                f"above the floor (hover height {hover_height_m} m)"
            )
        self.client = client
        self.hover_height_m = float(hover_height_m)
        self.rotor_rpm = float(rotor_rpm)
        self.law = law
        self.xy = (float(xy[0]), float(xy[1]))
        self.release_depth_m = float(release_depth_m)
        orn = client.getQuaternionFromEuler([0.0, 0.0, yaw_rad])
        self.body = int(
            client.loadURDF(
                str(iris_urdf()),
                [self.xy[0], self.xy[1], self.hover_height_m],
                orn,
                useFixedBase=True,
            )
        )
        for j in range(-1, client.getNumJoints(self.body)):
            client.setCollisionFilterGroupMask(self.body, j, 0, 0)  # kinematic, collision-free

    @property
    def rotor_centre(self) -> np.ndarray:
        """Centre of the rotor plane [m, W], shape (3,)."""
        return np.array([*self.xy, self.hover_height_m + ROTOR_PLANE_ABOVE_BASE_M])

    @property
    def release_point(self) -> np.ndarray:
        """Where the gripped item's centre of mass is released [m, W], shape (3,)."""
        return np.array([*self.xy, self.hover_height_m - self.release_depth_m])

    def air_velocity(self, points: np.ndarray) -> np.ndarray:
        """Downwash air velocity at points [m/s, W], shape (n, 3)."""
        return air_velocity(points, self.rotor_centre, self.rotor_rpm, self.law)

    def downwash_force(
        self, position: Sequence[float], velocity: Sequence[float], drag_c: float
    ) -> np.ndarray:
        """Force [N, W] the downwash adds to still-air drag on a body, shape (3,).

        Args:
            position: the body's centre of mass [m, W].
            velocity: its velocity [m/s, W].
            drag_c: ½ ρ C_d A [kg/m].
        """
        v = np.asarray(velocity, float)
        w = self.air_velocity(np.asarray(position, float)[None, :])[0]
        rel = v - w
        return -drag_c * float(np.linalg.norm(rel)) * rel + drag_c * float(np.linalg.norm(v)) * v

    def apply_downwash(self, client: Any, body: int, drag_c: float) -> np.ndarray:
        """Apply the downwash force to a body for the next physics step.

        Call it once per step for every free item, on top of the scene's
        still-air drag (which `CellScene.step` applies).

        Returns:
            The force applied [N, W], shape (3,).
        """
        pos, _ = client.getBasePositionAndOrientation(body)
        vel, _ = client.getBaseVelocity(body)
        f = self.downwash_force(pos, vel, drag_c)
        if f.any():
            client.applyExternalForce(body, -1, f.tolist(), pos, client.WORLD_FRAME)
        return f


class DroneScene(CellScene):
    """The cell without an arm, the end-effector held under a hovering drone.

    Args:
        hover_height_m: height of the drone's base frame [m, W].
        rotor_rpm: rotor speed [rpm].
        law: the downwash law (no downwash when its constant is 0).
        drone_xy: horizontal position of the drone [m, W].
        release_depth_m: item centre below the drone's base frame at release [m].
        **scene: CellScene's keywords (bins, pick_station_xy, dt_s …); robot is None.
    """

    def __init__(
        self,
        hover_height_m: float,
        rotor_rpm: float,
        law: DownwashLaw,
        *,
        drone_xy: tuple[float, float] = (0.0, 0.0),
        release_depth_m: float = DEFAULT_RELEASE_DEPTH_M,
        **scene: Any,
    ) -> None:
        scene.pop("robot", None)
        super().__init__(robot=None, **scene)
        self.drone = DronePlatform(
            self.client,
            hover_height_m,
            rotor_rpm,
            law,
            xy=drone_xy,
            release_depth_m=release_depth_m,
        )

    def hold_at_release(
        self,
        elevation: float,
        azimuth: float,
        stroke_m: float,
        obj: ObjectParams,
        roll: float = 0.0,
    ) -> None:
        """Teleport the end-effector to its release pose under the drone: the pose of E
        that puts the gripped item's centre of mass at the drone's `release_point`, the
        throw axis along u(e, a) (`cell.sim.frames.ee_pose_for_item_centre`)."""
        pos, orn = ee_pose_for_item_centre(
            self.drone.release_point, elevation, azimuth, stroke_m, obj, roll
        )
        self.hold_ee(pos, orn, teleport=True)

    def step(self, n: int = 1) -> None:
        """Advance n steps; each applies the downwash to every free item first."""
        for _ in range(n):
            if self.drone.rotor_rpm > 0 and self.items:
                held = self.held_bodies()
                for it in self.items:
                    if it.body not in held:
                        self.drone.apply_downwash(self.client, it.body, it.drag_c)
            super().step(1)
