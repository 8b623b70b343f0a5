"""What `cell throw` and `cell plan`, which ask the model alone, check of a throw against
the cell it models: the landing plane not under the floor (z = 0 in the world frame W,
where `cell run`'s bins stand), and an item the pads cannot hold said to be so (`cell run`
refuses it, `cell.arm.grip_limits`), its figures being the model's, not a throw the cell
can make."""

from __future__ import annotations

import sys

from cell.errors import InvalidInput
from cell.model.objects import ObjectParams
from cell.params import ModelParams

__all__ = ["refuse_under_floor", "warn_if_not_held"]


def refuse_under_floor(flag: str, z_m: float) -> None:
    """Refuse a landing plane under the floor.

    Raises:
        InvalidInput: `z_m` < 0, naming the flag and what is valid.
    """
    if z_m < 0.0:
        raise InvalidInput(
            f"{flag}: the landing plane z = {z_m:g} m is under the floor (z = 0 m in the "
            "world frame W); give 0 or more (a bin's rim height, or 0 for the floor)"
        )


def warn_if_not_held(params: ModelParams, obj: ObjectParams) -> None:
    """A warning on standard error where the pads cannot hold `obj` across its first size
    (x, the grip width) at any stroke, saying why."""
    from cell.arm.grip_limits import grip_refusal

    why = grip_refusal(params, obj)
    if why:
        name = obj.name or obj.shape
        print(
            f"cell: warning: {name} ({obj.mass * 1000:.0f} g) cannot be held: {why}; "
            "`cell run` refuses it, and the figures below are the model's, not a throw the "
            "cell can make",
            file=sys.stderr,
        )
