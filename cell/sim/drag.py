"""Air drag on items (MODEL.md eq. 3.10): F = -½ ρ C_d A |v| v.

PyBullet has no air; the scene applies this force at each item's centre of
mass on every step (an item at rest feels none).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams
from cell.model.params import aero_factor_kg_per_m

__all__ = ["drag_coefficient_kg_per_m", "drag_force", "apply_drag", "speed"]


def drag_coefficient_kg_per_m(obj: ObjectParams) -> float:
    """c = ½ ρ C_d A [kg/m], so that the drag force is -c |v| v [N]."""
    return float(aero_factor_kg_per_m(obj.cd, obj.area))


def speed(v: np.ndarray) -> float:
    """|v| of a 3-vector, shape (3,): the bits np.linalg.norm gives (the square root of
    v·v, the same dot product), at a third of its cost."""
    return math.sqrt(v.dot(v))


def drag_force(c_kg_per_m: float, velocity: np.ndarray) -> np.ndarray:
    """The drag force -c |v| v [N, W] for a velocity [m/s, W]."""
    v = np.asarray(velocity, float)
    return -c_kg_per_m * float(np.linalg.norm(v)) * v


def apply_drag(
    client: Any, body: int, c_kg_per_m: float, pos: Any = None, vel: Any = None
) -> list[float]:
    """Apply the drag force to a body's base at its centre of mass for the next step.

    Args:
        client: a pybullet BulletClient.
        body: the body.
        c_kg_per_m: its drag factor c [kg/m].
        pos, vel: its centre of mass [m, W] and velocity [m/s, W] now, if the caller has
            read them this step (else read here).

    Returns:
        The force applied [N, W], three floats: `drag_force`'s, each component the same
        product (-c |v|) · v_i.
    """
    if pos is None:
        pos, _ = client.getBasePositionAndOrientation(body)
    if vel is None:
        vel, _ = client.getBaseVelocity(body)
    vx, vy, vz = vel
    k = -c_kg_per_m * speed(np.array(vel, float))
    f = [k * vx, k * vy, k * vz]
    if f[0] != 0.0 or f[1] != 0.0 or f[2] != 0.0:
        client.applyExternalForce(body, -1, f, pos, client.WORLD_FRAME)
    return f
