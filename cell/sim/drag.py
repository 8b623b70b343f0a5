"""Air drag on items (MODEL.md eq. 3.10): F = -½ ρ C_d A |v| v.

PyBullet has no air; the scene applies this force at each item's centre of
mass on every step (an item at rest feels none).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.model.objects import ObjectParams
from cell.model.params import aero_factor_kg_per_m

__all__ = ["drag_coefficient_kg_per_m", "drag_force", "apply_drag"]


def drag_coefficient_kg_per_m(obj: ObjectParams) -> float:
    """c = ½ ρ C_d A [kg/m], so that the drag force is -c |v| v [N]."""
    return float(aero_factor_kg_per_m(obj.cd, obj.area))


def drag_force(c_kg_per_m: float, velocity: np.ndarray) -> np.ndarray:
    """The drag force -c |v| v [N, W] for a velocity [m/s, W]."""
    v = np.asarray(velocity, float)
    return -c_kg_per_m * float(np.linalg.norm(v)) * v


def apply_drag(client: Any, body: int, c_kg_per_m: float) -> np.ndarray:
    """Apply the drag force to a body's base at its centre of mass for the next step.

    Returns:
        The force applied [N, W], shape (3,).
    """
    pos, _ = client.getBasePositionAndOrientation(body)
    vel, _ = client.getBaseVelocity(body)
    f = drag_force(c_kg_per_m, np.asarray(vel))
    if f.any():
        client.applyExternalForce(body, -1, f.tolist(), pos, client.WORLD_FRAME)
    return f
