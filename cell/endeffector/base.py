"""One interface for the throwing end-effector, whatever drives it.

The end-effector (thesis §2.2, design 2.0) has two servos: M1 engages and
disengages the latch gear, M2 winds and unwinds the spool whose thread sets the
stroke L_s; an encoder on the spool measures L_s. Callers (the orchestrator,
the CLI) use only this interface; the PyBullet and Dynamixel back-ends sit
behind it.
"""

from __future__ import annotations

import abc
from dataclasses import dataclass

__all__ = ["EndEffector", "EndEffectorStatus"]


@dataclass(frozen=True)
class EndEffectorStatus:
    """What the end-effector reports.

    Attributes:
        stroke_m: measured stroke L_s [m].
        latch_engaged: True when the latch holds the band.
        holding: True when an object is gripped (as far as the back-end knows).
        detail: back-end specific text (servo temperatures, errors).
    """

    stroke_m: float
    latch_engaged: bool
    holding: bool
    detail: str = ""


class EndEffector(abc.ABC):
    """The throwing end-effector.

    Every method blocks until the action is done or raises a CellError subclass.
    """

    @abc.abstractmethod
    def grasp(self, stroke_m: float) -> None:
        """Close on the object: engage the latch and wind the spool to stroke L_s [m]."""

    @abc.abstractmethod
    def set_stroke(self, stroke_m: float) -> None:
        """Wind or unwind the spool to stroke L_s [m] with the latch engaged."""

    @abc.abstractmethod
    def place(self) -> None:
        """Release the object gently: unwind the spool slowly with the latch engaged."""

    @abc.abstractmethod
    def throw(self) -> None:
        """Release the stored energy at once: disengage the latch."""

    @abc.abstractmethod
    def stroke(self) -> float:
        """The measured stroke L_s [m]."""

    @abc.abstractmethod
    def status(self) -> EndEffectorStatus:
        """The end-effector's state."""

    def close(self) -> None:  # noqa: B027 - optional hook
        """Release resources (hardware: torque off)."""

    def __enter__(self) -> EndEffector:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
