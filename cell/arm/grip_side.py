"""The side the pads grip an item across: the sides they can meet from its resting pose,
which of them hold (`cell.arm.grip_limits`), and the one the cell takes.

An item rests on the pick station on its base; the grip comes down over it and may turn
about the vertical before the pads close. A box (a cuboid whose horizontal sizes differ)
is met across its first size (its x, the catalogue's "across the band") or, the grip
turned a quarter turn, across its second: the item as gripped then has those two sizes
swapped (`turned`), its inertia with them. A cube, an upright cylinder and a sphere are as
wide every way the pads meet them: one side. A mesh is met across its first size or,
turned a quarter turn, its second (its width across the pads comes from its vertices where
the pads meet them, `cell.catalogue.pad_width_m`).

The sides kept (`holding_sides`): those the pads hold briskly, the first size first; else
those held only slowly. A place takes the first kept (a place's cycle does not depend on
the side); a throw, only of an item held briskly (`throw_sides`), is planned across the
first kept and then across each other with the first's cycle estimate to beat, and takes
another only where its estimate is the shorter (`GripSideChoice._throw_side`). Where no
side holds, `CannotGrip` says what each side held.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from cell.arm.base import ArmBase
from cell.arm.grip_limits import (
    BRISK_CARRY_SAFETY,
    grip_refusal,
    grip_strokes,
    release_grip_use,
)
from cell.errors import CannotGrip, IKFailed, UnreachableTarget
from cell.model.objects import ObjectParams
from cell.params import ModelParams
from cell.robot.grip_hold import TILT_SLOWS_OVER

MESH_SAME_WIDTH_M = 1e-3  # [m] a mesh's two widths within this are one side

__all__ = [
    "GripSide",
    "GripSideChoice",
    "grip_sides",
    "holding_sides",
    "level_tip_use",
    "mesh_side_refusal",
    "throw_sides",
]


@dataclass(frozen=True)
class GripSide:
    """One side the pads grip an item across.

    Attributes:
        yaw_rad: [rad] the grip's turn about the item's vertical axis from its x axis:
            0 (across size x) or π/2 (across size y).
        obj: the item as gripped: its size x the width across the pads.
        stroke_max_m: [m] the longest stroke the pads hold it at (`grip_stroke_at`).
        brisk: the pads hold BRISK_CARRY_SAFETY x its weight there (else only within the
            carry's bound: it is carried as slowly as the grip asks).
    """

    yaw_rad: float
    obj: ObjectParams
    stroke_max_m: float
    brisk: bool = True

    @property
    def width_m(self) -> float:
        """[m] the item's width across the pads."""
        return self.obj.width


def grip_sides(obj: ObjectParams) -> list[tuple[float, ObjectParams]]:
    """The sides the pads can meet `obj` across from its resting pose: (the grip's yaw
    [rad] from the item's x axis, the item as gripped), the first size first. A box's
    two horizontal sizes; a mesh's two horizontal widths, each where the pads meet it
    (`cell.catalogue.pad_width_m`: the probe's strip across the grip, turned a quarter
    turn for the second, `cell.catalogue.mesh_turn`): rock_000 is 16 mm across its first
    (narrower than the band closes on) and 64 mm across its second."""
    if obj.shape == "cuboid" and not math.isclose(obj.size[0], obj.size[1], abs_tol=1e-9):
        return [(0.0, obj), (math.pi / 2, obj.turned())]
    if obj.shape == "mesh":
        from cell.catalogue import pad_width_m

        other = obj.turned()
        # a mesh round about its vertical (the egg: 42.9 and 43.0 mm, its facets) is as
        # wide both ways, as an upright cylinder: one side
        if not math.isclose(pad_width_m(obj), pad_width_m(other), abs_tol=MESH_SAME_WIDTH_M):
            return [(0.0, obj), (math.pi / 2, other)]
    return [(0.0, obj)]


def mesh_side_refusal(obj: ObjectParams, side: ObjectParams) -> str:
    """Why a mesh's second side (`side`, `obj` gripped a quarter turn round) is not
    offered, "" where it is. The throw model, the grip probe and the kinematic pick have
    a mesh seated in the grip in its catalogue frame; the physical pick holds it as it
    lies. The two agree only where it rests as the catalogue frame has it: its surface,
    tilted as it rests (`cell.sim.rest.rest_shift`), moves no more than the pads' half
    width, the strip across which they meet it (its width across the pads,
    `cell.catalogue.pad_width_m`, is that strip's). rock_000 rests level (0.0 mm):
    offered; shard_661, standing on its 40 mm edge in its catalogue frame, tips 22° over
    (13.2 mm, over the pads' 12 mm): not offered. A mesh's first side is offered as
    before (main's rule; the duck and the teddy rest tipped too)."""
    from cell.sim.mechanism import DEFAULT_GEOMETRY
    from cell.sim.rest import rest_shift

    if obj.shape != "mesh":
        return ""
    rest = rest_shift(obj)
    half = DEFAULT_GEOMETRY.pad_half_width_m
    if rest.shift_m <= half:
        return ""
    return (
        f"{side.width * 1000:.0f} mm across its other side, not offered: it rests on the "
        f"station tipped {math.degrees(rest.tilt_rad):.0f} deg from its catalogue frame "
        f"(its surface moves up to {rest.shift_m * 1000:.0f} mm, more than the pads' half "
        f"width {half * 1000:.0f} mm), where the throw model and the grip probe have it "
        "seated as the catalogue frame has it"
    )


def holding_sides(params: ModelParams, obj: ObjectParams) -> list[GripSide]:
    """The sides of `obj` the pads hold (`grip_sides`, in that order): those they hold
    briskly (BRISK_CARRY_SAFETY x its weight), where there are any; else those they hold
    only within the carry's bound (carried slowly). cuboid_a is held across 30 mm only
    carried slowly, across 50 mm briskly: it is offered 50 mm alone.

    The merge reverted at cf2d90b (docs/HISTORY.md) offered both sides so too and planned
    each in full; now the second's releases that cannot beat the first's estimate are not
    timed (`GripSideChoice._throw_side`), and a tie keeps the first size.

    Raises:
        CannotGrip: no side holds; the message names each side tried (its width in mm)
            and why it does not hold.
    """
    found, tried = [], []
    for yaw, side in grip_sides(obj):
        unseated = mesh_side_refusal(obj, side) if yaw else ""
        if unseated:
            tried.append(unseated)
            continue
        s_max, brisk = grip_strokes(params, side)
        if s_max is not None:
            found.append(GripSide(yaw, side, s_max, brisk))
        else:
            tried.append(grip_refusal(params, side))
    if any(s.brisk for s in found):
        found = [s for s in found if s.brisk]
    if not found:
        name = obj.name or obj.shape
        what = "; ".join(tried)
        where = " across either side" if len(tried) > 1 else ""
        raise CannotGrip(
            f"{name} ({obj.mass * 1000:.0f} g) cannot be held{where}: {what}; sort it by hand"
        )
    return found


def throw_sides(
    sides: list[GripSide], obj: ObjectParams, params: ModelParams | None = None
) -> list[GripSide]:
    """Of the `sides` that hold (`holding_sides`), those a throw may grip `obj` across:
    the ones held briskly. An item the pads hold only carried slowly is placed, not
    thrown: on tune layout 1 (UR5) the first of four 220 g tetrapacks thrown 1.7 m left
    the pads on its carry, whose route asked 1.23 of the grip held still (more than the
    pads hold at any speed), with the merge of this change and again with it narrowed.

    With `params`, of those, the ones a throw's swing keeps in the pads as well
    (`level_tip_use`): a throw's twist-free swing from hanging to its release passes
    the throw axis level, the item's weight on a pad, and a tall narrow light item tips
    out there (a 45 g cylinder 30 x 200 mm turned 30 deg in the pads as its swing went
    past level and landed 0.27 m off; 40 g 30 x 250 mm left them: docs/HISTORY.md).

    Raises:
        CannotGrip: none is held briskly, or (with `params`) every side held briskly
            tips out level; the message says to place it instead.
    """
    brisk = [s for s in sides if s.brisk]
    name = obj.name or obj.shape
    if not brisk:
        widths = " and ".join(f"{s.width_m * 1000:.0f} mm" for s in sides)
        raise CannotGrip(
            f"{name} ({obj.mass * 1000:.0f} g) is held only carried slowly ({widths} across "
            f"the pads: they hold under {BRISK_CARRY_SAFETY} x its weight at every stroke), "
            "too heavy for a throw's carry: place it in a bin within place reach, or sort "
            "it by hand"
        )
    if params is None:
        return brisk
    kept = [s for s in brisk if level_tip_use(params, s.obj) <= TILT_SLOWS_OVER]
    if not kept:
        side = brisk[0]
        use = level_tip_use(params, side.obj)
        raise CannotGrip(
            f"{name} ({obj.mass * 1000:.0f} g, {obj.size[2] * 1000:.0f} mm tall, "
            f"{side.width_m * 1000:.0f} mm across the pads) tips out of them on a throw's "
            f"swing: held with the throw axis level, its weight on a pad, it asks {use:.2f} "
            f"of what the pads hold even at the shortest stroke (over {TILT_SLOWS_OVER:g}: "
            "its centre of mass too high above their short patch for so light a grip); "
            "place it in a bin within place reach, or sort it by hand"
        )
    return kept


def level_tip_use(params: ModelParams, obj: ObjectParams) -> float:
    """What holding `obj` (as gripped) still with the throw axis level and its weight on
    a pad asks of the pads at the shortest stroke, where they hold hardest
    (`release_grip_use` at elevation 0, the tilt about y included): a throw's twist-free
    swing passes there. Over TILT_SLOWS_OVER (what the pads hold at all), no carry keeps
    it in the pads there. Measured, 30 mm cylinders thrown 1.6 m alone (panda): 30 g
    250 mm (1.32), 45 g 150 mm (1.18), 45 g 175 mm (1.37), 35 g 250 mm (1.54) stayed
    within 5-8 deg and landed; 45 g 200 mm (1.57) turned 30 deg and missed by 0.27 m,
    40 g 250 mm (1.76) left the pads. The scene's pads resist the tilt with 1.27-1.33
    of the model's T_y for these (`cell.sim.grip_probe`), 1.03-1.05 for the bottle: the
    bound is the model's own, taken without a margin chosen on these items."""
    return float(release_grip_use(params, obj, params.ee.stroke_min, [0.0])[0])


class GripSideChoice(ArmBase):
    """The side the arm grips an item across (a part of the arm;
    `cell.orchestrator.Orchestrator`)."""

    def _throw_side(self, sides: list[GripSide], target: Any, index: int) -> tuple[GripSide, Any]:
        """(the side, its `ThrowChoice`) of those that hold whose throw to `target` the
        planner finds with the shortest cycle estimate (`Planner._plan`'s cost: first
        whether it asks more of the grip than it holds, then the estimate); the first
        side found where an estimate is missing. A side the pads hold briskly only at the
        shortest stroke leaves no throw to plan (`grip_limits.grip_bounds`' CannotGrip):
        it is passed over for the others. UnreachableTarget, IKFailed or CannotGrip (the
        first side's) where no side's throw is found.

        A side wider than the widest grip the throw model is calibrated on
        (`cell.jobbins.calibrated_width_m`, 90 mm) is planned only where no narrower side
        that holds briskly gives a throw: the pads still squeeze so wide an item as it
        leaves them, which the model does not have, and a light one lands short (a 30 g
        box gripped across 120 mm, thrown 1.1 m, landed 0.49 m short; across its 30 mm
        side the scene's reach is the model's to 1.6 %: docs/HISTORY.md, `wide63`). No
        catalogue object nor `cell.jobgen` item is wider than 90 mm across any side:
        their choice is as before."""
        from cell.catalogue import pad_width_m
        from cell.jobbins import calibrated_width_m

        widest = calibrated_width_m() + 1e-9
        within = [s for s in sides if pad_width_m(s.obj) <= widest]
        if within and len(within) < len(sides):
            try:
                return self._best_side(within, target, index)
            except (UnreachableTarget, IKFailed, CannotGrip):
                sides = [s for s in sides if pad_width_m(s.obj) > widest]  # the wide ones
        return self._best_side(sides, target, index)

    def _best_side(self, sides: list[GripSide], target: Any, index: int) -> tuple[GripSide, Any]:
        """`_throw_side` of `sides`, all planned: the shortest cycle estimate."""
        best: tuple[GripSide, Any] | None = None
        err: Exception | None = None
        for side in sides:
            beat = None  # the first side's estimate: a later side's release that cannot
            if best is not None and best[1].cost is not None and not best[1].cost[0]:
                beat = best[1].cost[1]  # beat it is not timed (`Planner._plan`)
                if self._budget_spent():
                    break  # a throw that holds in hand, the budget spent (`release_budget`)
            try:
                choice = self._plan(side.obj, target, index, side.stroke_max_m, beat)
            except (UnreachableTarget, IKFailed, CannotGrip) as exc:
                err = err or exc
                continue
            if best is None:
                best = (side, choice)
                continue
            if best[1].cost is not None and choice.cost is not None and choice.cost < best[1].cost:
                best = (side, choice)
        if best is None:
            assert err is not None
            raise err
        return best
