"""Open bins in the cell scene: a floor plate and four walls of any size and rim height.

A bin is described in the world frame W (z up) by its centre on the floor,
its inner footprint and its rim height. `which_bin` decides which bin, if
any, a point (an item's rest position) lies in.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import InvalidParameter
from cell.jobschema import BIN_WALL_M

__all__ = ["BinSpec", "build_bin", "which_bin"]


@dataclass(frozen=True)
class BinSpec:
    """One open bin.

    Attributes:
        id: the bin's text id.
        center_xy: centre of the bin's footprint on the floor [m, W].
        size_xy: inner footprint (x, y) [m].
        rim_height: height of the rim above the floor [m].
        wall: wall and floor-plate thickness [m].
        yaw: rotation of the bin about z [rad].
    """

    id: str
    center_xy: tuple[float, float]
    size_xy: tuple[float, float]
    rim_height: float
    wall: float = BIN_WALL_M
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if len(self.center_xy) != 2 or len(self.size_xy) != 2:
            raise InvalidParameter(f"bin {self.id}: center_xy and size_xy need two numbers [m]")
        if not all(s > 0 for s in self.size_xy):
            raise InvalidParameter(f"bin {self.id}: size_xy {self.size_xy} m must be > 0")
        if not self.rim_height > self.wall:
            raise InvalidParameter(
                f"bin {self.id}: rim_height {self.rim_height} m must exceed the wall "
                f"thickness {self.wall} m"
            )
        if not self.wall > 0:
            raise InvalidParameter(f"bin {self.id}: wall {self.wall} m must be > 0")

    def to_local(self, point: Sequence[float]) -> np.ndarray:
        """(x, y) of a world point in the bin's frame (origin at its centre) [m]."""
        d = np.asarray(point[:2], float) - np.asarray(self.center_xy, float)
        c, s = np.cos(self.yaw), np.sin(self.yaw)
        return np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])

    def contains(self, point: Sequence[float], *, margin: float = 0.0) -> bool:
        """True if the point lies inside the bin's walls and below its rim (+ margin) [m]."""
        x, y = self.to_local(point)
        hx, hy = self.size_xy[0] / 2 + margin, self.size_xy[1] / 2 + margin
        inside = abs(x) <= hx and abs(y) <= hy
        if len(point) > 2:
            inside = inside and float(point[2]) <= self.rim_height + margin
        return bool(inside)


def which_bin(
    point: Sequence[float], bins: Sequence[BinSpec], *, above_rim_m: float = 0.0
) -> str | None:
    """The id of the bin whose inside holds the point (x, y[, z]) [m, W], or None.

    A point with a z coordinate must also lie below the bin's rim + `above_rim_m`,
    so an item resting on top of a wall or on the rim is in no bin, while a
    tall item standing inside (its centre above the rim) is; pass about half
    the item's largest extent.
    """
    for b in bins:
        x, y = b.to_local(point)
        if abs(x) > b.size_xy[0] / 2 or abs(y) > b.size_xy[1] / 2:
            continue
        if len(point) > 2 and float(point[2]) > b.rim_height + above_rim_m:
            continue
        return b.id
    return None


def build_bin(client: Any, spec: BinSpec, rgba: Sequence[float] = (0.3, 0.45, 0.7, 1.0)) -> int:
    """Create the bin as one static PyBullet body; returns its body id.

    Args:
        client: a pybullet BulletClient.
        spec: the bin.
        rgba: colour.
    """
    hx, hy = spec.size_xy[0] / 2, spec.size_xy[1] / 2
    w, h = spec.wall, spec.rim_height
    # floor plate, then walls at -x, +x, -y, +y (local frame of the bin)
    halves = [
        (hx + w, hy + w, w / 2),
        (w / 2, hy + w, h / 2),
        (w / 2, hy + w, h / 2),
        (hx, w / 2, h / 2),
        (hx, w / 2, h / 2),
    ]
    centres = [
        (0.0, 0.0, w / 2),
        (-hx - w / 2, 0.0, h / 2),
        (hx + w / 2, 0.0, h / 2),
        (0.0, -hy - w / 2, h / 2),
        (0.0, hy + w / 2, h / 2),
    ]
    n = len(halves)
    col = client.createCollisionShapeArray(
        shapeTypes=[client.GEOM_BOX] * n,
        halfExtents=halves,
        collisionFramePositions=centres,
    )
    vis = client.createVisualShapeArray(
        shapeTypes=[client.GEOM_BOX] * n,
        halfExtents=halves,
        visualFramePositions=centres,
        rgbaColors=[list(rgba)] * n,
    )
    orn = client.getQuaternionFromEuler([0.0, 0.0, spec.yaw])
    body = client.createMultiBody(
        baseMass=0.0,
        baseCollisionShapeIndex=col,
        baseVisualShapeIndex=vis,
        basePosition=[spec.center_xy[0], spec.center_xy[1], 0.0],
        baseOrientation=orn,
    )
    client.changeDynamics(body, -1, lateralFriction=0.6, restitution=0.1)
    return int(body)
