"""What `cell throw` and `cell plan`, which ask the model alone, check of a throw against
the cell it models: the landing plane not under the floor (z = 0 in the world frame W,
where `cell run`'s bins stand), and an item the pads cannot hold said to be so (`cell run`
refuses it, `cell.arm.grip_limits`), its figures being the model's, not a throw the cell
can make; and an item lighter than the model is calibrated on said to be so (as a job's
thrown item is, `cell.jobbins.light_item_warnings`): the push's launch speed grows as the
mass falls, so that of a 2 g item is some 80 m/s, which no throw of the cell makes."""

from __future__ import annotations

import sys

from cell.errors import InvalidInput
from cell.model.objects import ObjectParams
from cell.params import ModelParams

__all__ = [
    "refuse_release_under_floor",
    "refuse_under_floor",
    "warn_if_light",
    "warn_if_not_held",
    "warn_if_not_thrown",
    "warn_if_stroke_not_held",
]


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


def refuse_release_under_floor(flag: str, z_m: float) -> None:
    """Refuse a release point (its z, `z_m`) under the floor: no arm of the cell reaches
    there, and the model would fly the item up through the floor.

    Raises:
        InvalidInput: `z_m` < 0, naming the flag and what is valid.
    """
    if z_m < 0.0:
        raise InvalidInput(
            f"{flag}: a release point z = {z_m:g} m is under the floor (z = 0 m in the world "
            "frame W, where the arm's base stands); give a height of 0 or more"
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
    elif obj.shape != "mesh":  # a mesh's sides need its rest pose (cell.sim.rest)
        warn_if_not_thrown(params, obj)


def warn_if_not_thrown(params: ModelParams, obj: ObjectParams) -> None:
    """A warning on standard error where the pads hold `obj` but `cell run` does not throw
    it (`cell.arm.grip_side.throw_sides`: held only carried slowly, or tipped out of the
    pads on a throw's swing), saying why."""
    from cell.arm.grip_side import holding_sides, throw_sides
    from cell.errors import CannotGrip

    try:
        throw_sides(holding_sides(params, obj), obj, params)
    except CannotGrip as exc:
        print(
            f"cell: warning: {exc}; `cell run` does not throw it, and the figures below are "
            "the model's, not a throw the cell can make",
            file=sys.stderr,
        )


def warn_if_stroke_not_held(params: ModelParams, obj: ObjectParams, stroke_m: float) -> None:
    """A warning on standard error where the pads hold `obj` across its first size only at
    strokes shorter than `stroke_m` [m] (`grip_stroke_at`): `cell run` plans its throws
    within that. Not for a mesh, whose sides need its rest pose (`cell.sim.rest`)."""
    from cell.arm.grip_limits import grip_stroke_at

    if obj.shape == "mesh":
        return
    s_max = grip_stroke_at(params, obj)
    if s_max is not None and stroke_m > s_max + 1e-9:
        print(
            f"cell: warning: a stroke of {stroke_m:.4f} m is longer than the pads hold "
            f"{obj.name or obj.shape} ({obj.mass * 1000:.0f} g) at, gripped across its "
            f"{obj.width * 1000:.0f} mm ({s_max:.4f} m: the band closes them less the longer "
            "the stroke); `cell run` plans no throw at a stroke the pads do not hold, and "
            "the figures below are the model's, not a throw the cell can make",
            file=sys.stderr,
        )


def warn_if_light(obj: ObjectParams) -> None:
    """A warning on standard error where `obj` is lighter than the lightest catalogue
    object, the lightest the throw model is calibrated on."""
    from cell.catalogue import catalogue

    name, lightest = min(catalogue().items(), key=lambda kv: kv[1].params.mass)
    if obj.mass < lightest.params.mass:
        print(
            f"cell: warning: {obj.name or obj.shape} ({obj.mass * 1000:g} g) is lighter than "
            f"the lightest object the throw model is calibrated on ({name}, "
            f"{lightest.params.mass * 1000:g} g): the figures below extrapolate its push, "
            "whose launch speed grows as the mass falls; thrown by `cell run`, such an item "
            "misses where it is aimed (25 mm cubes thrown 1.5 m missed by 0.24 m at 2 g)",
            file=sys.stderr,
        )


def modelled(params: ModelParams, obj: ObjectParams) -> tuple[ObjectParams, str]:
    """The object as the planner models it with `params` (`ModelParams.model_object`: the
    file's identified η_o of a catalogue object, else the mass rule's effective mass), and
    a line saying so where that differs from `obj` ("" where it does not). `cell throw`
    and `cell plan --params` predicted with the catalogue's mass where `cell run` plans
    with the file's: cube50 at a stroke of 0.07 m, 30° up from 0.6 m, with the scene's
    calibrated file, 0.765 m out against the planner's 1.333 m."""
    model = params.model_object(obj)
    if model == obj:
        return obj, ""
    why = (
        "the parameter file's identified η_o"
        if obj.name and obj.name in params.objects
        else "the parameter file's mass rule, an effective mass"
    )
    size = " x ".join(f"{s:.4f}" for s in model.size)
    return model, f"modelled as   {model.mass:.4f} kg, {size} m ({why}, as `cell run` plans it)"
