"""The arm's own state of one item, from its decision to its release: what each step
leaves for the next (`Decision.state` of the arm, `cell.orchestrator.Orchestrator`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.arm.grip_side import GripSide
from cell.arm.planner import ThrowChoice
from cell.model.objects import ObjectParams

__all__ = ["ArmState"]


@dataclass
class ArmState:
    """What the arm's steps pass on for one item (configurations in [rad]).

    Attributes:
        target: the bin (`cell.jobs` bin spec) the item goes to.
        choice: the throw the planner chose (None: a place).
        q_release: the release configuration the carry goes to: the choice's, or the
            release on the move's (None: a place).
        moving: the release on the move chosen (`cell.robot.moving_release`), or None.
        q_lift: where the pick left the arm (`pick`).
        motion: the release on the move's motion from where the carry starts it (`carry`).
        q_above: a place: the configuration over its spot (`carry`).
        rise: a place: the way back up out of the bin, ending at q_above (`carry`).
        side: the side the pads grip the item across (`cell.arm.grip_side`); None: its
            first size.
    """

    target: Any
    choice: ThrowChoice | None = None
    q_release: np.ndarray | None = None
    moving: Any = None
    q_lift: np.ndarray | None = None
    motion: Any = None
    q_above: np.ndarray | None = None
    rise: list[np.ndarray] = field(default_factory=list)
    side: GripSide | None = None

    def gripped(self, obj: ObjectParams) -> ObjectParams:
        """The item `obj` as gripped: across the chosen side."""
        return obj if self.side is None else self.side.obj

    @property
    def grip_yaw_rad(self) -> float:
        """[rad] the grip's turn about the item's vertical from its x axis (0 or π/2)."""
        return 0.0 if self.side is None else self.side.yaw_rad
