"""The item loop's seams (`cell.loop.ItemLoop`): the plant it observes, the platform it
drives, and what a platform that places items offers as well. The loop knows nothing of
PyBullet: `cell.sim.CellScene` and `cell.sim.kinematic.KinematicPlant` are plants; the arm
(`cell.orchestrator`), the drone and moving base (`cell.platforms.runner`) and a campaign's
release poses (`cell.workflows.campaign`) are platforms. `cell.loop` re-exports these.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from cell.decision import Decision
from cell.model.objects import ObjectParams

__all__ = ["Places", "Plant", "Platform"]


class Plant(Protocol):
    """What the loop needs of the cell it runs in (`cell.sim.CellScene` is one)."""

    @property
    def t(self) -> float:
        """The plant's clock [s]."""
        ...

    dt_s: float

    def set_timestep(self, dt_s: float) -> None: ...
    def step(self, n: int = 1) -> None: ...
    def item_position(self, item: Any) -> np.ndarray:
        """The item's centre of mass now [m, W]."""
        ...

    def watch_until_rest(self, item: Any, *, timeout_s: float = 6.0) -> Any:
        """Observe the released item until it rests: its `Outcome`."""
        ...

    def outcome_if_settled(self, item: Any, *, timeout_s: float = 6.0) -> Any | None:
        """The released item's `Outcome` once it rests, else None (non-blocking)."""
        ...

    def tidy(self, item: Any) -> None:
        """Keep an item at rest in a bin there; take any other away."""
        ...

    def remove_item(self, item: Any) -> None:
        """Take an item away."""
        ...

    def tracker(self, item: Any) -> Any:
        """The released item's track so far (`samples`: t, x, y, z)."""
        ...

    def watch_until_crossing(
        self, item: Any, land_z: float, *, timeout_s: float = 4.0
    ) -> tuple[float, float, float]:
        """Observe the released item until it crosses z = land_z going down: (x, y, t)."""
        ...


class Platform(Protocol):
    """A platform carries the end-effector: the arm, a drone, a moving base, or the fixed
    release poses of a campaign. Each step may raise a CellError: the item fails with
    its reason (`failure_of`) and the run goes on; a HardwareError stops the run."""

    name: str  # "arm", "drone" or "mobile": the throw log's `platform`
    overlaps: bool  # may start the next item while a thrown one flies
    rotor_rpm: float  # the drone's rotor speed in the throw log (0 for the others)

    def present(self, index: int, obj: ObjectParams) -> Any:
        """Have the plant present the item for the grasp; the plant's item."""
        ...

    def decide(self, index: int, obj: ObjectParams, target: Any) -> Decision:
        """Place or throw, and the plan."""
        ...

    def pick(self, decision: Decision, obj: ObjectParams, item: Any) -> None:
        """Grip the item (the end-effector holds it at `decision.stroke_m`)."""
        ...

    def carry(self, decision: Decision, obj: ObjectParams, item: Any) -> None:
        """Take the end-effector to the release pose, the item still held (GraspLost)."""
        ...

    def release(self, decision: Decision) -> np.ndarray | None:
        """Open the latch: slowly for a place, at once for a throw. A release on the move
        returns the item's centre at the latch [m, W]; None: where it was held."""
        ...

    def finish(self, decision: Decision | None) -> None:
        """The item is done with (scored, or failed): let go of anything of it."""
        ...


@runtime_checkable
class Places(Protocol):
    """A platform that places items as well as throwing them (the arm): after the latch
    has let a placed item down, it leaves the bin."""

    def after_place(self, decision: Decision) -> None:
        """After a placed item is let go: leave the bin."""
        ...
