"""What a platform decides to do with an item: the loop passes it from decide to pick,
carry and release (`cell.loop.ItemLoop`); the platforms make it (`cell.arm`,
`cell.platforms`) without importing the loop."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Decision"]


@dataclass
class Decision:
    """What a platform will do with an item.

    Attributes:
        action: "throw" or "place".
        stroke_m: stroke the item is gripped and released at [m].
        plan: the throw plan (`cell.optimize.ThrowPlan`; None for a place).
        delta_stroke_m: learned ΔL_s included in `stroke_m` [m].
        model_obj: the item as the plan modelled it (for an observer).
        ee_params: the end-effector parameters the plan used (for an observer).
        moving: the latch opens while the platform moves; the release point is known
            once it has (`Platform.release` returns it).
        goal_xy: the point (x, y) [m, W] of the target's rim plane a throw is for (a
            point of the bin clear of what it holds); None: the bin's centre.
        state: the platform's own typed state for its later steps (the arm's:
            `cell.arm.state.ArmState`; None where a platform keeps none).
        gripped: the item as gripped (its size x the width across the pads: the arm may
            grip it across another side, `cell.arm.grip_side`), as the throw log records
            it; None: as the job gives it.
    """

    action: str
    stroke_m: float
    plan: Any = None
    delta_stroke_m: float = 0.0
    model_obj: Any = None
    ee_params: Any = None
    moving: bool = False
    goal_xy: tuple[float, float] | None = None
    state: Any = None
    gripped: Any = None
