"""One exception hierarchy for the whole cell.

Every error says what was wrong, where (file, row, field) and what would be
valid. Each also subclasses the matching builtin so callers may catch either.
"""

from __future__ import annotations

__all__ = [
    "plural",
    "CellError",
    "InvalidParameter",
    "InvalidInput",
    "LogFormatError",
    "NoLanding",
    "UnreachableTarget",
    "IKFailed",
    "TrajectoryError",
    "JobError",
    "HardwareError",
    "CellTimeoutError",
    "MissingDependency",
    "SimulationError",
    "NoReply",
    "CorruptReply",
    "ServoFault",
    "SafetyRefusal",
    "GraspLost",
    "CannotGrip",
]


def plural(n: int, word: str, words: str | None = None) -> str:
    """`n` and the word as a person writes them: "1 object", "3 objects", "0 objects"."""
    return f"{n} {word if n == 1 else (words or word + 's')}"


class CellError(Exception):
    """Base class of every error the cell raises on purpose."""


class InvalidParameter(CellError, ValueError):
    """A model or configuration parameter is outside what is physical or allowed."""


class InvalidInput(CellError, ValueError):
    """A user-supplied value (CLI flag, file field) is not valid."""


class LogFormatError(InvalidInput):
    """A throw log (docs/throw_log.md format) has a bad row, column or value.

    Attributes:
        path: the file.
        row: 1-based data row number (header is row 0), or None for the header.
        column: the offending column, or None.
    """

    def __init__(self, path: str, row: int | None, column: str | None, message: str) -> None:
        where = str(path)
        if row is not None:
            where += f", row {row}"
        if column is not None:
            where += f", column '{column}'"
        super().__init__(f"{where}: {message}")
        self.path = path
        self.row = row
        self.column = column


class NoLanding(CellError, ValueError):
    """A throw never crosses its landing plane while descending."""


class UnreachableTarget(CellError, ValueError):
    """No release state within bounds lands the object on the target."""


class IKFailed(CellError, RuntimeError):
    """Inverse kinematics found no configuration within tolerance."""


class TrajectoryError(CellError, RuntimeError):
    """A time parameterisation or jerk-limited move could not be computed."""


class JobError(InvalidInput):
    """A sort-job YAML file is not valid."""


class HardwareError(CellError, IOError):
    """The end-effector hardware did not answer or answered with an error."""


class CellTimeoutError(CellError, TimeoutError):
    """Something did not happen within its time limit."""


class SimulationError(CellError, RuntimeError):
    """The simulated cell could not do what was asked."""


class GraspLost(SimulationError):
    """The item is not (or no longer) in the grip: the pick failed or it fell while carried.

    Attributes:
        stage: "grasp" (the fingers did not close on it) or "carry" (it left the grip
            between the pick and the release).
    """

    def __init__(self, message: str, stage: str) -> None:
        super().__init__(message)
        self.stage = stage


class CannotGrip(InvalidInput):
    """An item the pads cannot hold (too wide, too thin, too heavy for the grip force)."""


class MissingDependency(CellError, ImportError):
    """An optional dependency is not installed; the message names what to install."""


class NoReply(HardwareError):
    """A servo did not answer (power, cable, baud rate or ID)."""


class CorruptReply(HardwareError):
    """A servo's reply failed its CRC or was cut short (cable, termination, noise)."""


class ServoFault(HardwareError):
    """A servo reports a hardware error (overload, overheating, voltage, ...).

    Attributes:
        servo_id: the servo's bus ID.
        bits: its Hardware Error Status register.
    """

    def __init__(self, message: str, servo_id: int = -1, bits: int = 0) -> None:
        super().__init__(message)
        self.servo_id = servo_id
        self.bits = bits


class SafetyRefusal(HardwareError):
    """The end-effector refused an action that would not be safe in its current state."""
