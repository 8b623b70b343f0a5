"""The PyBullet cell with the effects of a diagnosis world acting physically on its flying
items (`cell.gap.world_scene` throws its campaigns in it): a steady air flow and a rotor's
downwash jet as the air the item moves through, drag as a force from the object's own C_d and
area times a factor, a constant side force, and the floor's contact (restitution, friction).
It is part of the plant: nothing above it talks to PyBullet."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams
from cell.sim.drag import speed
from cell.sim.scene import CellScene

__all__ = ["RHO", "STATION_XY", "EffectScene"]

RHO = 1.225  # [kg/m³] air density of this world
STATION_XY = (-8.0, -8.0)  # [m] the pick station, far from every flight


@functools.lru_cache(maxsize=256)
def _cd_area(obj: ObjectParams) -> tuple[float, float]:
    """An object's drag coefficient and mean projected area [m²] (`ObjectParams.cd`,
    `.area`, which compute it anew each call: once per item and physics step here)."""
    return obj.cd, obj.area


class EffectScene(CellScene):
    """The cell's scene (no arm, no bins) with the effects of one throw acting on its items.

    Set `throw_effects` before each throw: the air flow w [m/s, W] (or None), the drag
    factor, the downwash jet's source (release point, rpm) and the side acceleration.
    """

    def __init__(self) -> None:
        super().__init__(robot=None, bins=(), pick_station_xy=STATION_XY)
        self.wind = np.zeros(3)  # [m/s, W]
        self.drag_factor = 1.0
        self.jet: tuple[np.ndarray, float, dict[str, Any]] | None = None
        self.side_mps2 = np.zeros(3)

    def set_floor(self, restitution: float, friction: float, rolling_m: float = 0.0) -> None:
        """The floor's contact: restitution, lateral friction and rolling friction [m]."""
        self.client.changeDynamics(
            self.floor,
            -1,
            restitution=float(restitution),
            lateralFriction=float(friction),
            rollingFriction=float(rolling_m),
        )

    def launch_error(self, item: Any, yaw_rad: float, speed_share: float) -> None:
        """Turn a just-launched item's velocity by yaw_rad about the vertical and scale its
        speed by (1 + speed_share): a launch error applied as the item leaves the pads."""
        cl = self.client
        v, w = cl.getBaseVelocity(item.body)
        c, s = math.cos(yaw_rad), math.sin(yaw_rad)
        f = 1.0 + speed_share
        out = [f * (c * v[0] - s * v[1]), f * (s * v[0] + c * v[1]), f * v[2]]
        cl.resetBaseVelocity(item.body, out, w)

    def air(self, p: Sequence[float]) -> np.ndarray:
        """The air velocity at a point [m/s, W]: the steady flow plus the rotor jet."""
        w = self.wind.copy()
        if self.jet is not None:
            src, rpm, jet = self.jet
            depth = src[2] - p[2]
            if depth > 0.0:
                r = math.hypot(p[0] - src[0], p[1] - src[1])
                width = float(jet["radius_m"]) + 0.2 * depth
                centre = float(jet["w_mps"]) * rpm / 5000.0 / (1.0 + depth / float(jet["core_m"]))
                w[2] -= centre * math.exp(-((r / width) ** 2))
        return w

    def _air_z_drop(self, px: float, py: float, pz: float) -> float:
        """The rotor jet's downward air speed at a point [m/s] (what `air` takes off the
        steady flow's z), 0.0 above the rotor or without a jet: the same operations, in
        the same order, on plain floats."""
        src, rpm, jet = self.jet  # type: ignore[misc]
        depth = src[2] - pz
        if not depth > 0.0:
            return 0.0
        r = math.hypot(px - src[0], py - src[1])
        width = float(jet["radius_m"]) + 0.2 * depth
        centre = float(jet["w_mps"]) * rpm / 5000.0 / (1.0 + depth / float(jet["core_m"]))
        return centre * math.exp(-((r / width) ** 2))

    def _item_forces(self) -> None:
        """Before each physics step, on every item: the effect's force, the air drag taken
        on the velocity relative to the air (`air`) with this world's factor, the scene's
        own drag cancelled, plus the side force; then the scene's own drag (not on an item
        kept in a bin). The item's position and velocity are read once for both, on plain
        floats: each component the same products and sums, in the same order, as the
        vectors gave. The steady flow and the side force are read as floats once a step;
        |v| is taken once for both forces (the scene's drag -c |v| v is the cancelling
        term's negation, `cell.sim.drag.apply_drag`'s bits: (-c)·s = -(c·s) exactly)."""
        cl, kept = self.client, self._kept
        sx, sy, sz = self.side_mps2.tolist()
        ax, ay, az = self.wind.tolist()
        jet = self.jet is not None
        world = cl.WORLD_FRAME
        for it in self.items:
            body = it.body
            pos, _ = cl.getBasePositionAndOrientation(body)
            vel, _ = cl.getBaseVelocity(body)
            vx, vy, vz = vel
            wz = az - self._air_z_drop(*pos) if jet else az
            rx, ry, rz = vx - ax, vy - ay, vz - wz
            cd, area = _cd_area(it.obj)
            c_f = self.drag_factor * 0.5 * RHO * cd * area  # [kg/m]
            k_air = -c_f * speed(np.array((rx, ry, rz)))
            k_own = it.drag_c * speed(np.array(vel, float))
            m = it.obj.mass
            f = [
                k_air * rx + k_own * vx + m * sx,
                k_air * ry + k_own * vy + m * sy,
                k_air * rz + k_own * vz + m * sz,
            ]
            if f[0] != 0.0 or f[1] != 0.0 or f[2] != 0.0:
                cl.applyExternalForce(body, -1, f, pos, world)
            if body not in kept:
                k = -k_own  # apply_drag's -c |v|
                g = [k * vx, k * vy, k * vz]
                if g[0] != 0.0 or g[1] != 0.0 or g[2] != 0.0:
                    cl.applyExternalForce(body, -1, g, pos, world)
