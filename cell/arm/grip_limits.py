"""What the grip holds: the pads' force and couple on an item (`carry_hold`), the longest
stroke they hold it at, what a release or a swing asks of them, and the bounds a throw is
planned in for it.
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import distinct_waypoints
from cell.arm.tuning import TUNING, ArmTuning
from cell.decision import Decision
from cell.errors import (
    CannotGrip,
    GraspLost,
)
from cell.model.objects import ObjectParams
from cell.params import ModelParams

log = logging.getLogger(__name__)


# The pads' couple against a twist about their axis, in units of F r̄ (F their friction
# force, r̄ the contact patch's mean radius). The pads' torsional friction alone gives 1
# (cell.sim.mechanism); measured in the scene, with gravity turning tall boxes in the
# grip (tests/test_carry.py), the pads held up to 4.6 F r̄ and let go at 6.9 F r̄: the
# engine's contact points add their own couple. 4 is taken.
PAD_COUPLE_FACTOR = 4.0


# A mesh the probe holds with at least this fraction of the grip model's force is carried
# to a throw at the probed couple (carry_hold): the egg, a rock (1.0) and the teddy (0.88),
# not the duck (0.69), which turned 4° in the pads so carried
MESH_PROBED_MIN_RATIO = 0.85


# A throw's stroke is kept where the pads hold this multiple of the item's weight (the
# 1.6 the grip model used as its carrying margin), where there is such a stroke: the cell's
# throws of the items it sorted before keep their strokes and carries. Not a refusal: an
# item the pads hold only below it is carried within CARRY_MARGIN (`grip_stroke_at`).
BRISK_CARRY_SAFETY = 1.6


MIN_THROW_STROKE_RANGE_M = 1e-3  # [m] a throw needs at least this much stroke to choose from


def as_gripped(obj: ObjectParams) -> ObjectParams:
    """The item as the pads see it: a mesh is as wide as it is where the pads meet it."""
    from dataclasses import replace as dc_replace

    from cell.catalogue import pad_width_m

    width = pad_width_m(obj)
    if width < obj.width:
        return dc_replace(obj, size=(width, *obj.size[1:]))
    return obj


def grip_force_n(params: ModelParams, obj: ObjectParams, stroke_m: float) -> float:
    """The friction force [N] the grip model's pads hold `obj` with at stroke L_s [m],
    F = 2 μ f_g: the band's closing force at the width the pads meet (`as_gripped`)."""
    from cell.model.grip import grip_friction, holding_mass_kg
    from cell.model.params import G
    from cell.sim.mechanism import DEFAULT_GEOMETRY as GEO

    mu = grip_friction(obj, GEO.pad_length_m)
    return float(holding_mass_kg(params.ee, stroke_m, as_gripped(obj).width, mu) * G)


def carry_hold(
    params: ModelParams,
    obj: ObjectParams,
    stroke_m: float,
    *,
    probed: bool = False,
    placing: bool = False,
) -> Any:
    """What the pads hold `obj` with at stroke L_s [m] (a `cell.robot.carry.GripHold`):
    the friction force of the grip model, the couple of the pads' contact patches (as
    long as the pads and the item overlap along the throw axis, as wide as both along
    y), and where the item's centre of mass sits above that patch.

    A mesh meets the flat pads wherever its surface does: no patch gives its couple.
    Seated in the pads as the grip probe seats it (`probed`: a kinematic pick), it is
    held as the scene measures it (`mesh_grip`: the probe's force, at most the model's,
    and its couple) when it is `placing`, where a turn in the pads matters little, or
    when the probe holds it with the model's force (MESH_PROBED_MIN_RATIO of it at
    least: its contacts act as the model's faces); else it is given none (any turn asks
    too much: the carry goes at GENTLE_SCALE).

    Measured, carried to a throw's release at the probed hold's limit (tests/test_carry.py)
    against at GENTLE_SCALE, at strokes 0.04-0.08 m: the egg (probed ratio 1.0) and a
    rock (1.0) kept within 1.5 mm and 0.8° in the pads either way, the teddy (0.88)
    turned 1.9-3.1° against 2.7-3.8°, the duck (0.69) 0.5-4.4° against 0.5-0.6°; each
    carry 1.4 s against 2.5 s. Over the 20 random layouts (`cell bench sort`) the 67 eggs,
    teddies and rocks so thrown cycled in 199 s instead of 265 s, 66 in their bins before
    and after, the eggs' median landing error 0.035 -> 0.028 m. The force alone, without
    the couple, is not enough: a duck carried at 0.45 of its grip's force turned 7-8° in
    the pads and landed 0.12 m off. The route's choices (the level swing, a release on
    the move) keep a mesh held at points: given the couple there too, a duck took a
    release on the move and missed its bin by 1.3 m."""
    from cell.model.grip import grip_friction
    from cell.robot.carry import GripHold, patch_torsion_radius_m
    from cell.sim import EE_TO_TCP_M
    from cell.sim.mechanism import DEFAULT_GEOMETRY as GEO

    height = obj.size[2]
    length = min(GEO.pad_length_m, height)
    force = grip_force_n(params, obj, stroke_m)
    # a cylinder standing on the carriage meets each flat pad along a line (its side,
    # along the throw axis): the patch has no width
    half_y = 0.0 if obj.shape == "cylinder" else min(GEO.pad_half_width_m, obj.size[1] / 2)
    # a sphere meets the flat pads at two points: no couple to count on
    seated = probed and obj.shape == "mesh" and force > 0
    ratio, arm = mesh_grip(params, obj) if seated else (0.0, 0.0)
    if seated and (placing or ratio >= MESH_PROBED_MIN_RATIO):
        force, couple = ratio * force, arm * force
    elif obj.shape in ("sphere", "mesh"):
        couple = 0.0
    else:
        couple = PAD_COUPLE_FACTOR * force * patch_torsion_radius_m(half_y, length / 2)
    lever, base_half, inertia = (height - length) / 2, obj.size[1] / 2, float(obj.inertia[0])
    # a box or a cylinder pressed between the flat pads resists a tilt about y with the
    # pads' pressure along the patch and their friction w apart (cell.robot.carry)
    tilt = 0.0
    if obj.shape in ("cube", "cuboid", "cylinder") and force > 0:
        tilt = force * (length / (2 * grip_friction(obj, GEO.pad_length_m)) + obj.width / 2)
    if obj.shape == "sphere":
        # held at two points: at its equator (R ≤ L_p), on the line through its centre, so
        # a turn about the pads' axis moves nothing and the sphere need not turn with the
        # grip (no I α to supply); else at the pads' edges, R − L_p below its centre; it
        # meets the carriage's face at one point (no base to right it)
        lever, base_half, inertia = max(0.0, height / 2 - GEO.pad_length_m), 0.0, 0.0
    return GripHold(
        force_n=force,
        torque_nm=couple,
        mass_kg=obj.mass,
        inertia_xx=inertia,
        offset_tcp_m=(0.0, 0.0, stroke_m + height / 2 - EE_TO_TCP_M),
        lever_m=lever,
        base_half_m=base_half,
        torque_y_nm=tilt,
        inertia_yy=float(obj.inertia[1]) if tilt > 0 else 0.0,
        base_half_x_m=obj.width / 2 if tilt > 0 else 0.0,
    )


def mesh_grip(params: ModelParams, obj: ObjectParams) -> tuple[float, float]:
    """How the pads hold mesh `obj`, measured in the scene (`cell.sim.grip_probe`) at each
    of PROBE_STROKES_M: (the smallest ratio of the measured force to the grip model's, at
    most 1; the smallest arm [m] of the model's force that the measured couple is).

    The grip model's force, made for faces, may overstate what holds a mesh: the duck
    slides along the pads at 0.69 of it. The same probe gives a box's force and patch
    couple within 10 % (tests/test_grip_probe.py)."""
    from cell.sim.grip_probe import PROBE_STROKES_M, probe_grip

    ratios, arms = [1.0], []
    for stroke in PROBE_STROKES_M:
        force = grip_force_n(params, obj, stroke)
        if force > 0:
            probe = probe_grip(obj, stroke)
            ratios.append(probe.force_n / force)
            arms.append(probe.couple_nm / force)
    return min(ratios), min(arms, default=0.0)


def point_hold_use(params: ModelParams, obj: ObjectParams, stroke_m: float) -> float:
    """The share of what the scene's pads hold a sphere with at stroke L_s [m] that its
    weight asks held still: m g over the grip model's force times the least ratio the
    grip probe measures against it (`mesh_grip`, at PROBE_STROKES_M; a 72 mm sphere is
    pulled out of the pads at 0.91-0.93 of the model's force, where they meet it at
    their edges below its equator). A carry of an item held at points keeps its use
    within 1/`carry_safety`; where the weight alone asks more, no carry at that stroke
    does (`GripUse._carry_stroke`)."""
    from cell.model.params import G

    force = grip_force_n(params, obj, stroke_m)
    if force <= 0.0:
        return math.inf
    ratio, _ = mesh_grip(params, obj)
    return obj.mass * G / (ratio * force)


def grip_stroke_limit(params: ModelParams, obj: ObjectParams) -> float:
    """The longest stroke [m] the pads hold `obj` at (cell.model.grip), gripped across its
    first size (`cell.arm.grip_side` turns the item to grip it across another).

    Where the pads hold BRISK_CARRY_SAFETY x the item's weight, the longest stroke they do
    (the carries of the items the cell sorted before, unchanged); else, where they hold
    CARRY_MARGIN x its weight (what a carry may use of the grip, `cell.robot.carry`), the
    longest stroke they do: a heavy item, carried as slowly as its grip asks
    (`cell.robot.carry.plan_carry`, the tilt included).

    Raises:
        CannotGrip: the item is too wide for the pads, or too heavy for its width at
            every stroke even carried slowly; the message says what it was tried at.
    """
    why = grip_refusal(params, obj)
    if why:
        name = obj.name or obj.shape
        raise CannotGrip(f"{name} ({obj.mass * 1000:.0f} g) cannot be held: {why}; sort it by hand")
    s_max = grip_stroke_at(params, obj)
    assert s_max is not None
    return s_max


def grip_stroke_at(params: ModelParams, obj: ObjectParams) -> float | None:
    """The longest stroke [m] at which the pads hold BRISK_CARRY_SAFETY x the weight of
    `obj` (as gripped), else CARRY_MARGIN x it; None where neither at any stroke or the
    item is wider than the pads open."""
    return grip_strokes(params, obj)[0]


def grip_strokes(params: ModelParams, obj: ObjectParams) -> tuple[float | None, bool]:
    """(`grip_stroke_at`, whether the pads hold BRISK_CARRY_SAFETY x the weight there)."""
    from cell.model.grip import grip_friction, max_grip_stroke
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    obj = as_gripped(obj)
    if obj.width > 2 * DEFAULT_GEOMETRY.finger_open_m:
        return None, False
    mu = grip_friction(obj, DEFAULT_GEOMETRY.pad_length_m)
    for safety in (BRISK_CARRY_SAFETY, carry_safety(obj)):
        s_max = max_grip_stroke(params.ee, obj, safety=safety, friction=mu)
        if s_max is not None:
            return s_max, safety == BRISK_CARRY_SAFETY
    return None, False


def carry_safety(obj: ObjectParams, tuning: ArmTuning = TUNING) -> float:
    """The multiple of its weight the pads must hold `obj` with to carry it at all: the
    carry's bound CARRY_MARGIN for an item the pads hold by its faces (a box, a cylinder:
    its carry is slowed to keep the force, twist and tilt within it); for one they hold
    at points (a sphere, a mesh), the margin measured in the scene,
    `tuning.point_hold_margin` (a carry's time scaling cannot keep such an item from
    turning in the pads: it goes at GENTLE_SCALE)."""
    from cell.robot.carry import CARRY_MARGIN

    if obj.shape in ("sphere", "mesh"):
        return max(CARRY_MARGIN, tuning.point_hold_margin)
    return CARRY_MARGIN


def grip_refusal(params: ModelParams, obj: ObjectParams) -> str:
    """Why the pads cannot hold `obj` across its first size (as gripped), "" where they
    can: too wide for the pads, too narrow for the band to close on, or too heavy for
    its width even carried slowly (the weight over CARRY_MARGIN of the grip's force)."""
    from cell.model.grip import grip_friction, holding_mass_kg
    from cell.robot.carry import CARRY_MARGIN
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    ee = params.ee
    obj = as_gripped(obj)
    across = f"{obj.width * 1000:.0f} mm across the pads"
    widest = 2 * DEFAULT_GEOMETRY.finger_open_m
    if obj.width > widest:
        return f"{across}, wider than they open ({widest * 1000:.0f} mm)"
    if grip_stroke_at(params, obj) is not None:
        return ""
    if obj.width <= ee.d:
        return (
            f"{across}: the band closes the pads only on items wider than its anchor "
            f"spacing d = {ee.d * 1000:.0f} mm"
        )
    mu = grip_friction(obj, DEFAULT_GEOMETRY.pad_length_m)
    margin = carry_safety(obj)
    hold = holding_mass_kg(ee, ee.stroke_min, obj.width, mu) / margin
    what = "the carry's bound" if margin == CARRY_MARGIN else "held at points, as measured"
    return (
        f"{across}, the pads hold up to {hold * 1000:.0f} g even carried slowly (1/"
        f"{margin} of their friction: {what})"
    )


def release_grip_use(
    params: ModelParams, obj: ObjectParams, stroke_m: float, elevations_rad: Any
) -> np.ndarray:
    """What holding `obj` still with the throw axis at each of `elevations_rad` asks of
    the grip (`cell.robot.carry.uses`, the tilt about y included; ≤ 1/CARRY_MARGIN to
    carry it there), the grip rolled so the item's weight is on a pad (a throw's
    release, `cell.robot.ik.WEIGHT_ROLLS_RAD`, and the twist-free swing up to it), the
    pads at stroke L_s [m]. In ee_tcp axes gravity then asks f = (g cos e, 0, g sin e):
    along the pads' normal, which tilts a tall item about y, and onto the carriage."""
    from cell.model.params import G
    from cell.robot.carry import uses

    e = np.atleast_1d(np.asarray(elevations_rad, float))
    f = G * np.c_[np.cos(e), np.zeros_like(e), np.sin(e)]
    return uses(f, np.zeros_like(f), carry_hold(params, obj, stroke_m))


def release_elevation_min(
    params: ModelParams, obj: ObjectParams, stroke_m: float, lo_rad: float, hi_rad: float
) -> float | None:
    """The least elevation [rad] in [lo_rad, hi_rad] (on a 0.5° grid) at whose release
    the grip holds `obj` still within the carry's bound (`release_grip_use`); None when
    lo_rad already does, or when none in the range does (the elevation does not help)."""
    from cell.robot.carry import CARRY_MARGIN

    es = np.r_[lo_rad, np.arange(lo_rad, hi_rad + 1e-9, math.radians(0.5))[1:]]
    ok = release_grip_use(params, obj, stroke_m, es) <= 1.0 / CARRY_MARGIN
    if ok[0] or not ok.any():
        return None
    return float(es[int(np.argmax(ok))])


def grip_bounds(bounds: Any, params: ModelParams, stroke_max_m: float, what: str = "") -> Any:
    """`bounds` with the stroke capped at what the grip holds the item at [m].

    Raises:
        CannotGrip: the grip holds it only at (about) the shortest stroke, so no throw is
            left to plan; the message names `what` and what the cell can do instead.
    """
    from dataclasses import replace as dc_replace

    lo = params.ee.stroke_min if bounds.stroke_min is None else bounds.stroke_min
    hi = min(stroke_max_m, params.ee.stroke_max)
    if hi - lo < MIN_THROW_STROKE_RANGE_M:
        raise CannotGrip(
            f"{what or 'the item'}: the pads hold it only at the shortest stroke "
            f"({lo * 1000:.0f} mm), too weak a throw to plan: place it in a bin within "
            "reach, or sort it by hand"
        )
    return dc_replace(bounds, stroke_min=lo, stroke_max=hi)


class GripUse(ArmBase):
    """What the grip holds (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    def _swing_holds(
        self,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float],
        elevation_rad: float,
    ) -> bool:
        """Does the spline through the swing's waypoints (the path the carry follows, as
        `plan_path` shapes it) ask no more of the grip, held still anywhere
        (`static_grip_use`, the tilt about y included), than the carry's bound, or than
        the twist-free swing must (`release_grip_use` at every elevation it passes, up
        to the release's `elevation_rad`), or than its ends do? Between sparse waypoints
        the spline can roll the grip: on random layout 5 (UR5) a 200 mm bottle's swing
        rolled it 22° and the bottle left the pads. `carried`: the item and its stroke
        [m]."""
        most, allowed = self._swing_static(waypoints, carried, elevation_rad)
        return most <= allowed + self._over_bound(carried[0])

    def _over_bound(self, obj: ObjectParams) -> float:
        """How far over the carry's bound a box's route or carry may ask at rest
        (GRIP_USE_TIE: the pads held a box at 0.74-0.78 of their static limit
        accelerated); 0 for other shapes: a 200 mm cylinder whose swing asked 0.756 at
        rest, carried within 0.741 + 0.02, left the pads (its line contact)."""
        return self.tuning.grip_use_tie if obj.shape in ("cube", "cuboid") else 0.0

    def _swing_static(
        self,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float],
        elevation_rad: float,
    ) -> tuple[float, float]:
        """(the most the spline through `waypoints` asks of the grip held still, what a
        swing may ask: the carry's bound, the twist-free swing's own most, its ends'),
        as `_swing_holds` compares them; (0, 0) for an item held at points (a sphere, a
        mesh: any roll at all turns it, and the twist-free swing is all a route can do for
        it)."""
        from cell.robot.carry import static_grip_use
        from cell.robot.motion import spline_path

        obj, stroke = carried
        hold = carry_hold(self.params, obj, stroke)
        keep = distinct_waypoints(waypoints)
        if hold.torque_nm <= 0.0 or len(keep) < 2:
            return 0.0, 0.0
        lim = self.robot.limits
        path = spline_path(keep, lim.lower, lim.upper)  # as `plan_path` shapes it
        qs = np.asarray(path(np.linspace(0.0, 1.0, self.tuning.swing_check_samples)))
        use = static_grip_use(self.robot, hold, qs)
        allowed = max(self._level_swing_use(carried, elevation_rad), use[0], use[-1])
        return float(np.max(use)), float(allowed)

    def _level_swing_use(self, carried: tuple[ObjectParams, float], elevation_rad: float) -> float:
        """The most a twist-free swing from hanging to `elevation_rad` asks of the grip
        held still (`release_grip_use` at every elevation it passes), or the carry's bound
        if more."""
        from cell.robot.carry import CARRY_MARGIN

        level = release_grip_use(
            self.params, *carried, np.linspace(-math.pi / 2, elevation_rad, 46)
        )
        return max(1.0 / CARRY_MARGIN, float(np.max(level)))

    def _turns_if_rolled(self, obj: ObjectParams | None = None, stroke: float = 0.0) -> bool:
        """Would the carried item (or `obj` at `stroke` [m]) turn in the pads if the grip
        rolled its y axis up while it hangs (gravity along the pads' faces)? Then the
        swing is kept level."""
        from cell.model.params import G
        from cell.robot.carry import CARRY_MARGIN

        if obj is None:
            obj, stroke = self._carried
        h = carry_hold(self.params, obj, stroke)
        w = obj.mass * G
        turn = w * h.lever_m / h.torque_nm if h.torque_nm > 0 else math.inf
        return w / h.force_n + turn > 1.0 / CARRY_MARGIN

    def _seated_as_probed(self) -> bool:
        """Is the item carried seated in the pads as the grip probe seats it (`carry_hold`)?
        A kinematic pick seats it so; a physical pick grips it where the pads meet it as it
        lay: the probe's figures do not hold there (a teddy gripped so left the pads on a
        place's carry at them, once with each arm)."""
        return self.pick_mode != "physical"

    def _carry_stroke(self, obj: ObjectParams, d: Decision) -> float:
        """The stroke [m] the item is carried at: the throw's, or the shortest, where the
        band closes the pads hardest, for a static throw whose twist-free swing at the
        throw's stroke asks more of the grip held still than a carry may
        (`_level_swing_use`: a tall item's weight on a pad as the swing passes
        horizontal). The spool winds to the short stroke once the pads hold the item and
        back to the throw's at the release (`carry`), the arm still, at its speed (0.1 m/s
        in the scene: 0.45 s each way for a 75 mm stroke).

        Held still horizontal with its weight on a pad, a 150 g, 200 mm bottle
        (`o6_bottle`) tips out of the scene's pads at 75 and 60 mm and stays at 50 and
        30 mm (tests/test_tall_item.py). Over the 20 random layouts (`cell bench sort`), 14
        of 17 bottles landed in their bins instead of 8 (15 instead of 9 with the release
        turned toward the station), 0.3-0.6 s longer a cycle on average; carried at the
        throw's stroke they had left the pads as the swing passed horizontal (on layout 3
        their tilt about y reached 1.02-1.06 of what the pads resist while the carry's law
        used its whole bound). A kinematic pick only: a physical pick grips the item as it
        lay, where the probe's and the model's figures do not hold.

        A sphere is carried at the shortest stroke as well where, at the throw's, its
        weight alone asks more than its carry may of the pads' hold as the scene measures
        it (`point_hold_use`): then no carry at that stroke keeps within its bound, and
        it went at GENTLE_SCALE. Two 72 mm, 102 g spheres thrown at 97 mm (weight 0.60 of
        the model's force, 0.65 of the measured, over 1/1.6) left the pads 0.6 s into
        such a carry on random layout 3 (UR5, issue 59)."""
        from cell.robot.carry import CARRY_MARGIN

        short = max(self.params.ee.stroke_min, self.ee.band.ee.stroke_min)
        if self.pick_mode == "physical" or d.action != "throw" or d.moving or d.plan is None:
            return d.stroke_m
        if d.stroke_m <= short:
            return d.stroke_m
        if obj.shape == "sphere" and point_hold_use(self.params, obj, d.stroke_m) > 1.0 / (
            carry_safety(obj, self.tuning)
        ):
            log.info(
                "%s: its weight asks more than 1/%.2f of the pads' measured hold at the "
                "%.3f m stroke: carried at %.3f m, wound back at the release",
                obj.name or obj.shape,
                carry_safety(obj, self.tuning),
                d.stroke_m,
                short,
            )
            return short
        if carry_hold(self.params, obj, d.stroke_m).torque_nm <= 0.0:
            return d.stroke_m  # held at points (a sphere, a mesh): `_swing_static` leaves it
        level = self._level_swing_use((obj, d.stroke_m), d.plan.elevation_rad)
        if level <= 1.0 / CARRY_MARGIN + self._over_bound(obj):
            return d.stroke_m
        log.info(
            "%s: carried at the %.3f m stroke, wound to %.3f m at the release",
            obj.name or obj.shape,
            short,
            d.stroke_m,
        )
        return short

    def _check_held(self, obj: ObjectParams) -> None:
        """GraspLost when the item is no longer between the pads at the release pose."""
        if not self.ee.holds_item():
            raise GraspLost(
                f"{obj.name or obj.shape} left the grip while carried (mass "
                f"{obj.mass * 1000:.0f} g, width {obj.width * 1000:.0f} mm)",
                "carry",
            )
