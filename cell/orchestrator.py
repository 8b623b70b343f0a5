"""The arm as a platform of the item loop (`cell.loop`): pick, decide, plan, move, release.

For each item of a job the orchestrator has the item set on the pick station, moves
the arm over it (Pinocchio IK + a toppra path), grasps it, decides to place
(bin within reach) or throw (beyond), plans the release (throw optimisation
plus the learned ΔL_s when a residual model is given), moves to the release
configuration (toppra through pick → lift → release) and commands the
end-effector; the loop (`cell.loop.ItemLoop`) watches the item to rest in the
plant, scores it and appends the throw to the log store, each in its own
transaction. No PyBullet call is made here: the plant (`cell.sim.CellScene`)
reports where items are and what touches them.

A failure on one item (no IK solution, unreachable bin, item dropped) is
recorded with its reason and the run goes on.

Time accounting (honest): an item's `cycle_time_s` is the simulated time from
the start of its pick to the start of the next item's pick, everything
included: the moves, the end-effector's actions, the wait for the item to come
to rest, the retreat after a place, and the time lost on an item that failed.
`items_per_hour` counts only items at rest in their target bin, over the sum
of all cycles: a run whose items all fail sorts 0 items per hour.
"""

from __future__ import annotations

import logging
import math
import uuid
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from cell.arm.spots import place_spots, throw_spot
from cell.errors import (
    CannotGrip,
    CellError,
    GraspLost,
    IKFailed,
    InvalidInput,
    TrajectoryError,
    UnreachableTarget,
)
from cell.jobs import ItemSpec, Job, check_order
from cell.kinds import PICKS, RELEASES
from cell.loop import FAILURES, Decision, ItemLoop, ItemResult, RunSummary
from cell.model.objects import ObjectParams
from cell.params import ModelParams, load_params, scene_params_path

__all__ = [
    "FAILURES",  # re-exported from cell.loop, where it is defined
    "ItemResult",
    "RunSummary",
    "Orchestrator",
]

log = logging.getLogger(__name__)

PICK_STROKE_M = (
    0.045  # [m] stroke while carrying: grip force enough to hold items through arm moves
)
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
SWING_WAYPOINTS = 2  # waypoints that keep the carry's swing free of twist (see _swing)
SWING_WAYPOINTS_MAX = 8  # doubled up to this while the spline between them rolls the grip
SWING_CHECK_SAMPLES = 60  # configurations along the swing's spline its grip use is checked at
# Grip uses this close are taken as equal: routes compared at rest, and a route or a carry
# that asks this little over the carry's bound (0.741, CARRY_MARGIN) is taken as within it
# (the pads held 0.74-0.78 of their static limit accelerated, slid at 0.80)
GRIP_USE_TIE = 0.02
# A level swing whose joints travel farther than this × the ends' gap goes round (the
# demo's swings travel 1.5-1.8 × the gap; a UR5's that flung its items, 3.4 ×)
SWING_MAX_DETOUR = 2.5
# [s] wait after a move so the end-effector and item come to rest: none (0.05 s before; on
# random layouts 0-5 with the release search and the turn, 190 -> 189 of 198 in their bins
# and 1,420 -> 1,430 items per hour; with the constants below, README "Throughput")
SETTLE_S = 0.0
LIFT_M = 0.15  # [m] lift above the pick pose before moving to the release
# A lift's configuration farther than this from the pick's, in any joint, is on another
# IK branch: the straight lift would swing the arm round (a UR5 grip folded back over the
# station took 3.4 s to come up 0.15 m, 1.2 s to come up 0.075 m on its own branch)
LIFT_MAX_DQ_RAD = 1.0
# The carry from the pick leaves through the lowest of these lifts [m] (0: straight from the
# pick) whose path keeps the item rising out of the station, at least as far as it moves
# sideways, up to DEPARTURE_CLEAR_M (Orchestrator._departure); else through LIFT_M
DEPARTURE_LIFTS_M = (0.0, 0.01, 0.02, 0.04)
DEPARTURE_CLEAR_M = 0.02
# The empty arm's approach to a (kinematic) pick passes, without stopping, the point where
# the open pads' tips are this far over the item's top, and goes straight down from there
PICK_OVER_CLEARANCE_M = 0.01
GRIP_DOWN = (-math.pi / 2, 0.0)  # (elevation, azimuth) [rad] of the throw axis pointing down
PLACE_CLEARANCE_M = 0.02  # [m] item's lowest point above the bin floor when the place starts
PLACE_SPOTS_TRIED = 8  # place spots tried, best first, for one the arm reaches (IK)
ARM_SPEED_SCALE = 1.0  # fraction of the joint velocity/acceleration limits used
# The physical pick (Orchestrator._pick)
PICK_SCATTER_M = 0.03  # [m] items come to rest within ± this of the station's centre, in x and y
APPROACH_M = 0.02  # [m] the carriage's face this far above the item's top ends the approach move
DESCENT_MPS = 0.1  # [m/s] speed of the guarded descent onto the item
FINGER_CLEARANCE_M = 0.01  # [m] each open pad this far outside the item's gripping width
PRESS_M = 0.003  # [m] the guarded descent ends this far into the item's box (it stops at contact;
# a mesh whose top lies lower is gripped there, its box's top 3 mm under the carriage's face)
GRIP_IK_TOL = (1e-4, math.radians(0.02))  # [m], [rad] the grip's pose over the item
REPLAN_M = 1e-3  # [m] an item found this far (or REPLAN_RAD) from where the approach aimed …
REPLAN_RAD = math.radians(1.0)  # … gets a new approach before the descent
MAX_TILT_RAD = math.radians(25.0)  # [rad] the grip's approach leans at most this far from vertical
GRIP_LEANS = (1.0, 0.8, 0.6, 0.4, 0.2, 0.0)  # fractions of an item's tilt the approach follows
TOUCH_GAP_M = 5e-4  # [m] the pads close with the carriage's face this far above the item's top
PAD_TIP_CLEARANCE_M = 5e-4  # [m] … or with the pads' tips this far above the station (flat items)
LIFT_CHECK_M = 0.03  # [m] the first lift, in LIFT_CHECK_S [s], shows whether the pads hold it
LIFT_CHECK_S = 0.2
# [m] a release pose IK's whole search misses by this much is out of reach from any seed
# (`Orchestrator._release_ik`): 5 × POSITION_TOL_M
IK_OUT_OF_REACH_M = 5e-3
PICK_ATTEMPTS = 2  # a failed grasp is tried once more while the item is still on the station


def joint_gap(qa: np.ndarray, qb: np.ndarray) -> float:
    """The largest joint move between two configurations [rad]."""
    return float(np.max(np.abs(np.asarray(qb) - np.asarray(qa))))


def distinct_waypoints(waypoints: list[np.ndarray]) -> list[np.ndarray]:
    """The waypoints [rad] without those equal to the one before (a spline needs distinct
    knots): the first, then each that moves a joint more than 1e-9 rad from its predecessor."""
    return [waypoints[0]] + [
        w for a, w in zip(waypoints, waypoints[1:], strict=False) if joint_gap(a, w) > 1e-9
    ]


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


def grip_stroke_limit(params: ModelParams, obj: ObjectParams) -> float:
    """The longest stroke [m] the pads hold `obj` at (cell.model.grip).

    Raises:
        CannotGrip: the item is too wide for the pads, or too heavy for its width at
            every stroke; the message says what the cell can hold instead.
    """
    from cell.model.grip import GRIP_SAFETY, grip_friction, holding_mass_kg, max_grip_stroke
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    ee = params.ee
    name = obj.name or obj.shape
    obj = as_gripped(obj)
    widest = 2 * DEFAULT_GEOMETRY.finger_open_m
    # a sphere is as wide every way: no other side to turn toward the pads
    turn = "" if obj.shape == "sphere" else "turn it so a narrower side faces the pads, or "
    if obj.width > widest:
        raise CannotGrip(
            f"{name} is {obj.width * 1000:.0f} mm wide across the pads; they open to "
            f"{widest * 1000:.0f} mm: {turn}sort it by hand"
        )
    mu = grip_friction(obj, DEFAULT_GEOMETRY.pad_length_m)
    s_max = max_grip_stroke(ee, obj, friction=mu)
    if s_max is None:
        hold = holding_mass_kg(ee, ee.stroke_min, obj.width, mu) / GRIP_SAFETY
        if obj.width <= ee.d:
            why = (
                f"the band closes the pads only on items wider than its anchor spacing "
                f"d = {ee.d * 1000:.0f} mm"
            )
        else:
            why = (
                f"the pads hold up to {hold * 1000:.0f} g at {obj.width * 1000:.0f} mm "
                f"(with a {GRIP_SAFETY}x margin for carrying)"
            )
        wider = "" if obj.shape == "sphere" else "grip it across a wider side, or "
        raise CannotGrip(
            f"{name} ({obj.mass * 1000:.0f} g, {obj.width * 1000:.0f} mm across the pads) "
            f"cannot be held: {why}; {wider}sort it by hand"
        )
    return s_max


MIN_THROW_STROKE_RANGE_M = 1e-3  # [m] a throw needs at least this much stroke to choose from


# A launch slower than this [m/s] (the model's launch speed) is thrown flat, with the throw
# axis at most SLOW_LAUNCH_MAX_ELEVATION_RAD up. Measured in the scene (ad-hoc items
# 30-171 g): launched at 0.58-0.84 m/s at 35-60°, items fell back onto the pads (reach 17-66 %
# short of the model's, or no landing); at 10° a 100 g box launched at 0.72 m/s landed within
# 3 % of the model, and at 1.0 m/s and faster the model's reach holds at every elevation.
LAUNCH_SPEED_MIN_MPS = 1.0
SLOW_LAUNCH_MAX_ELEVATION_RAD = math.radians(20.0)


def clean_launch(speed_mps: float, elevation_rad: float) -> bool:
    """Does an item launched at `speed_mps` [m/s] with the throw axis at `elevation_rad`
    leave the pads as the model has it (fast enough, or flat enough not to fall back)?"""
    return speed_mps >= LAUNCH_SPEED_MIN_MPS or elevation_rad <= SLOW_LAUNCH_MAX_ELEVATION_RAD


def launch_stroke_limit(
    params: ModelParams,
    obj: ObjectParams,
    elevation_max_rad: float,
    model_obj: ObjectParams | None = None,
) -> float:
    """The longest stroke [m] at which the model launches `obj` at LAUNCH_SPEED_MIN_MPS
    or faster at every elevation up to `elevation_max_rad` (the steepest is the slowest),
    `obj` as the plan models it (`model_obj`; default `params.model_object(obj)`).

    Raises:
        UnreachableTarget: even the shortest stroke launches it slower (too heavy to
            throw steeply); the message says what the cell can do instead.
    """
    from cell.model.throw import longest_stroke_launching

    ee, name = params.ee, obj.name or obj.shape
    modelled = params.model_object(obj) if model_obj is None else model_obj
    s_max = longest_stroke_launching(ee, modelled, LAUNCH_SPEED_MIN_MPS, elevation_max_rad)
    if s_max is None or s_max < ee.stroke_min + MIN_THROW_STROKE_RANGE_M:
        raise UnreachableTarget(
            f"{name} ({obj.mass * 1000:.0f} g) is too heavy to throw steeply: the band "
            f"launches it slower than {LAUNCH_SPEED_MIN_MPS:.1f} m/s at every stroke, and a "
            "slow steep launch falls back onto the pads; place it in a bin within reach, or "
            "sort it by hand"
        )
    return s_max


def plan_clean(
    params: ModelParams, obj: ObjectParams, model_obj: ObjectParams, goal: Any, bounds: Any
) -> Any:
    """`plan_facing` within the launches the pads release cleanly (`clean_launch`): the
    planner's throw when it is one; else the same goal thrown flat (a slow launch at most
    SLOW_LAUNCH_MAX_ELEVATION_RAD up); else at strokes that launch at least
    LAUNCH_SPEED_MIN_MPS (`launch_stroke_limit`).

    Raises:
        UnreachableTarget: no clean launch within the bounds lands on the goal.
    """
    from dataclasses import replace as dc_replace

    from cell.optimize.plan import plan_facing

    plan = plan_facing(model_obj, goal, params.ee, bounds)
    if clean_launch(launch_speed_mps(params, model_obj, plan), plan.elevation_rad):
        return plan
    flat = dc_replace(
        bounds,
        elevation_min=min(bounds.elevation_min, SLOW_LAUNCH_MAX_ELEVATION_RAD),
        elevation_max=min(bounds.elevation_max, SLOW_LAUNCH_MAX_ELEVATION_RAD),
    )
    try:
        return plan_facing(model_obj, goal, params.ee, flat)
    except UnreachableTarget:
        pass
    s_fast = launch_stroke_limit(params, obj, bounds.elevation_max, model_obj)
    if bounds.stroke_max is not None:  # a cap the bounds already have (the grip's)
        s_fast = min(s_fast, bounds.stroke_max)
    return plan_facing(model_obj, goal, params.ee, grip_bounds(bounds, params, s_fast))


def launch_speed_mps(params: ModelParams, model_obj: ObjectParams, plan: Any) -> float:
    """The model's launch speed [m/s] of a static throw plan (the push and the ride)."""
    from cell.model.throw import launch_state

    return float(np.linalg.norm(launch_state(plan.to_batch(model_obj), params.ee)[1][0]))


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
            "reach, grip it across a narrower side, or sort it by hand"
        )
    return dc_replace(bounds, stroke_min=lo, stroke_max=hi)


def check_sortable(
    params: ModelParams,
    obj: ObjectParams,
    bin_spec: Any,
    *,
    policy: str = "auto",
    place_reach_m: float = 0.75,
    bounds: Any = None,
) -> None:
    """Raise CannotGrip or UnreachableTarget when the cell cannot sort `obj` into the
    bin: the pads cannot hold it, or (for a throw) no release within the bounds lands
    it there by the planner's model of the scene."""
    from cell.optimize.bounds import ThrowBounds

    s_max = grip_stroke_limit(params, obj)
    dist = math.hypot(*bin_spec.position)
    if policy == "place" or (policy == "auto" and dist <= place_reach_m):
        return
    b = bounds or ThrowBounds()
    if b.stroke_max is None or s_max < b.stroke_max:
        b = grip_bounds(b, params, s_max, obj.name or obj.shape)
    goal = (*bin_spec.position, bin_spec.rim_height)
    plan_clean(params, obj, params.model_object(obj), goal, b)


@dataclass
class LandingCorrection:
    """What the landings of one object (or class) taught the planner.

    The scene's reach along a throw is ρ times what the model predicted, and its
    direction is turned by δ: the next throw of the object aims at a point moved so
    that, with the same ρ and δ, it lands on the goal.

    Attributes:
        log_ratio: mean of log(observed reach / aimed reach), ρ = exp(log_ratio).
        turn_rad: mean angle from the aimed to the observed landing, seen from the
            release point [rad].
        n: landings averaged.
    """

    log_ratio: float = 0.0
    turn_rad: float = 0.0
    n: int = 0

    def add(self, log_ratio: float, turn_rad: float) -> None:
        """Average one more landing in."""
        self.n += 1
        self.log_ratio += (log_ratio - self.log_ratio) / self.n
        self.turn_rad += (turn_rad - self.turn_rad) / self.n


LEARN_MAX_LOG_RATIO = math.log(1.5)  # an object's correction stays within ×1/1.5 … ×1.5
LEARN_MAX_TURN_RAD = math.radians(10.0)  # … and ±10° of turn
LEARN_CLASS_MAX_LOG_RATIO = math.log(1.15)  # a class's (shape's) within ±15 %, for new objects
LEARN_CLASS_MAX_TURN_RAD = math.radians(3.0)


# Release fallbacks when the arm cannot reach a plan's release pose: (largest
# elevation [rad], the fast path's release height [m]), tried in turn.
RELEASE_FALLBACKS = ((math.radians(45.0), 0.7), (math.radians(30.0), 0.6))
# … then each of those with the release box shrunk to these fractions about its centre, in
# turn: the optimiser puts a long throw of a heavy item in the box's far upper corner, which
# the arm does not reach with the throw axis tilted (a 174 g disc to a bin 2.5 m out: 15 mm
# short). The 0.75 box can leave the target out of reach: the same disc aimed 0.1 m
# farther (a point of the bin clear of what it holds, `cell.arm.spots.throw_spot`) lay 2.17 m
# beyond its nearest release, and the item failed (random layout 0); the 0.9 box reaches
# both (tests/test_release_box.py)
RELEASE_BOX_SHRINKS = (0.75, 0.9)
# With `cycle_search`, a release's cycle estimate (`Orchestrator._release_costs`) counts
# this much of the empty arm's approach from where it is: the approach is paid once, the
# cycle by this item and the like ones after it. Counted in full, random layout 0's first
# item, chosen from the arm's start, kept the next ones on a branch 0.8 s slower a cycle;
# left out, the UR5's two wrist rolls (equal cycles) alternated on layout 3, each approach
# turning the wrist half a turn (0.4-0.6 s a pick).
APPROACH_WEIGHT = 0.25
# a throw's release turns from its bin toward the pick station (_facing_toward_station):
FACE_TURN_MAX_RAD = math.radians(90.0)  # [rad] at most this far,
FACE_MIN_OFF_RAD = math.radians(30.0)  # [rad] for a bin at least this far round from the station,
FACE_THROW_STRETCH = 1.10  # lengthening the throw at most this much


# Where a carry starts, for planning it before the pick (`Orchestrator._departure`): the
# pick's configuration [rad], the item's centre there [m, W] (None: not known), the item and
# the stroke it is held at [m].
PickState = tuple[np.ndarray, np.ndarray | None, ObjectParams, float]


class _Release(NamedTuple):
    """A throw's plan in one release bounds, as `Orchestrator._plan_facing` compares them."""

    cost: tuple[bool, float] | None  # (asks more of the grip than it holds, cycle [s]) or None
    plan: Any
    delta: float  # [m] the learned ΔL_s
    q_release: np.ndarray  # [rad] the release configuration chosen
    bounds: Any  # the release bounds it was planned in
    aim: np.ndarray  # [m, W] where the plan aims to cross the rim plane
    model_obj: ObjectParams  # the object the plan's model assumed


def _plan_time(trajs: list[Any], settle_s: float) -> float:
    """How long [s] `_move` takes along `_move_plan`'s trajectories: their durations and a
    settle of `settle_s` [s] at each stop between them."""
    return sum(float(t.duration) for t in trajs) + settle_s * (len(trajs) - 1)


def _clip(v: float, lim: float) -> float:
    return max(-lim, min(lim, v))


class Orchestrator:
    """Runs a sort job in the PyBullet cell.

    Args:
        job: the validated job.
        gui: show PyBullet's GUI.
        store: a throw-log store with `append(record)` (None: do not record).
        session: the session id written with every throw.
        params: model parameters for planning; default: the job's `cell.params`,
            else the scene's calibrated parameter file.
        end_effector: "pybullet" (the simulated one) or a ready EndEffector
            (e.g. the Dynamixel back-end): then the hardware end-effector is
            commanded in step with the simulated one.
        observer: told of the scene, each item's start, release, flight and result
            (`cell.record.observer.RunObserver`, e.g. the Rerun recorder), or None.
        pick: "kinematic": the item appears at the station's centre and is moved into
            the open grip (PyBulletEndEffector.grasp); "physical": it rests at a seeded
            random spot and yaw, and the arm grips it by contact (`_pick`).
        release: "auto": the planner releases a throw on the move where that is sooner
            than stopping and lands in the bin by the model; "static": always stop.
        turn_release: a throw to a bin far round from the pick station may be released
            with the arm turned toward the station, the throw axis on the bin, where the
            cycle estimate is shorter (`_facing_toward_station`; on by default, with
            `cycle_search`: README, "Throughput").
        learn: correct the planner from each observed landing (the flywheel): an
            object's next throw aims where its earlier landings say it must
            (LandingCorrection), and an object never thrown before takes its
            class's (shape's) correction, bounded more tightly.
        speed_scale: fraction of the joint velocity and acceleration limits the arm's
            moves use, in (0, 1] (a carry may go slower, as its grip allows).
        floor: also time each item's approach and throw's carry as one direct move
            (`floors`, `_time_floor`): what the routes cost against the arm's limits.
        cycle_search: choose each throw's release by its pick-to-pick cycle as the cell
            makes it, among the cell's release bounds and the lower ones
            (RELEASE_FALLBACKS), and carry it there (`_release_costs`, `_plan_facing`,
            `_release_branch`): sooner cycles for several times the planning (on by
            default: the planning of a throw then takes longer than its cycle here).
        order: the order the job's items are taken in (`cell.jobs.ORDERS`): "job", as
            listed; "bins", each bin's items one after another (the items at hand, as in
            a tote). A pick's IK is solved from where the arm is, the last release: after
            one at another bin it can come out elsewhere on the arm's redundancy, bin by
            bin the picks stay alike (tests/test_item_order.py).
    """

    def __init__(
        self,
        job: Job,
        *,
        gui: bool = False,
        store: Any = None,
        session: str = "",
        params: ModelParams | None = None,
        end_effector: Any = None,
        observer: Any = None,
        learn: bool = False,
        speed_scale: float = ARM_SPEED_SCALE,
        pick: str = "kinematic",
        release: str = "auto",
        turn_release: bool = True,
        floor: bool = False,
        cycle_search: bool = True,
        order: str = "job",
    ) -> None:
        from cell.endeffector.factory import make_in_step
        from cell.optimize.bounds import ThrowBounds
        from cell.robot.model import load_robot
        from cell.sim import BinSpec, CellScene

        if not (0.0 < speed_scale <= 1.0):
            raise InvalidInput(f"speed_scale {speed_scale!r}: give a fraction in (0, 1]")
        self.speed_scale = float(speed_scale)
        if pick not in PICKS:
            raise InvalidInput(f"pick {pick!r}: valid are {list(PICKS)}")
        check_order(order)  # before the scene is built
        self.job = job
        self.params = params or load_params(job.params or scene_params_path())
        self.bounds = ThrowBounds()
        self.bounds_now = self.bounds  # the bounds of the plan being made (see _plan)
        self._check_job()  # before the scene is built: a refused job leaves nothing open
        self.store = store
        self.session = session or f"run-{uuid.uuid4().hex[:8]}"
        self.robot = load_robot(job.robot)
        bins = [BinSpec(b.id, b.position, b.size, b.rim_height) for b in job.bins]
        self.scene = CellScene(
            job.robot,
            bins,
            gui=gui,
            pick_station_xy=job.pick_position[:2],
            pick_station_height=job.pick_position[2],
        )
        self.pick_mode = pick
        if release not in RELEASES:
            raise InvalidInput(f"release {release!r}: valid are {list(RELEASES)}")
        self.release_mode = release
        self.turn_release = bool(turn_release)  # `_facing_toward_station`
        self.cycle_search = bool(cycle_search)  # `_release_costs`, `_plan_facing`
        # with `floor`: per item index, (the seconds its approach and its throw's carry
        # took, the seconds each would take as one direct move: `_time_floor`)
        self.floor = bool(floor)
        self.floors: dict[int, tuple[float, float]] = {}
        self._index = -1  # the item being handled (`present`)
        self._presented: Any = None  # the item the plant presented last
        # the kinematic pick moves the item into the grip: the pads, longer than a flat
        # item, must not jam on the station's top while the fingers close
        self.scene.ee_collides_with_station(pick == "physical")
        self.effector = make_in_step(self.scene, end_effector)  # commands, in step
        self.ee = self.effector.sim  # the plant's end-effector: the physical pick's steps
        self._q_release = np.zeros(0)
        self._steepened = False  # the last plan was raised for the grip (`_steep_enough`)
        self._goal = np.zeros(3)  # the point of the rim plane the last plan is for (`throw_spot`)
        self._aim = np.zeros(3)  # where the last plan aims (the goal, or the learned aim)
        self._model_obj: Any = None  # the object as the last plan knew it (ObjectParams)
        self.residual = None
        if job.residual:
            from cell.residual.model import ResidualModel

            self.residual = ResidualModel.load(job.residual)
        self.q = np.asarray(self.scene.ready_q, float)
        self.observer = observer
        self.learn = learn
        self.corrections: dict[str, LandingCorrection] = {}
        self._frame: tuple[float, float] | None = None  # the grip's (azimuth, roll) now
        # IK solved and approaches timed since the decision began (`_solve_ik`,
        # `_approach_s`; `decide` clears them)
        self._ik_memo: dict[tuple[bytes, ...], Any] = {}
        self._approach_memo: dict[tuple[Any, ...], float] = {}
        self._placing = False  # the item carried is to be placed (carry_hold)
        self.loop = ItemLoop(
            job,
            self,
            self.scene,
            store=store,
            session=self.session,
            observer=observer,
            wait_for=self._same_kind if learn else None,
            order=order,
        )
        if observer is not None:
            observer.on_scene(self.scene, job)

    def _check_job(self) -> None:
        """Refuse the job before it starts if an item cannot be gripped or its bin is
        out of its reach (by the planner's model of the scene)."""
        from cell.errors import JobError

        job = self.job
        for spec in job.items:
            try:
                check_sortable(
                    self.params,
                    spec.obj,
                    job.bin(spec.bin),
                    policy=job.policy,
                    place_reach_m=job.place_reach_m,
                    bounds=self.bounds,
                )
            except (CannotGrip, UnreachableTarget) as exc:
                instead = (
                    ""
                    if isinstance(exc, CannotGrip)
                    else f"; move bin {spec.bin!r} within the reach above, or send the item "
                    "to another bin"
                )
                raise JobError(
                    f"{job.path}, line {spec.line}: item {spec.obj.name or spec.obj.shape} "
                    f"to bin {spec.bin!r}: {exc}{instead}"
                ) from None

    # -- motion ----------------------------------------------------------------
    def _tcp_for_item_centre(
        self, centre: np.ndarray, elevation: float, azimuth: float, stroke: float, obj: ObjectParams
    ) -> np.ndarray:
        """TCP position [m, W] that puts the gripped item's centre at `centre`."""
        from cell.frames import tcp_for_item_centre

        return tcp_for_item_centre(centre, elevation, azimuth, stroke, obj)

    def _ik(self, tcp: np.ndarray, elevation: float, azimuth: float) -> np.ndarray:
        from cell.robot.ik import solve_release_ik

        return solve_release_ik(self.robot, tcp, elevation, azimuth, self.q, self._release_ik).q

    def _release_ik(self, robot: Any, pose: Any, seed: np.ndarray | None = None) -> Any:
        """`solve_ik(robot, pose, seed)` for a release pose, remembered while one decision
        is made (`decide` clears it): a plan is made in up to three release bounds, each
        steep and not, both rolls, from up to three seeds, and the lower bounds often come
        to the same release pose. The same pose from the same seed is the same solution
        (the search is deterministic), so by default nothing changes but the time. With
        `cycle_search`, a pose the search (the seed, home, 30 random seeds, the polish)
        missed by IK_OUT_OF_REACH_M or more is out of the arm's reach and is not searched
        again from another seed. On the demo, a release 0.42 m out and 0.61 m up (the
        lowest release bounds) was missed by 12.4 mm from every seed, again and again:
        207 searches failed in its 18 throws, 81 now, and nothing chosen changed."""
        from cell.robot.ik import solve_ik

        if robot is not self.robot:
            return solve_ik(robot, pose, seed)
        return self._solve_ik(pose, seed, reach=self.cycle_search)

    def _solve_ik(self, pose: Any, seed: np.ndarray | None = None, reach: bool = False) -> Any:
        """`solve_ik(self.robot, pose, seed)`, remembered until the next decision
        (`decide` clears it): the same pose from the same seed is the same solution, or
        the same IKNoSolution. Every caller gets the same IKResult: nothing in the cell
        writes into a configuration array. `reach`: a pose missed by IK_OUT_OF_REACH_M or
        more is not searched again from another seed either (`_release_ik`)."""
        from cell.robot.ik import IKNoSolution, solve_ik

        where = (pose.position.tobytes(), pose.axis.tobytes(), repr(pose.roll).encode())
        key = (*where, b"" if seed is None else np.asarray(seed, float).tobytes())
        found = self._ik_memo.get(key)
        if found is None and reach:
            found = self._ik_memo.get(where)
        if found is None:
            try:
                found = solve_ik(self.robot, pose, seed)
            except IKNoSolution as exc:
                found = exc
                if reach and exc.position_error_m >= IK_OUT_OF_REACH_M:
                    self._ik_memo[where] = exc
            self._ik_memo[key] = found
        if isinstance(found, Exception):
            raise found
        return found

    def _swing(
        self,
        q_lift: np.ndarray,
        q_rel: np.ndarray,
        plan: Any,
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[np.ndarray]:
        """Waypoints between the lift and the release that keep the grip on the twist-free
        swing (`_pick_frame`): the throw axis turns up about one horizontal axis, the
        pads' y axis stays level. A joint-space spline between the two ends alone rolls
        the grip sideways on the way, and a tall item hanging from the pads turns in
        them (cell.robot.carry). Empty when the grip was not taken twist-free, or when
        no swing on the ends' IK branch is found (the spline between the ends is used).

        Each waypoint is solved from the previous one; when that chain leaves the ends'
        branch (a seed that does not converge falls back to home: a UR5 swing came out
        4.4 rad round in a joint between waypoints and flung the item), from the point
        on the joint-space line between the ends instead. A swing whose joints travel
        more than SWING_MAX_DETOUR × the ends' gap is not taken. Where the spline through
        SWING_WAYPOINTS of them rolls the grip more than the level swing must
        (`_swing_holds`), twice as many are tried, up to SWING_WAYPOINTS_MAX, and the
        one asking least of the grip at rest is kept (the fewer on a tie). `carried`:
        the item and its stroke [m] (default: the one in the grip)."""
        if self._frame is None or SWING_WAYPOINTS < 1 or not self._turns_if_rolled(*carried or ()):
            return []
        held = carried or self._carried
        n, best = SWING_WAYPOINTS, None
        while n <= SWING_WAYPOINTS_MAX:
            out = self._swing_waypoints(q_lift, q_rel, plan, n)
            if not out:  # none found with more: the sparser one (or none)
                break
            if best is not None and self._spline_within_limits([q_lift, *out, q_rel], 400) is None:
                break  # a denser one whose spline leaves the joint limits stops at each
            most, allowed = self._swing_static([q_lift, *out, q_rel], held, plan.elevation_rad)
            if best is None or most < best[0] - GRIP_USE_TIE:
                best = (most, allowed, out)
            if most <= allowed + self._over_bound(held[0]):
                break
            n *= 2
        if best is None:
            return []
        if best[0] > best[1] + self._over_bound(held[0]):
            log.info("the level swing asks more of the grip than it must, even at rest")
        if self._direct_is_better([q_lift, *best[2], q_rel], best[0], held, plan):
            return []
        return best[2]

    def _direct_is_better(
        self, route: list[np.ndarray], most: float, held: tuple[ObjectParams, float], plan: Any
    ) -> bool:
        """For a sphere: does the spline between the swing's ends alone turn the grip no
        more off one rotation (`_twist`) than the swing's `route`, ask no more of the grip
        at rest (than `most`, the route's), and carry the item sooner?"""
        if held[0].shape != "sphere":
            # only a sphere is the same turned about the throw axis: for other items
            # without a couple in the grip, over the 20 random layouts, 6 fewer landed
            return False
        direct = [route[0], route[-1]]
        if self._twist(direct) > self._twist(route):
            return False
        if self._swing_static(direct, held, plan.elevation_rad)[0] > most:
            return False
        try:
            sooner = (
                self._carry_path(direct, held).duration < self._carry_path(route, held).duration
            )
        except TrajectoryError:
            return False
        if sooner:
            log.debug("the spline between the swing's ends turns the grip less, and is sooner")
        return bool(sooner)

    def _twist(self, waypoints: list[np.ndarray]) -> float:
        """How far [rad] the grip turns off the one rotation that takes it from the first
        waypoint's orientation to the last's, at most along the spline through the
        `waypoints` (the path a carry follows): 0 for a swing about one fixed axis.

        The twist-free swing's waypoints are solved in the frame the release swings up
        from (`_pick_frame`), but a grip pointing down is solved at azimuth 0
        (`ReleasePose` keeps the axis, which has no azimuth there): on random layout 4 a
        sphere's swing to a bin behind the arm turned its grip 74° off that rotation and
        its wrist 3.4 rad, where the spline between the ends turned it 27° and took
        1.0 s against 2.5 s."""
        from scipy.spatial.transform import Rotation

        from cell.robot.motion import spline_path

        keep = distinct_waypoints(waypoints)
        if len(keep) < 2:
            return 0.0
        lim = self.robot.limits
        qs = np.asarray(
            spline_path(keep, lim.lower, lim.upper)(np.linspace(0, 1, SWING_CHECK_SAMPLES))
        )
        rots = [self.robot.tcp_pose(q)[1] for q in qs]
        # the axis of the one rotation between the ends (its sign does not matter here)
        rotvec = Rotation.from_matrix(rots[-1] @ rots[0].T).as_rotvec()
        angle = float(np.linalg.norm(rotvec))
        # no turn between the ends: any turn of the throw axis on the way is a twist
        k = rots[0][:, 2] if angle < 1e-6 else rotvec / angle
        v = rots[0].T @ k
        return max(math.acos(max(-1.0, min(1.0, float((r @ v) @ k)))) for r in rots)

    def _swing_waypoints(
        self, q_lift: np.ndarray, q_rel: np.ndarray, plan: Any, n: int
    ) -> list[np.ndarray]:
        """n waypoints of the twist-free swing from q_lift to q_rel (`_swing`), evenly in
        position and elevation; none when it goes round or has no IK."""
        az, roll = self._frame or (0.0, 0.0)
        rb = self.robot
        p0, p1 = rb.tcp_pose(q_lift)[0], rb.tcp_pose(q_rel)[0]
        e0, e1 = -math.pi / 2, plan.elevation_rad
        fs = [k / (n + 1) for k in range(1, n + 1)]
        from cell.robot.ik import ReleasePose, solve_ik

        poses = [
            ReleasePose.from_angles(p0 + f * (p1 - p0), e0 + f * (e1 - e0), az, roll) for f in fs
        ]
        gap = joint_gap(q_lift, q_rel)
        for chained in (True, False):
            out: list[np.ndarray] = []
            try:
                for f, pose in zip(fs, poses, strict=True):
                    if chained:  # from the previous waypoint (the lift for the first)
                        seed = out[-1] if out else q_lift
                    else:  # from the joint line between the ends
                        seed = q_lift + f * (q_rel - q_lift)
                    out.append(solve_ik(rb, pose, seed, random_seeds=0, solutions=1).q)
            except IKFailed:
                continue
            path = [q_lift, *out, q_rel]
            travel = sum(joint_gap(a, b) for a, b in zip(path[:-1], path[1:], strict=True))
            if travel <= SWING_MAX_DETOUR * gap + 1e-9:
                return out
            log.info("the level swing goes round (%.1f rad in a joint for %.1f)", travel, gap)
        return []

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

    @staticmethod
    def _over_bound(obj: ObjectParams) -> float:
        """How far over the carry's bound a box's route or carry may ask at rest
        (GRIP_USE_TIE: the pads held a box at 0.74-0.78 of their static limit
        accelerated); 0 for other shapes: a 200 mm cylinder whose swing asked 0.756 at
        rest, carried within 0.741 + 0.02, left the pads (its line contact)."""
        return GRIP_USE_TIE if obj.shape in ("cube", "cuboid") else 0.0

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
        qs = np.asarray(path(np.linspace(0.0, 1.0, SWING_CHECK_SAMPLES)))
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

    def _pick_frame(self, plan: Any) -> tuple[float, float] | None:
        """(azimuth, roll) [rad] of the grip pointing down that the release's frame swings
        up from without a twist about the throw axis, or None (a place: any roll).

        axis_frame(e, a, roll) = Rz(a) Ry(π/2 − e) Rz(roll): with the same a and roll, the
        down frame (e = −π/2) turns into the release frame about one horizontal axis. A
        twist about the axis while the pads hold the item shifts its contacts and spoils
        the launch (measured in the scene: a cylinder carried through a half turn about
        the axis left at 0.25 m/s sideways and downward instead of 2.5 m/s forward).

        The grip pointing down is solved from `ReleasePose.from_angles`, which keeps the
        throw axis and the roll but not the azimuth of a vertical axis: it is gripped as
        at azimuth 0, and the swing's waypoints (at the release's azimuth) turn it about
        the axis on the way up, by as much as the release's azimuth. Measured on random
        layout 4: up to 80° off the one rotation between the swing's ends, to a bin
        behind the arm; solving the pick at the release's azimuth made that layout slower
        (81.5 → 92.2 s simulated), so it is kept as it is (README, Limits, Throughput).
        """
        if plan is None:
            return None
        roll = self._roll_of(self._q_release, plan.elevation_rad, plan.azimuth_rad)
        return (float(plan.azimuth_rad), roll)

    def _ik_frame(self, tcp: np.ndarray, seed: np.ndarray | None = None) -> np.ndarray:
        """IK for the grip pointing down at `tcp` [m, W], in the item's frame
        (`self._frame`: (azimuth, roll), else the roll is free), from `seed` (default:
        where the arm is)."""
        az = 0.0 if self._frame is None else self._frame[0]
        return self._ik_gripped(tcp, -math.pi / 2, az, seed)

    def _ik_gripped(
        self, tcp: np.ndarray, elevation: float, azimuth: float, seed: np.ndarray | None = None
    ) -> np.ndarray:
        """IK at the roll the item was gripped for (`self._frame`); without one, or when that
        roll has no solution, the roll `solve_release_ik` chooses. From `seed` (default:
        where the arm is)."""
        from cell.robot.ik import ReleasePose, solve_release_ik

        q0 = self.q if seed is None else seed
        if self._frame is not None:
            pose = ReleasePose.from_angles(tcp, elevation, azimuth, self._frame[1])
            try:
                return self._solve_ik(pose, q0).q
            except IKFailed:
                log.info("no IK at the gripped roll at %s: the roll is left to the solver", tcp)
        return solve_release_ik(self.robot, tcp, elevation, azimuth, q0).q

    def _release_branch(
        self, q_lift: np.ndarray, q_rel: np.ndarray, chosen: Any, tcp: np.ndarray, plan: Any
    ) -> np.ndarray:
        """The release configuration a throw's carry goes to: q_rel (solved from where the
        pick left the arm), unless the item must be carried level (`_turns_if_rolled`),
        IK landed on another branch than the release `_release_q` chose and timed
        (`chosen`, [rad]), and the chosen one's swing asks clearly less of the grip at
        rest (`_swing_static`, by more than GRIP_USE_TIE). A UR5 carried a 200 mm bottle
        round on the other branch (1.33 against 1.00), its grip rolled 50°, and the
        bottle left the pads; a 70 mm, 60 g cylinder's re-solved branch asked 0.97
        against the chosen one's 0.746, so its carry went at the gentle scale (5.8 s
        against the 3.2 s the decision timed). This holds even where the level swing
        alone is within the carry's bound: the spline between its waypoints is not.

        With `cycle_search` the decision times each candidate along the route the carry
        takes, from the pick: the carry goes to the chosen configuration wherever it is
        one of the release pose (its TCP within IK's own tolerance, POSITION_TOL_M, of
        `tcp` [m, W]). IK from the pick can land on another branch than the one timed:
        on random layout 2, a 67 mm cube's re-solved release was 3.13 rad away in a
        wrist joint, and its carry took 2.11 s in the scene against the 1.06 s timed
        (tests/test_release_choice.py). Without it, the decision times the carry from
        the lift, not from the pick, and the branch found from the pick is often the
        sooner: carried to the chosen one, that job's 67 mm cube took 1.91 s a cycle
        instead of 2.96 s, but its three 57 mm, 165 g cubes 15.65 s instead of 10.80 s."""
        from cell.robot.ik import POSITION_TOL_M

        if chosen is None or self.pick_mode == "physical":
            return q_rel
        chosen = np.asarray(chosen, float)
        if chosen.shape != q_rel.shape:
            return q_rel
        off_m = float(np.linalg.norm(self.robot.tcp_pose(chosen)[0] - np.asarray(tcp)))
        if self.cycle_search:
            return chosen if off_m <= POSITION_TOL_M else q_rel
        if not self._turns_if_rolled() or joint_gap(chosen, q_rel) < 1e-3 or off_m > 1e-4:
            return q_rel

        def most(q: np.ndarray) -> float:
            way = [q_lift, *self._swing(q_lift, q, plan), q]
            return self._swing_static(way, self._carried, plan.elevation_rad)[0]

        m_chosen, m_rel = most(chosen), most(q_rel)
        log.debug(
            "release branches: chosen %.3f, re-solved %.3f (grip use at rest)", m_chosen, m_rel
        )
        if m_chosen >= m_rel - GRIP_USE_TIE:
            return q_rel
        log.info("the release on the branch chosen for it: the other rolls the grip more")
        return chosen

    def _roll_of(self, q: np.ndarray, elevation: float, azimuth: float) -> float:
        """The roll (0 or π) of the release configuration q: its pads' axis against roll 0's."""
        from cell.robot.ik import ReleasePose

        x0 = ReleasePose.from_angles(np.zeros(3), elevation, azimuth, 0.0).rotation()[:, 0]
        return 0.0 if float(self.robot.tcp_pose(q)[1][:, 0] @ x0) >= 0.0 else math.pi

    def _move(self, waypoints: list[np.ndarray], settle_s: float | None = None) -> float:
        """Follow a toppra path through joint waypoints in the scene; returns its duration [s].

        Empty, the path uses `speed_scale` of the joint limits; carrying, the
        fastest time-scaling of it whose item acceleration the grip holds
        (`cell.robot.carry`).

        Where the cubic spline through the waypoints would leave the joint limits, the path
        keeps to the shape-preserving one (`cell.robot.motion.spline_path`) and is timed
        as a whole; stopping at each waypoint is timed too, each stretch at its own pace,
        and the sooner of the two is taken (a carry is slowed to its hardest stretch all
        along: on random layout 2, one path took 0.6-0.7 s longer than the stops for two
        of the three such carries). When no path through them is found, the arm stops at
        each.
        """
        settle_s = SETTLE_S if settle_s is None else settle_s
        trajs = self._move_plan(self.q, waypoints, settle_s)
        ends = waypoints if len(trajs) > 1 else waypoints[-1:]
        return sum(self._follow(t, w, settle_s) for t, w in zip(trajs, ends, strict=True))

    def _move_plan(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        settle_s: float,
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[Any]:
        """The trajectories `_move` follows from q_from through the waypoints [rad]: the
        one path, or one per waypoint when it stops at each (`_move`'s choice, a settle of
        `settle_s` [s] at each stop). `carried`: the item and its stroke [m] carried
        (default: what the grip holds)."""
        path: Any = None
        try:
            path = self._path(q_from, waypoints, carried)
        except TrajectoryError:
            if len(waypoints) < 2:
                raise
        if len(waypoints) >= 2 and (
            path is None or self._spline_within_limits([q_from, *waypoints], 400) is None
        ):
            stops = self._stops(q_from, waypoints, carried)
            t_stops = _plan_time(stops, settle_s)
            if path is None or t_stops < path.duration:
                return stops
        return [path]

    def _path(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float] | None = None,
    ) -> Any:
        """The trajectory of a move from q_from through the waypoints [rad]: empty, at
        `speed_scale` of the joint limits; carrying (`carried`, else what the grip
        holds), the fastest the grip holds the item along (`_carry_path`).
        TrajectoryError when there is none."""
        from cell.robot.motion import plan_path

        if carried is None and self.ee.item is None:
            return plan_path(
                [q_from, *waypoints],
                self.robot,
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )
        return self._carry_path([q_from, *waypoints], carried)

    def _stops(
        self,
        q_from: np.ndarray,
        waypoints: list[np.ndarray],
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[Any]:
        """The trajectories of a move that stops at each waypoint: a straight joint-space
        stretch each, which stays inside the joint limits' box."""
        out, q = [], q_from
        for w in waypoints:
            out.append(self._path(q, [w], carried))
            q = w
        return out

    def _follow(self, traj: Any, q_end: np.ndarray, settle_s: float) -> float:
        """Step the scene along a joint trajectory ending at rest at q_end [rad], then
        `settle_s` [s] more; returns the time taken [s]."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        ts = np.arange(sc.dt_s, traj.duration + sc.dt_s, sc.dt_s)
        qs, _, _ = traj.sample_many(ts)
        for q in qs:
            sc.set_arm(q)
            sc.step()
        if settle_s > 0:
            sc.run_for(settle_s)
        self.q = np.asarray(q_end, float)
        self.loop.land()
        return float(traj.duration) + settle_s

    def _carry_path(
        self, waypoints: list[np.ndarray], carried: tuple[ObjectParams, float] | None = None
    ) -> Any:
        """The fastest path through the waypoints (the first: where the arm starts) that
        the grip holds the item along (`carried`: the item and its stroke [m]; default:
        the one in the grip).

        A mesh thrown at the probe's couple (`carry_hold`) is never carried slower than at
        GENTLE_SCALE, as it was without that couple: where its path at rest asks nearly
        all the bound allows, the fastest uniform carry within it crawls (three eggs on
        random layout 11, UR5: 29 s a cycle without this floor, 8.6 s with it, 6.1-6.9 s
        before the probe's couple)."""
        from cell.robot.carry import plan_carry

        obj, stroke = carried or (self._carried[0], self._grip_stroke)
        hold = carry_hold(
            self.params, obj, stroke, probed=self._seated_as_probed(), placing=self._placing
        )
        traj, _ = plan_carry(
            waypoints,
            self.robot,
            hold,
            velocity_scale=self.speed_scale,
            acceleration_scale=self.speed_scale,
            tie=self._over_bound(obj),
            gentle_floor=obj.shape == "mesh" and hold.torque_nm > 0.0 and not self._placing,
        )
        return traj

    def _seated_as_probed(self) -> bool:
        """Is the item carried seated in the pads as the grip probe seats it (`carry_hold`)?
        A kinematic pick seats it so; a physical pick grips it where the pads meet it as it
        lay: the probe's figures do not hold there (a teddy gripped so left the pads on a
        place's carry at them, once with each arm)."""
        return self.pick_mode != "physical"

    def _time_floor(self, q_from: np.ndarray, t_from: float, settle_s: float = 0.0) -> None:
        """With `floor`, add to `floors` the move just made, from q_from [rad] at scene time
        t_from [s] to where the arm is: the time it took, and what one direct move would
        take (a jerk-limited rest-to-rest move at the arm's full limits, `move_time`;
        carrying, no faster than the grip holds the item along that joint-space line,
        as `_carry_path` times a carry; plus `settle_s` [s] after it). The direct move
        ignores what the routes are for (the clearance over the station, the level
        swing, the stop over the pick): a floor for these poses, not a plan."""
        if not self.floor:
            return
        from cell.robot.motion import move_time

        took = self.scene.t - t_from
        try:
            direct = move_time(q_from, self.q, self.robot)
            if self.ee.item is not None:
                direct = max(direct, float(self._carry_path([q_from, self.q]).duration))
        except TrajectoryError:
            direct = took - settle_s  # no direct move found: the one made
        spent, floor = self.floors.get(self._index, (0.0, 0.0))
        self.floors[self._index] = (spent + took, floor + min(took, direct + settle_s))

    # -- the platform's steps (cell.loop.Platform) -----------------------------
    name = "arm"
    overlaps = True  # the next pick starts while a thrown item flies
    rotor_rpm = 0.0

    def run_item(self, index: int, spec: ItemSpec) -> ItemResult:
        """Pick, decide, plan, move, release, observe and record one item, and wait
        for it to come to rest (`cell.loop.ItemLoop.run_item`)."""
        return self.loop.run_item(index, spec)

    def run(self, on_item: Callable[[ItemResult], None] | None = None) -> RunSummary:
        """Sort every item of the job (`cell.loop.ItemLoop.run`): the next pick starts
        as soon as an item is thrown; with `learn`, an item waits for the landing of an
        earlier throw of the same object (or class) still in flight, to learn from it."""
        return self.loop.run(on_item)

    def present(self, index: int, obj: ObjectParams) -> Any:
        """The item on the pick station: at its centre (kinematic pick), or at a seeded
        random spot and yaw (physical pick, `_spawn_at_station`)."""
        self._index = index
        if self.pick_mode == "physical":
            self._presented = self._spawn_at_station(index, obj)
            return self._presented
        # The station presents it as the arm leaves the previous item: at rest, as the arm
        # comes. A box, a cylinder or a sphere is set down resting on the station; a mesh
        # (whose box's bottom need not be its lowest point) 1 mm over it and drops there
        # while the arm is on its way (it rests within 15 ms).
        if obj.shape == "mesh":
            item = self.scene.spawn_item(obj.name)
        else:
            item = self.scene.spawn_item(obj, gap_m=0.0)
        self._presented = item
        return item

    def decide(self, index: int, obj: ObjectParams, target: Any) -> Decision:
        """Place (a bin within the job's place reach, or the job's policy) or throw, and
        the throw's plan, made before the pick: the end-effector grasps at the stroke it
        will throw with, so the item sits on the band carriage as the plan assumes."""
        self._ik_memo.clear()
        self._approach_memo.clear()
        dist = math.hypot(*target.position)
        place = self.job.policy == "place" or (
            self.job.policy == "auto" and dist <= self.job.place_reach_m
        )
        s_grip = grip_stroke_limit(self.params, obj)
        if place:
            return Decision("place", min(PICK_STROKE_M, s_grip), state={"target": target})
        plan, delta = self._plan(obj, target, index, s_grip)
        d = Decision(
            "throw",
            plan.stroke_m + delta,
            plan,
            delta,
            model_obj=self._model_obj,
            ee_params=self.params.ee,
            state={
                "target": target,
                "goal": self._goal,
                "aim": self._aim,
                "q_release": self._q_release,
            },
        )
        mt = None
        if self._may_release_moving(obj, d):
            mt = self._moving_choice(obj, plan, delta, s_grip)
        if mt is not None:
            d.plan, d.stroke_m, d.moving = mt.plan, mt.plan.stroke_m + delta, True
            d.state.update(moving=mt, q_release=mt.motion.q_release)
        return d

    def _may_release_moving(self, obj: ObjectParams, d: Decision) -> bool:
        """A release on the move is considered (`release="auto"`) unless a hardware
        end-effector rides along (its latch's timing is not modelled), a residual model
        corrects the stroke (it learned on static releases), or the item would turn in
        the pads on the way (the moving approach has no level swing)."""
        return (
            self.release_mode == "auto"
            and self.effector.hardware is None
            and self.residual is None
            and not self._turns_if_rolled(obj, d.stroke_m)
        )

    def _moving_choice(
        self, obj: ObjectParams, plan: Any, delta: float, stroke_max_m: float
    ) -> Any:
        """The release on the move that the planner prefers to the static one by cycle
        time, landing in the bin by the model (`cell.robot.moving_release.choose_release`,
        from where the lift over the presented item will be, its stroke at most
        `stroke_max_m`: what the grip holds), and that is sooner than the static one as
        the cell makes them from the pick (`_moving_sooner`); or None."""
        from cell.robot.moving_release import choose_release

        stroke = plan.stroke_m + delta
        self._frame = self._pick_frame(plan)
        try:
            _, q_lift = self._over_item(self._presented, stroke, obj)
            choice = choose_release(
                self.robot,
                self._model_obj,
                plan,
                q_lift,
                self.params.ee,
                bounds=grip_bounds(self.bounds_now, self.params, stroke_max_m),
                ik=lambda t, e, a: self._ik_gripped(t, e, a, q_lift),
                hold=carry_hold(self.params, obj, stroke),
                criterion="cycle",
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )
            if choice.moving is not None and not self._moving_sooner(
                obj, plan, stroke, choice.moving, delta
            ):
                return None
        except (IKFailed, TrajectoryError) as exc:
            log.info("no release on the move for %s: %s", obj.name or obj.shape, exc)
            return None
        finally:
            self._frame = None
        if choice.moving is not None:
            log.info("%s: release on the move saves %.2f s", obj.name or obj.shape, choice.saved_s)
        return choice.moving

    def _moving_sooner(
        self, obj: ObjectParams, plan: Any, stroke: float, mt: Any, delta: float
    ) -> bool:
        """Is the release on the move `mt` sooner than the static release of `plan` at
        `stroke` [m], each from the pick of the presented item to the release and back
        to that pick, as the cell makes them? The static: `_static_cycle_s`; the
        moving: its motion from the pick, or the move up to the lift, its settle and its
        motion from there (`_moving_route`), and the way back from where it stops. The
        moving plan's stroke is its own plus `delta`.

        `choose_release` times both from rest at the lift and back to it; the cell's
        static carry leaves the pick without stopping, and a moving release whose move
        from the pick does not rise from the station stops at the lift first. On random
        layouts 6 and 11, 13 of the 17 releases on the move it had chosen took 0.36-1.45 s
        longer a cycle than the static release of the same item (layout 11's three 51 mm
        cubes stopped at the lift); four 50 mm cubes' were 0.28-0.45 s sooner
        (tests/test_moving_choice.py). Where the static route is not found, the moving
        one is kept; where the moving one is not, IKFailed or TrajectoryError (then
        `_moving_choice` takes none)."""
        item = self._presented
        if item is None or self.pick_mode == "physical":
            return True  # no pick to time from (`choose_release`'s choice stands)
        s_moving = mt.plan.stroke_m + delta
        q_pick, q_lift = self._over_item(item, s_moving, obj)
        lifted, motion = self._moving_route(mt, obj, s_moving, q_pick, q_lift)
        t_moving = motion.duration_s + self._approach_s(
            motion.q_end, (q_pick, q_lift), s_moving, obj
        )
        if lifted:  # `_move` to the lift, its settle there
            held = (obj, s_moving)
            lift = self._move_plan(q_pick, [q_lift], SETTLE_S, held)
            t_moving += _plan_time(lift, SETTLE_S) + SETTLE_S
        try:
            t_static = self._static_cycle_s(obj, plan, stroke, self._q_release)
        except (IKFailed, TrajectoryError):
            return True
        log.info(
            "%s: release on the move %.2f s, static %.2f s, pick to pick",
            obj.name or obj.shape,
            t_moving,
            t_static,
        )
        return t_moving < t_static

    def pick(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """Grip the item turned as the release will hold it: the carry then only swings
        the throw axis up, it does not twist the item about it (a twist in the grip
        spoils the launch, see `_pick_frame`)."""
        self._q_release = d.state.get("q_release", self._q_release)
        self._frame = self._pick_frame(d.plan)
        if self.pick_mode == "physical":
            heading = self._carry_heading(d.plan, d.state["target"])
            d.state["q_lift"] = self._pick(obj, item, d.stroke_m, *heading)
            self._frame = None  # gripped as the item lay: its own heading (_carry_heading)
        else:
            d.state["q_lift"] = self._pick_kinematic(obj, item, d.stroke_m)
        self.effector.grasp(d.stroke_m)  # held in the plant already: the hardware winds
        stroke = self._carry_stroke(obj, d)
        if stroke != d.stroke_m:  # the item held, the carriage draws it up off the station
            self.effector.set_stroke(stroke)
            self._grip_stroke = stroke

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
        lay, where the probe's and the model's figures do not hold."""
        from cell.robot.carry import CARRY_MARGIN

        short = max(self.params.ee.stroke_min, self.ee.band.ee.stroke_min)
        if self.pick_mode == "physical" or d.action != "throw" or d.moving or d.plan is None:
            return d.stroke_m
        if d.stroke_m <= short or carry_hold(self.params, obj, d.stroke_m).torque_nm <= 0.0:
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

    def carry(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """To the release pose: over the bin and down into it (a place), or along the
        twist-free swing to the release configuration (a throw); the item still held."""
        q_lift = d.state["q_lift"]
        if d.action == "place":
            self._carry_to_place(d, obj, q_lift)
        elif d.moving:
            # the move is the release's own (approach, latch on the move, coast, stop),
            # planned from where the pick left the arm: the grip round the item, the item
            # on the station. Where that move would not lift it clear first (ruckig's move
            # need not go straight up: it can sweep the item out of the pads across the
            # station's top, `tests/test_moving_station.py`), or leaves the joint limits,
            # the arm goes up to the lift, where `_moving_choice` timed the release from
            lifted, motion = self._moving_route(d.state["moving"], obj, d.stroke_m, self.q, q_lift)
            if lifted:
                log.info("%s: up to the lift, then the release on the move", obj.name or obj.shape)
                self._move([q_lift])
            d.state["motion"] = motion
        else:
            plan = d.plan
            centre = np.array([plan.x_m, plan.y_m, plan.z_m])
            tcp = self._tcp_for_item_centre(
                centre, plan.elevation_rad, plan.azimuth_rad, d.stroke_m, obj
            )
            try:  # IK from the lift pose the arm is at; _plan checked one exists before
                q_rel = self._ik_gripped(tcp, plan.elevation_rad, plan.azimuth_rad)
            except IKFailed:
                q_rel = d.state["q_release"]
            q_rel = self._release_branch(q_lift, q_rel, d.state.get("q_release"), tcp, plan)
            q0, t0 = self.q, self.scene.t
            self._move(self._departure(q_lift, q_rel, plan))
            self._time_floor(q0, t0, settle_s=SETTLE_S)
            if self._grip_stroke != d.stroke_m:  # carried at a shorter one (`_carry_stroke`)
                self._check_held(obj)
                self.effector.set_stroke(d.stroke_m)
                self._grip_stroke = d.stroke_m
                self.scene.run_for(SETTLE_S)
        self._check_held(obj)

    def _static_carry(
        self,
        at: PickState,
        q_lift: np.ndarray,
        q_rel: np.ndarray,
        plan: Any,
    ) -> tuple[list[np.ndarray], float]:
        """(the waypoints, how long [s] `_move` takes along them) of a static throw's carry
        from the pick `at` (as `_departure` takes it) to the release q_rel [rad]: the
        route `_departure` plans and `_move_plan`'s trajectories along it, with a settle
        at each stop and at the release (tests/test_moving_choice.py: the scene's clock
        agrees within 20 ms)."""
        way = self._departure(q_lift, q_rel, plan, at)
        trajs = self._move_plan(at[0], way, SETTLE_S, (at[2], at[3]))
        return way, _plan_time(trajs, SETTLE_S) + SETTLE_S

    def _static_cycle_s(
        self,
        obj: ObjectParams,
        plan: Any,
        stroke: float,
        q_rel: np.ndarray,
        over: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> float:
        """How long [s] the cell takes from the pick of the presented item, gripped at
        `stroke` [m] in the frame `self._frame`, to its static release at q_rel [rad] for
        `plan` and back to that pick: the carry along `_departure`'s route
        (`_static_carry`), the push (COAST_S) and the empty arm's way back
        (`_approach_s`). The next item of the same kind is picked where this one was, so
        this is its pick-to-pick cycle; on random layout 3, 11 of 15 such cycles were
        within 0.03 s of the scene's. `over`: the pick's and the lift's configurations
        (`_over_item`), where known. IKFailed or TrajectoryError where a move is not
        found."""
        from cell.robot.moving_release import COAST_S

        q_pick, q_lift = over or self._over_item(self._presented, stroke, obj)
        at = (q_pick, self.scene.item_position(self._presented), obj, stroke)
        _, t_carry = self._static_carry(at, q_lift, q_rel, plan)
        return t_carry + COAST_S + self._approach_s(q_rel, (q_pick, q_lift), stroke, obj)

    def _moving_route(
        self, mt: Any, obj: ObjectParams, stroke: float, q_pick: np.ndarray, q_lift: np.ndarray
    ) -> tuple[bool, Any]:
        """(up to the lift first?, the motion) of the release on the move `mt` carrying
        `obj` at `stroke` [m] (`carry`): the release's own move from the pick q_pick
        [rad] where it leaves the station upward (`_moving_leaves_station`), else from
        rest at the lift q_lift. TrajectoryError when there is none from the lift."""
        from cell.robot.moving_release import plan_moving_release

        def motion_from(q: np.ndarray) -> Any:
            return plan_moving_release(
                self.robot,
                q,
                mt.motion.q_release,
                mt.motion.v_release,
                hold=carry_hold(self.params, obj, stroke),
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )

        try:
            motion = motion_from(q_pick)
            if self._moving_leaves_station(motion):
                return False, motion
        except TrajectoryError:
            pass
        return True, motion_from(q_lift)

    def release(self, d: Decision) -> np.ndarray | None:
        """Open the latch: slowly to place, at once to throw (a hardware end-effector
        first for a throw, after the simulated one for a place); on the move, at the
        planned instant while the arm moves (`cell.sim.release.release_in_scene`): then
        the item's centre at the latch [m, W] is returned."""
        if d.action == "place":
            self.effector.place()
            return None
        if not d.moving:
            self.effector.throw()
            return None
        from cell.sim.release import release_in_scene

        motion = d.state["motion"]
        rel = release_in_scene(self.scene, self.ee, motion)
        self.q = np.asarray(motion.q_end, float)
        self.loop.land()
        return np.asarray(rel.released_at, float)

    def after_place(self, d: Decision) -> None:
        """Back up out of the bin; no settle: nothing is held, and the next move starts
        from rest."""
        self._move(d.state.get("rise") or [d.state["q_above"]], settle_s=0.0)

    def finish(self, d: Decision | None) -> None:
        """Nothing of the item is held any more."""
        self.ee.item = None

    def landed(self, d: Decision, obj: ObjectParams, crossing: Any) -> None:
        """The flywheel: learn from the throw's observed crossing."""
        if self.learn:
            self._learn_from(obj, d.plan, crossing, d.state["aim"])

    def _same_kind(self, obj: ObjectParams, other: ObjectParams) -> bool:
        """Is `other` (in flight) the same object or class as `obj` (learning waits)?"""
        keys = {obj.name or "", self._class_key(obj)}
        return bool({other.name or "", self._class_key(other)} & keys)

    # -- the pick ----------------------------------------------------------------
    def _pick_kinematic(self, obj: ObjectParams, item: Any, stroke: float) -> np.ndarray:
        """The kinematic pick: the grip over the item, which is moved into it
        (PyBulletEndEffector.grasp); returns the lift configuration."""
        q_pick, q_lift = self._over_item(item, stroke, obj)
        q0, t0 = self.q, self.scene.t
        if not self._approach(item, stroke, obj, q_pick):
            self._move([q_lift, q_pick])
        self._time_floor(q0, t0)
        self.ee.grasp(stroke, item)
        self._carried = (obj, stroke)  # the item and its throw's stroke: what routes are for
        self._grip_stroke = stroke  # where the carriage holds it now (`_carry_stroke`)
        return q_lift

    def _approach(self, item: Any, stroke: float, obj: ObjectParams, q_pick: np.ndarray) -> bool:
        """The empty arm to the pick without stopping over it (`_approach_plan`); False
        when there is none, and nothing has moved."""
        traj, why = self._approach_plan(item, stroke, obj, q_pick)
        if traj is None:
            log.info("%s: over the lift instead", why)
            return False
        # no settle: the grasp that follows holds the arm still while the pads close
        self._follow(traj, q_pick, 0.0)
        return True

    def _approach_plan(
        self,
        item: Any,
        stroke: float,
        obj: ObjectParams,
        q_pick: np.ndarray,
        q_from: np.ndarray | None = None,
    ) -> tuple[Any, str]:
        """(the trajectory, "") of the empty arm from where it is (or `q_from`) to the pick
        without stopping over it: anywhere to the point the pads' length and PICK_OVER_CLEARANCE_M
        over the pick, then down the straight joint-space segment onto the item
        (`plan_approach`). Taken only if, until that point, the grip stays at least that
        high wherever it is over the station or within the grip's reach of it
        (`_keeps_over_station`); else (or when no IK or move is found) (None, why)."""
        from cell.robot.motion import plan_approach

        over = self.scene.geometry.pad_length_m + PICK_OVER_CLEARANCE_M
        p_item = self.scene.item_position(item)
        try:
            tcp = self._tcp_for_item_centre(
                p_item + np.array([0, 0, over]), *GRIP_DOWN, stroke, obj
            )
            q_over = self._ik_frame(tcp, q_pick)
            if joint_gap(q_pick, q_over) > LIFT_MAX_DQ_RAD:  # another IK branch
                return None, "the point over the pick is on another IK branch"
            traj = plan_approach(
                self.q if q_from is None else q_from,
                q_over,
                q_pick,
                self.robot,
                velocity_scale=self.speed_scale,
                acceleration_scale=self.speed_scale,
            )
        except (IKFailed, TrajectoryError) as exc:
            return None, f"no straight approach to the pick ({exc})"
        if not self._keeps_over_station(traj.parts[0], float(self.robot.tcp_pose(q_over)[0][2])):
            return None, "the approach to the pick dips over the station"
        return traj, ""

    def _departure(
        self,
        q_lift: np.ndarray,
        q_end: np.ndarray,
        plan: Any = None,
        at: PickState | None = None,
    ) -> list[np.ndarray]:
        """Waypoints from the pick (where the arm is) to q_end (a throw's release
        configuration, for its `plan`, or over a bin): through the lowest of
        DEPARTURE_LIFTS_M over the pick (the first: none) whose spline lifts the item out
        of the station (`_rises_from_station`) and stays within the joint limits, then
        (a throw) along the twist-free swing (`_swing`), which must keep a tall item within
        the grip held still anywhere (`_swing_holds`: the swing solved from a lower lift
        can come out on another branch and roll the grip); else through the full lift
        q_lift (the route `_release_q` timed). A spline through a lift LIFT_M up turns back
        on itself: the demo's throws carried 0.3-0.4 s longer than a per-joint time-optimal
        move.

        For an item the swing keeps level and the pads hold with a couple (not at points),
        the route without the swing's waypoints is a candidate beside it at each lift, held
        to the same test: what the twist-free swing would ask of the grip held still is
        what any route may ask, and where both pass, the sooner is taken (`_soonest`). On
        random layout 1 (UR5), four 100 mm boxes (cuboid_c) whose swing routes had failed
        from the pick went straight from it: 0.73-0.77 s against 1.38-1.43 s through the
        lift and the swing (tests/test_departure.py).

        `at`: where the carry starts (`PickState`), to time a departure before the pick
        (`_moving_sooner`); default: where the arm is, with what the grip holds."""
        # the swing is the throw's item at its throw's stroke (`_swing`'s default); the
        # routes' tests are at the stroke it is held at (`_carry_stroke`)
        swing_of: tuple[ObjectParams, float] | None = None
        if at is None:
            p_held = self.scene.item_position(self.ee.item) if self.ee.item is not None else None
            at = (self.q, p_held, self._carried[0], self._grip_stroke)
        else:
            swing_of = (at[2], at[3])
        q_pick, p_pick, obj, stroke = at
        level = plan is not None and self._turns_if_rolled(*swing_of or ())
        # a route that leaves the swing out, where it holds the item as well (below)
        unswung = level and carry_hold(self.params, obj, stroke).torque_nm > 0.0

        def holds(way: list[np.ndarray]) -> bool:
            return not level or self._swing_holds([q_pick, *way], (obj, stroke), plan.elevation_rad)

        for up in DEPARTURE_LIFTS_M:
            start: list[np.ndarray] = []
            if up > 0.0 and p_pick is not None:
                lift = p_pick + np.array([0.0, 0.0, up])
                try:
                    q_up = self._ik_frame(
                        self._tcp_for_item_centre(lift, *GRIP_DOWN, stroke, obj), q_pick
                    )
                except IKFailed:
                    continue
                if joint_gap(q_pick, q_up) > LIFT_MAX_DQ_RAD:
                    continue
                start = [q_up]
            elif up > 0.0:
                continue
            swung = self._swung(start[-1] if start else q_pick, q_end, plan, swing_of)
            ways = [[*start, *swung, q_end]] + ([[*start, q_end]] if swung and unswung else [])
            ways = [w for w in ways if self._rises_from_station([q_pick, *w]) and holds(w)]
            if ways:
                return self._soonest(ways, q_pick, (obj, stroke))
        swung = self._swung(q_lift, q_end, plan, swing_of)
        way = [q_lift, *swung, q_end]
        if swung and unswung and holds([q_lift, q_end]):
            return self._soonest([way, [q_lift, q_end]], q_pick, (obj, stroke))
        return way

    def _soonest(
        self,
        ways: list[list[np.ndarray]],
        q_from: np.ndarray,
        carried: tuple[ObjectParams, float],
    ) -> list[np.ndarray]:
        """Of routes from q_from [rad] carrying `carried` (the item and its stroke [m]: a
        carry's, `_departure`), the one `_move` takes soonest, its stops and settles
        counted; the first where none is timed."""
        if len(ways) == 1:
            return ways[0]
        best: tuple[float, list[np.ndarray]] | None = None
        for way in ways:
            try:
                trajs = self._move_plan(q_from, way, SETTLE_S, carried)
            except TrajectoryError:
                continue
            took = _plan_time(trajs, SETTLE_S)
            if best is None or took < best[0]:
                best = (took, way)
        return ways[0] if best is None else best[1]

    def _swung(
        self,
        q_from: np.ndarray,
        q_end: np.ndarray,
        plan: Any,
        carried: tuple[ObjectParams, float] | None = None,
    ) -> list[np.ndarray]:
        """The twist-free swing's waypoints for a throw's `plan` (`_swing`, `carried` as
        there); none for a place."""
        return [] if plan is None else self._swing(q_from, q_end, plan, carried)

    def _rises_from_station(self, waypoints: list[np.ndarray], n: int = 400) -> bool:
        """Does the spline through `waypoints` (`cell.robot.motion.spline_path`, the path a
        carry follows whatever its timing) stay within the joint limits and leave the
        station upward (`_leaves_station_upward`)? Then the item leaves the station
        neither dragged across its top nor pushed into it."""
        qs = self._spline_within_limits(waypoints, n)
        return qs is not None and self._leaves_station_upward(qs)

    def _moving_leaves_station(self, motion: Any, n: int = 200) -> bool:
        """Does a release on the move's `motion` (`plan_moving_release`, from the pick),
        at n instants up to the latch, leave the station upward (`_leaves_station_upward`)?
        The check `carry` makes before it takes that move."""
        ts = np.linspace(0.0, motion.t_release_s, n)
        return self._leaves_station_upward(np.array([motion.state(t)[0] for t in ts]))

    def _leaves_station_upward(self, qs: np.ndarray) -> bool:
        """Do the configurations `qs` [rad], a path from the pick in order, keep the grip,
        wherever it is over the pick station widened by the grip's reach, risen from the
        first at least as far as it has moved sideways (up to DEPARTURE_CLEAR_M; 1 mm
        tolerance)? The test of `_rises_from_station`, and of a release on the move's
        motion (`carry`)."""
        lo, hi = self.scene.pick_station_bounds()
        reach = self._grip_reach_m()
        p0 = self.robot.tcp_pose(qs[0])[0]
        for q in qs:
            p = self.robot.tcp_pose(q)[0]
            near = np.all(p[:2] > lo[:2] - reach) and np.all(p[:2] < hi[:2] + reach)
            side = float(np.hypot(*(p[:2] - p0[:2])))
            if near and p[2] - p0[2] < min(DEPARTURE_CLEAR_M, side) - 1e-3:
                return False
        return True

    def _spline_within_limits(self, waypoints: list[np.ndarray], n: int) -> np.ndarray | None:
        """n configurations [rad] evenly along the cubic spline through the distinct
        `waypoints` (`cell.robot.motion.spline_path` without limits: the path a move
        follows whatever its timing), or None when they are fewer than two or that spline
        leaves the joint limits: such a route is not chosen (a move along one, the last
        resort of `_departure`, follows the shape-preserving path instead)."""
        from cell.robot.motion import spline_path

        keep = distinct_waypoints(waypoints)
        if len(keep) < 2:
            return None
        qs = np.asarray(spline_path(keep)(np.linspace(0.0, 1.0, n)))
        lim = self.robot.limits
        if np.any(qs < lim.lower - 1e-6) or np.any(qs > lim.upper + 1e-6):
            return None
        return qs

    def _grip_reach_m(self) -> float:
        """How far [m] the grip reaches out from its centre, horizontally: the carriage's
        half side, the open pads and their thickness."""
        geo = self.scene.geometry
        return float(geo.carriage_half_xy_m + geo.finger_open_m + geo.pad_thickness_m)

    def _keeps_over_station(self, traj: Any, z_min: float) -> bool:
        """Does the grip centre stay at least z_min [m] high (1 mm tolerance) wherever it
        passes over the pick station's top, widened by the grip's reach (the carriage's
        half side and the open pads), along `traj` (sampled every physics step)?"""
        sc = self.scene
        lo, hi = sc.pick_station_bounds()
        reach = self._grip_reach_m()
        ts = np.arange(0.0, traj.duration + sc.dt_s, sc.dt_s)
        for q in traj.sample_many(ts)[0]:
            p = self.robot.tcp_pose(q)[0]
            near = np.all(p[:2] > lo[:2] - reach) and np.all(p[:2] < hi[:2] + reach)
            if near and p[2] < z_min - 1e-3:
                return False
        return True

    def _over_item(
        self, item: Any, stroke: float, obj: ObjectParams
    ) -> tuple[np.ndarray, np.ndarray]:
        """(pick, lift) configurations of the grip pointing down over the item where the
        plant has it, the pick putting the item's centre where the gripped item's will be."""
        p_item = self.scene.item_position(item)
        q_pick = self._ik_frame(self._tcp_for_item_centre(p_item, *GRIP_DOWN, stroke, obj))
        return q_pick, self._lift_q(p_item, stroke, obj, q_pick)

    def _lift_q(
        self, p_item: np.ndarray, stroke: float, obj: ObjectParams, q_pick: np.ndarray
    ) -> np.ndarray:
        """The configuration LIFT_M over the pick (IK from the pick's), or as high as the
        arm reaches on the pick's own IK branch (within LIFT_MAX_DQ_RAD of it in every
        joint): a tall item gripped at a long stroke puts the flange up to 0.3 m over the
        item, and 0.15 m more can be out of the arm's reach, or only reached on another
        branch, a swing of the whole arm away."""
        err: IKFailed | None = None
        far: list[tuple[float, np.ndarray]] = []  # (joint gap from the pick, lift)
        for up in (LIFT_M, LIFT_M / 2, LIFT_M / 4):
            lift = p_item + np.array([0, 0, up])
            try:
                q = self._ik_frame(self._tcp_for_item_centre(lift, *GRIP_DOWN, stroke, obj), q_pick)
            except IKFailed as exc:
                err = err or exc
                continue
            gap = joint_gap(q_pick, q)
            if gap <= LIFT_MAX_DQ_RAD:
                return q
            far.append((gap, q))
        if far:  # no lift on the pick's own branch: the nearest other (a long way round)
            log.info("no lift over the pick within %.1f rad of its joints", LIFT_MAX_DQ_RAD)
            return min(far, key=lambda gq: gq[0])[1]
        assert err is not None
        raise err

    def _spawn_at_station(self, index: int, obj: ObjectParams) -> Any:
        """The item, set down on the pick station at a random spot (± PICK_SCATTER_M) and
        yaw drawn from the job's seed and the item's index (reproducible); it settles while
        the arm comes over it (`_pick_once` waits for it to rest before the descent)."""
        rng = np.random.default_rng([self.job.seed, index])
        dx, dy = rng.uniform(-PICK_SCATTER_M, PICK_SCATTER_M, 2)
        yaw = float(rng.uniform(-math.pi, math.pi))
        item = self.scene.spawn_item(
            obj if obj.shape != "mesh" else obj.name, offset_xy=(dx, dy), yaw=yaw
        )
        self.scene.run_for(0.05)  # let it settle on the station
        return item

    def _item_pose(self, item: Any) -> tuple[np.ndarray, np.ndarray]:
        """The item as the plant reports it: centre [m, W] and rotation matrix (3, 3)."""
        return self.scene.item_pose(item)

    @staticmethod
    def _grip_axes(
        obj: ObjectParams, rot: np.ndarray, heading: float, signed: bool, lean: float = 1.0
    ) -> tuple[float, float, list[float]]:
        """The grip for an item at rotation `rot` (its pose as the plant reports it):
        (elevation, azimuth [rad]) of the approach axis u, and the rolls [rad] about it
        that close the pads across the item's x axis (its gripping width).

        The grip comes down the item's own axis (−z), so that an item resting tilted (a
        mesh on an uneven side) ends seated square on the carriage as the throw model
        assumes; straight down onto a sphere. `lean` < 1 turns the approach that fraction
        of the way from straight down to the item's axis (`_grip_plan`: where the full
        lean would put a pad on the station). Of the rolls the item's symmetry allows
        (a quarter turn for a square section, a half turn else; any for an upright
        cylinder), those that point the pads' axis (E's x) nearest the horizontal direction
        `heading` [rad] (`signed`: along it, else either way): the carry's heading is a
        throw's azimuth, E's x pointing the way that turns the grip up to the release's
        roll about E's y alone (or a place's bin). Then the pads' normal forces, not
        their friction alone, hold the item against the turn's and the carry's
        accelerations, which would swing it about the pads' axis.
        """
        from cell.frames import axis_frame

        vertical = np.array([0.0, 0.0, 1.0])
        up = vertical if obj.shape == "sphere" else rot[:, 2] / np.linalg.norm(rot[:, 2])
        up = (1.0 - lean) * vertical + lean * up
        u = -up / np.linalg.norm(up)
        if math.hypot(u[0], u[1]) < 1e-9:  # straight down (as ReleasePose reads it)
            elevation, azimuth = -math.pi / 2, 0.0
        else:
            elevation = math.asin(max(-1.0, min(1.0, float(u[2]))))
            azimuth = math.atan2(float(u[1]), float(u[0]))
        a0 = axis_frame(elevation, azimuth, 0.0)
        h = np.array([math.cos(heading), math.sin(heading), 0.0])
        if obj.shape in ("sphere", "cylinder"):  # any roll grips it: along the heading
            d = h - (h @ a0[:, 2]) * a0[:, 2]
            dirs = [d, -d]
        else:
            square = obj.shape == "cube" or (
                obj.shape == "cuboid" and abs(obj.size[0] - obj.size[1]) < 1e-9
            )
            n = 4 if square else 2
            dirs = [
                rot @ np.array([math.cos(k * 2 * math.pi / n), math.sin(k * 2 * math.pi / n), 0])
                for k in range(n)
            ]
            dirs = [d - (d @ u) * u for d in dirs]  # across the axis (a leaning grip's)

        def off(d: np.ndarray) -> float:  # angle between d's horizontal part and the heading
            ang = math.atan2(float(d[1]), float(d[0])) - heading
            return abs(math.remainder(ang, 2 * math.pi if signed else math.pi))

        best = min(off(d) for d in dirs)
        rolls = [
            math.atan2(float(a0[:, 1] @ d), float(a0[:, 0] @ d))
            for d in dirs
            if off(d) < best + 1e-6
        ]
        return elevation, azimuth, rolls

    def _grip_plan(
        self, obj: ObjectParams, item: Any, heading: float, signed: bool, opening: float
    ) -> tuple[np.ndarray, float, float, list[float], float]:
        """The item's centre [m, W] as the plant reports it, the grip's approach axis
        (elevation, azimuth) and rolls [rad] (`_grip_axes`), and the least standoff h_min
        [m] of the carriage's face from the item's top along the axis that keeps every pad
        corner (the pads open `opening` [m] from the axis) PAD_TIP_CLEARANCE_M above the
        station: down the item's axis if that lets the grip reach its top (h_min ≤ 0),
        else leaning less towards it (GRIP_LEANS), at most MAX_TILT_RAD from vertical."""
        from cell.frames import axis_frame

        geo = self.scene.geometry
        p, rot = self._item_pose(item)
        tilt = math.acos(max(-1.0, min(1.0, float(rot[2, 2]))))
        for lean in GRIP_LEANS:
            if lean * tilt > MAX_TILT_RAD and lean > 0:
                continue
            elevation, azimuth, rolls = self._grip_axes(obj, rot, heading, signed, lean)
            u = axis_frame(elevation, azimuth)[:, 2]
            drop = max(  # lowest pad corner below the pads' tip line on the axis [m]
                (opening + geo.pad_thickness_m) * abs(f[2, 0]) + geo.pad_half_width_m * abs(f[2, 1])
                for f in (axis_frame(elevation, azimuth, r) for r in rolls)
            )
            floor = self.scene.pick_station_height + PAD_TIP_CLEARANCE_M + drop
            h_min = (floor - p[2]) / -u[2] - obj.size[2] / 2 + geo.pad_length_m
            if h_min <= 0 or lean == 0:
                break
        return p, elevation, azimuth, rolls, float(h_min)

    def _ik_grip(
        self, centre: np.ndarray, stroke: float, obj: ObjectParams, axes: tuple[float, float, float]
    ) -> np.ndarray:
        """IK of the grip with the item's centre at `centre` [m, W], seated on the carriage
        at `stroke`, the approach axis and roll `axes` (elevation, azimuth, roll [rad]).

        Solved to GRIP_IK_TOL (far tighter than a release's): pads a fraction of a degree
        off the item's sides close on its edges, whose contacts can hook it when the
        carriage hits its end stop; the release's tolerance if that does not converge."""
        from cell.robot.ik import ReleasePose, solve_ik

        tcp = self._tcp_for_item_centre(centre, axes[0], axes[1], stroke, obj)
        pose = ReleasePose.from_angles(tcp, *axes)
        try:
            return solve_ik(
                self.robot, pose, self.q, tol_position_m=GRIP_IK_TOL[0], tol_axis_rad=GRIP_IK_TOL[1]
            ).q
        except IKFailed:
            return solve_ik(self.robot, pose, self.q).q

    def _ik_grip_any(
        self,
        centre: np.ndarray,
        stroke: float,
        obj: ObjectParams,
        elevation: float,
        azimuth: float,
        rolls: list[float],
    ) -> tuple[np.ndarray, float]:
        """`_ik_grip` at whichever of the rolls gives the configuration nearest the current
        one, and that roll."""
        found: list[tuple[np.ndarray, float]] = []
        err: IKFailed | None = None
        for roll in rolls:
            try:
                found.append((self._ik_grip(centre, stroke, obj, (elevation, azimuth, roll)), roll))
            except IKFailed as exc:
                err = err or exc
        if not found:
            assert err is not None
            raise err
        return min(found, key=lambda f: float(np.linalg.norm(f[0] - self.q)))

    def _straight(
        self,
        q_to: np.ndarray,
        duration_s: float,
        stop: Callable[[], bool] | None = None,
        *,
        smooth: bool = False,
    ) -> float:
        """A short move along the joint-space segment to q_to in `duration_s` [s] (nearby
        configurations: the grip moves on a near-straight line), at constant speed or with
        a smooth start and stop (3τ² − 2τ³); it ends early when `stop()` says so (a guarded
        move). Returns the fraction of the segment done (1.0: all of it)."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        q0 = self.q.copy()
        n = max(1, math.ceil(duration_s / sc.dt_s))
        done = 1.0
        for k in range(1, n + 1):
            tau = k / n
            done = tau * tau * (3 - 2 * tau) if smooth else tau
            self.q = q0 + (q_to - q0) * done
            sc.set_arm(self.q.tolist())
            sc.step()
            if stop is not None and stop():
                break
        return done

    def _wait_at_rest(self, item: Any, timeout_s: float = 1.0) -> None:
        """Step until the item rests (below 2 mm/s and 0.05 rad/s) or `timeout_s` [s]."""
        sc = self.scene
        t_end = sc.t + timeout_s
        while sc.t < t_end:
            v, w = sc.item_velocity(item)
            if np.linalg.norm(v) < 2e-3 and np.linalg.norm(w) < 0.05:
                return
            sc.step()

    def _carry_heading(self, plan: Any, target: Any) -> tuple[float, bool]:
        """Where the pads' axis (E's x) should point while the item is carried, and whether
        its sense matters (see `_grip_axes`): for a throw, along the azimuth, the way the
        release's roll (0 or π, `_q_release`) turns up to about E's y alone; for a place,
        either way along the line from the station to the bin."""
        if plan is None:
            x0, y0 = self.scene.pick_station_xy
            return math.atan2(target.position[1] - y0, target.position[0] - x0), False
        # at the release, roll 0 puts E's x at (sin e cos a, sin e sin a, −cos e): turned
        # down about E's y it points back along the azimuth; roll π, forward
        roll = self._roll_of(self._q_release, plan.elevation_rad, plan.azimuth_rad)
        return plan.azimuth_rad + math.pi - roll, True

    def _pick(
        self, obj: ObjectParams, item: Any, stroke: float, heading: float, signed: bool
    ) -> np.ndarray:
        """Pick the item off the station into the grip at `stroke` [m], by contact: returns
        the lift configuration the arm is at, the item held by friction between the pads.
        `heading` [rad], `signed`: where the pads' axis should point while it is carried
        (`_carry_heading`), as far as the item's symmetry allows.

        A grasp that fails (the pads close on nothing, the item slips out on the lift) is
        tried again while the item is still on the station, PICK_ATTEMPTS in all.

        Raises:
            GraspLost: (stage "grasp") every attempt failed, or the item left the station.
            IKFailed: no configuration reaches over the item.
        """
        for attempt in range(1, PICK_ATTEMPTS + 1):
            try:
                return self._pick_once(obj, item, stroke, heading, signed)
            except GraspLost as exc:
                self.ee.let_go()
                self.scene.run_for(0.1)  # the fingers open
                self._wait_at_rest(item)
                if attempt == PICK_ATTEMPTS or not self.scene.on_station(item):
                    raise GraspLost(
                        f"{exc} (pick attempt {attempt} of {PICK_ATTEMPTS})", "grasp"
                    ) from exc
                log.info("pick of %s failed (%s): trying again", obj.name or obj.shape, exc)
        raise AssertionError("unreachable")  # pragma: no cover

    def _pick_once(
        self, obj: ObjectParams, item: Any, stroke: float, heading: float, signed: bool
    ) -> np.ndarray:
        """One pick: over the item (as the plant reports it) with the pads open and the
        spool wound to `stroke`, a guarded descent until the grip touches it, the pads
        closed by contact, and the lift; GraspLost when it did not come up in the grip."""
        from cell.catalogue import pad_width_m
        from cell.frames import axis_frame

        opening = min(pad_width_m(obj) / 2 + FINGER_CLEARANCE_M, self.scene.geometry.finger_open_m)
        self.ee.open_for_pick(stroke, opening)
        p, elevation, azimuth, rolls, h_min = self._grip_plan(obj, item, heading, signed, opening)

        def at(h: float) -> np.ndarray:
            """Where the item's centre would sit in the grip with the carriage's face h out
            from its top along the approach axis (h_min at least: the pads clear the station)."""
            return p - axis_frame(elevation, azimuth)[:, 2] * max(h, h_min)

        q_high, roll = self._ik_grip_any(at(LIFT_M), stroke, obj, elevation, azimuth, rolls)
        q_near = self._ik_grip(at(APPROACH_M), stroke, obj, (elevation, azimuth, roll))
        self._move([q_high])
        # the carriage may still be on its way in from the last throw's end stop: the
        # grip goes down over the item only once it is at the stroke
        self.ee.wait_wound()
        self._move([q_near])
        # the item as the plant reports it now that it rests (a mesh may still have been
        # rocking when it was first seen): over it again if it moved, then a guarded
        # descent onto it
        self._wait_at_rest(item)
        if not self.scene.on_station(item):
            where = self.scene.item_position(item)
            raise GraspLost(
                f"{obj.name or obj.shape} is no longer on the pick station (its centre at "
                f"{', '.join(f'{v:.3f}' for v in where)} m)",
                "grasp",
            )
        aimed = (p, elevation, azimuth)
        p, elevation, azimuth, rolls, h_min = self._grip_plan(obj, item, heading, signed, opening)
        roll = min(rolls, key=lambda r: abs(math.remainder(r - roll, 2 * math.pi)))
        axes = (elevation, azimuth, roll)
        u0, u1 = (axis_frame(e, a)[:, 2] for e, a in (aimed[1:], axes[:2]))
        turned = math.acos(max(-1.0, min(1.0, float(u0 @ u1))))
        if np.linalg.norm(p - aimed[0]) > REPLAN_M or turned > REPLAN_RAD:
            q_over = self._ik_grip(at(APPROACH_M), stroke, obj, axes)
            if not np.allclose(q_over, self.q, atol=1e-6):
                self._move([q_over])
        q_from, q_to = self.q.copy(), self._ik_grip(at(-PRESS_M), stroke, obj, axes)
        depth = float(np.linalg.norm(self.robot.tcp_pose(q_to)[0] - self.robot.tcp_pose(q_from)[0]))

        def along(d: float) -> np.ndarray:
            """The configuration d [m] down the descent's (near-straight) joint segment."""
            return q_from + (q_to - q_from) * (d / depth)

        touched = self._straight(q_to, depth / DESCENT_MPS, lambda: self.scene.ee_touches(item))
        d_touch = touched * depth
        if touched < 1.0:
            # back to a hair over where it touched: the mount pulls E along behind the
            # flange (pressing on would squeeze the item onto the station with up to the
            # mount's force), and the item must be free to slide as the pads centre it
            d_touch -= float(np.linalg.norm(self.scene.ee_lag()))
            self._straight(along(max(0.0, d_touch - TOUCH_GAP_M)), 0.02)
        self.ee.close_on(item)
        self._carried = (obj, stroke)
        self._grip_stroke = stroke
        # a short lift that shows whether the pads hold it (the move on starts at LIFT_M)
        z0 = p[2]
        held = at(0.0)  # where the grip holds it: lifted straight up from there
        q_check = self._ik_grip(held + [0.0, 0.0, LIFT_CHECK_M], stroke, obj, axes)
        self._straight(q_check, LIFT_CHECK_S, smooth=True)
        self.scene.run_for(0.05)
        z1 = float(self.scene.item_position(item)[2])
        if not self.ee.holds_item() or z1 - z0 < LIFT_CHECK_M / 2:
            self.ee.item = None
            raise GraspLost(
                f"{obj.name or obj.shape} slipped out of the grip on the lift (its centre rose "
                f"{(z1 - z0) * 1000:.0f} mm of {LIFT_CHECK_M * 1000:.0f}; pads touching it: "
                f"{sorted(self.ee.pads_touching(item)) or 'none'})",
                "grasp",
            )
        return self._ik_grip(held + [0.0, 0.0, LIFT_M], stroke, obj, axes)

    def _carry_to_place(self, d: Decision, obj: ObjectParams, q_lift: np.ndarray) -> None:
        """Over the bin, then down into it on a short move of its own (a spline through
        both would cut the corner and sweep the item through the bin's wall)."""
        self._placing = True
        try:
            self._carry_to_spot(d, obj, q_lift)
        finally:
            self._placing = False

    def _carry_to_spot(self, d: Decision, obj: ObjectParams, q_lift: np.ndarray) -> None:
        from cell.endeffector.pybullet_backend import PLACE_OPENING_M

        sc = self.scene
        target = d.state["target"]
        # a spot on the bin's floor clear of what it holds (its centre while it is empty),
        # and of the walls by the pads that open beside the item (PLACE_OPENING_M) and 1 cm
        # (5 mm: an open pad still met a tote's wall as the grip rose out of it)
        g = sc.geometry
        pads = PLACE_OPENING_M + g.pad_thickness_m + 0.01
        # where the housing goes down below the rim (a deep bin), the walls kept as far
        # from it as well, 1 cm beyond the circle about its sides: its sides are wider
        # than the pads (random layout 17: seven items placed into a 0.25 m rim bin were
        # knocked out of the grip as the housing met the bin's walls)
        floor = sc.bin_spec(target.id).wall + obj.size[2] / 2 + PLACE_CLEARANCE_M
        at_floor = self._tcp_for_item_centre(np.array([0, 0, floor]), *GRIP_DOWN, d.stroke_m, obj)
        housing_low = self._housing_below_rim(at_floor[2], target)
        if housing_low:
            r_item = max(obj.size[0], obj.size[1]) / 2
            pads = max(pads, g.housing_radius_m + 0.01 - r_item)

        # the best spot the arm reaches over and down to, on one IK branch: the down pose
        # solved down the vertical from over the spot, each step from the one above
        # (`_down_vertical`; solved from where the arm is, the two came out 3.5 rad apart
        # on a UR5, random layout 11, and the line between them swept the grip through the
        # bin; solved from over the spot in one step, the demo's last teddy went down onto
        # a Panda branch 1.4-1.7 rad away in four joints: 1.2 s down, 2.0 s back up); the
        # next spot where the arm reaches none there
        def poses(spot: tuple[float, float, float], on_branch: bool) -> tuple[Any, ...]:
            sx, sy, surface_z = spot
            centre = np.array([sx, sy, obj.size[2] / 2 + PLACE_CLEARANCE_M + surface_z])
            above = centre + np.array([0, 0, max(LIFT_M, target.rim_height + 0.05)])
            q_above = self._ik_frame(self._tcp_for_item_centre(above, *GRIP_DOWN, d.stroke_m, obj))
            tcp_down = self._tcp_for_item_centre(centre, *GRIP_DOWN, d.stroke_m, obj)
            if not on_branch:
                return centre, q_above, self._ik_frame(tcp_down)
            return centre, q_above, self._down_vertical(q_above, tcp_down)[-1]

        spots = place_spots(sc, target.id, obj, wall_margin_m=pads)
        for spot in self._spots_to_try(spots, sc.bin_spec(target.id).wall):
            try:
                centre, q_above, q_down = poses(spot, on_branch=True)
                break
            except IKFailed:
                log.info("place: no IK at the spot (%.3f, %.3f) m: the next spot", *spot[:2])
        else:  # none on one branch: the first spot, each pose from where the arm is
            centre, q_above, q_down = poses(spots[0], on_branch=False)
        # where the housing goes below the rim, the vertical between them, through
        # configurations on it: a joint-space line between the two strays sideways, and
        # the housing met the bin's wall
        inner = self._vertical(q_above, q_down) if housing_low else []
        d.state["rise"] = [*inner[::-1], q_above]
        way = self._departure(q_lift, q_above)
        bottom = centre[2] - obj.size[2] / 2  # the item's lowest point at the spot [m]
        # over the spot without stopping there, straight, or through the point where the
        # item's lowest point is DEPARTURE_CLEAR_M over the rim (the bins stand on the floor)
        mid = centre + np.array([0.0, 0.0, target.rim_height + DEPARTURE_CLEAR_M - bottom])
        for via in ([], [mid]):
            try:
                qs = [
                    self._ik_frame(
                        self._tcp_for_item_centre(v, *GRIP_DOWN, d.stroke_m, obj), q_above
                    )
                    for v in via
                ]
            except IKFailed:
                continue
            if self._descends_straight([self.q, *way, *qs, q_down], bottom, target, obj):
                log.debug("place: over the spot without stopping (%d via)", len(via))
                self._move([*way, *qs, q_down])
                break
        else:
            log.debug("place: stopping over the spot")
            self._move(way)
            self._move([*inner, q_down])
        d.state["q_above"] = q_above

    @staticmethod
    def _spots_to_try(
        spots: list[tuple[float, float, float]], floor_z: float
    ) -> list[tuple[float, float, float]]:
        """The place spots tried, in order: the best PLACE_SPOTS_TRIED (`place_spots`),
        then as many of the rest nearest the robot's base, those on the bin's floor
        first: a bin whose middle is beyond the arm's reach may have its near side within
        it (random layout 3's bin, 0.87 m from a UR5, whose TCP over it with a 200 mm bottle
        held down misses the centre by 40 mm; a Panda's 0.92 m out in layout 18 it does
        not reach anywhere: a place there still fails with IK)."""
        first = spots[:PLACE_SPOTS_TRIED]
        rest = sorted(
            spots[PLACE_SPOTS_TRIED:],
            key=lambda s: (s[2] > floor_z + 1e-6, math.hypot(s[0], s[1])),
        )
        return first + rest[:PLACE_SPOTS_TRIED]

    def _housing_below_rim(self, tcp_z: float, target: Any) -> bool:
        """Is the housing below the `target` bin's rim + 1 cm with the grip pointing down
        and the TCP at height tcp_z [m]?"""
        return tcp_z + self.scene.geometry.housing_to_tcp_m < target.rim_height + 0.01

    def _down_vertical(
        self, q_top: np.ndarray, p_bottom: np.ndarray, step_m: float = 0.04
    ) -> list[np.ndarray]:
        """Configurations, grip pointing down, on the vertical line from q_top's TCP
        [rad] down to p_bottom [m, W] (which shares its x and y), every `step_m` [m] or
        less, each solved from the one above: q_top's end excluded, p_bottom's the last.
        IKFailed where IK fails on the way."""
        p0 = self.robot.tcp_pose(q_top)[0]
        k = max(1, math.ceil(float(np.linalg.norm(p_bottom - p0)) / step_m))
        out: list[np.ndarray] = []
        seed = q_top
        for i in range(1, k + 1):
            seed = self._ik_frame(p0 + (p_bottom - p0) * i / k, seed)
            out.append(seed)
        return out

    def _vertical(
        self, q_top: np.ndarray, q_bottom: np.ndarray, step_m: float = 0.04
    ) -> list[np.ndarray]:
        """Configurations, grip pointing down, on the vertical line between the TCPs of
        q_top and q_bottom [rad] (which share x and y), every `step_m` [m] or less, ends
        excluded, each solved from the one above (`_down_vertical`); none where IK fails
        on the way (the line between the ends is then used)."""
        try:
            return self._down_vertical(q_top, self.robot.tcp_pose(q_bottom)[0], step_m)[:-1]
        except IKFailed:
            return []

    def _descends_straight(
        self,
        waypoints: list[np.ndarray],
        bottom_z: float,
        target: Any,
        obj: ObjectParams,
        n: int = 400,
    ) -> bool:
        """May a place's carry pass over its spot without stopping? The spline through
        `waypoints` (ending at the spot, the item's lowest point then at bottom_z [m]) must
        stay within the joint limits, never dip below its end, and, wherever the item's
        lowest point is below DEPARTURE_CLEAR_M over the rim of the `target` bin, keep the
        grip (the item's footprint, and the open pads' reach) as far from the bin's walls,
        and the item as far from what the bin already holds, as the spot does (or 1 cm),
        though it cuts the corner the stop over the spot makes."""
        sc = self.scene
        spec = sc.bin_spec(target.id)
        r_item = max(obj.size[0], obj.size[1]) / 2
        r_grip = max(r_item, self._grip_reach_m())
        held = [
            (np.asarray(sc.item_position(it), float)[:2], max(it.obj.size) / 2)
            for it in sc.kept_items(target.id)
        ]

        r_housing = sc.geometry.housing_radius_m

        def clearance(p: np.ndarray) -> float:
            x, y = np.abs(spec.to_local(p[:2].tolist()))
            r = r_grip
            if self._housing_below_rim(p[2], target):  # the housing too
                r = max(r, r_housing)
            walls = min(spec.size_xy[0] / 2 - x, spec.size_xy[1] / 2 - y) - r
            items = min(
                (float(np.linalg.norm(p[:2] - c)) - rc - r_item for c, rc in held), default=1.0
            )
            return float(min(walls, items))

        qs = self._spline_within_limits(waypoints, n)
        if qs is None:
            return False
        end = self.robot.tcp_pose(qs[-1])[0]
        need = min(clearance(end), 0.01) - 1e-3
        for q in qs:
            p = self.robot.tcp_pose(q)[0]
            dz = p[2] - end[2]
            if dz < -1e-3:
                return False
            if bottom_z + dz < target.rim_height + DEPARTURE_CLEAR_M and clearance(p) < need:
                return False
        return True

    def _check_held(self, obj: ObjectParams) -> None:
        """GraspLost when the item is no longer between the pads at the release pose."""
        if not self.ee.holds_item():
            raise GraspLost(
                f"{obj.name or obj.shape} left the grip while carried (mass "
                f"{obj.mass * 1000:.0f} g, width {obj.width * 1000:.0f} mm)",
                "carry",
            )

    def _plan(
        self, obj: ObjectParams, target: Any, index: int, stroke_max_m: float = math.inf
    ) -> tuple[Any, float]:
        """The throw plan to a bin (and the learned ΔL_s) whose release pose the arm
        reaches (its configuration is kept for the throw), or UnreachableTarget / IKFailed.

        With `turn_release`, planned twice (`_plan_facing`): with the arm facing the bin at
        the release, and turned from it toward the pick station (`_facing_toward_station`),
        the throw axis still on the bin; the one whose cycle estimate (`_release_q`) is the
        shorter is kept, the first where there is no estimate to compare.
        """
        # the bin's centre, or a point of it clear of what the bin holds: the same for
        # every bounds tried (the scene does not move meanwhile)
        goal = (*throw_spot(self.scene, target.id, obj), target.rim_height)
        self._goal = np.asarray(goal, float)  # where it should cross the rim plane
        err: CellError | None = None
        best: tuple[Any, ...] | None = None
        turned = self._facing_toward_station(target)
        for facing in (None,) if turned is None else (None, turned):
            try:
                plan, delta, cost = self._plan_facing(
                    obj, goal, target, index, stroke_max_m, facing
                )
            except (UnreachableTarget, IKFailed) as exc:
                err = err or exc
                continue
            log.debug("facing %s: (slips, cycle estimate) %s", facing, cost)
            if best is not None and (cost is None or best[0] is None or not cost < best[0]):
                continue
            best = (cost, plan, delta, self._q_release, self.bounds_now, self._aim, self._model_obj)
            if cost is None:  # nothing to compare by: the arm faces the bin
                break
        if best is None:
            assert err is not None
            raise err
        _, plan, delta, self._q_release, self.bounds_now, aim, model_obj = best
        self._aim, self._model_obj = aim, model_obj
        return plan, delta

    def _facing_toward_station(self, target: Any) -> float | None:
        """The azimuth [rad, W] the arm faces at a throw's release if it turns from the
        bin toward the pick station (both the carry and the next approach then turn the
        arm that much less), or None: without `turn_release`, or for a bin less than
        FACE_MIN_OFF_RAD round from the station. From 70° while the turn was compared by
        the cycle estimate without `cycle_search`: that erred by more than a small turn
        saves (the demo's bins, 28–64° round, went from 1,529 to 1,490 items per hour with
        it). With the search timing both as the cell makes them, from 30° (README, "The
        defaults": over the 20 random layouts 1,474 -> 1,507 items per hour with the rise
        out of the station to 2 cm as well).

        The release point is `release_radius` r from the base along the azimuth faced,
        so turning it by Δ from the bin at distance d lengthens the throw from d − r to
        √(r² + d² − 2rd·cos Δ). A longer throw lands faster and bounces out of a low rim
        more: turned up to 90°, items that landed within 0.02 m of their aim came to
        rest outside (random layout 16: six 60 mm cylinders out of a 55 mm rim bin 1.4 m
        away, the throw 46 % longer). So Δ is at most FACE_TURN_MAX_RAD and what keeps
        the throw within FACE_THROW_STRETCH of the bin-facing one's: small for a bin near
        the base, large for one far out."""
        if not self.turn_release:
            return None
        sx, sy = self.scene.pick_station_xy
        tx, ty = (float(v) for v in target.position[:2])
        phi = math.atan2(ty, tx)
        off = math.atan2(sy, sx) - phi
        lim = self.robot.limits
        if lim.upper[0] - lim.lower[0] >= 2.0 * math.pi:  # the UR5's: the shorter way round
            off = math.remainder(off, 2.0 * math.pi)
        # else not across ±180°: the Panda's first joint stops at ±166°, so from a bin at
        # 150° the way to a station at -42° is down through 0°
        r, d = self.bounds.release_radius, math.hypot(tx, ty)
        if abs(off) < FACE_MIN_OFF_RAD or d <= r:
            return None
        longest = FACE_THROW_STRETCH * (d - r)
        turn = math.acos(max(-1.0, min(1.0, (r * r + d * d - longest**2) / (2.0 * r * d))))
        turn = min(turn, FACE_TURN_MAX_RAD)
        if turn < 1e-3:
            return None
        return phi + _clip(off, turn)

    def _plan_facing(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        target: Any,
        index: int,
        stroke_max_m: float,
        facing: float | None,
    ) -> tuple[Any, float, tuple[bool, float] | None]:
        """`_plan` with the arm facing `facing` [rad, W] at the release (None: the bin), and
        the release's cycle estimate (`_release_q`; None where none was made).

        The plan is made in the cell's release bounds; where IK finds no configuration for
        its release pose, again with the release lower and the throw axis flatter
        (RELEASE_FALLBACKS): the arm cannot point steeply up at shoulder height close to
        its base. With `cycle_search`, in all of these, the sooner kept
        (`_soonest_release`): a lower release can be nearer the pick. Random layout 11's
        three eggs took up to 8.6 s a cycle released in the cell's bounds, 2.48 s each
        released lower, where the carry's grip bound is far less tight. Where none of these
        is reached, the plan is made in a smaller release box (RELEASE_BOX_SHRINKS), the
        first reached kept.
        """
        from dataclasses import replace as dc_replace

        err: CellError | None = None
        ordinary, shrunk = self._release_bounds(target)
        for tier in (ordinary, shrunk):
            found: list[_Release] = []
            for bounds in tier:
                if found and (tier is shrunk or not self.cycle_search):
                    break  # the first reached is kept
                try:
                    found.append(
                        self._plan_in(
                            obj,
                            goal,
                            index,
                            stroke_max_m,
                            dc_replace(bounds, facing_rad=facing),
                            self._beat(found),
                        )
                    )
                except (UnreachableTarget, IKFailed) as exc:
                    err = err or exc
            if found:
                r = self._soonest_release(obj, found)
                self._q_release, self.bounds_now = r.q_release, r.bounds
                self._aim, self._model_obj = r.aim, r.model_obj
                return r.plan, r.delta, r.cost
        assert err is not None
        raise err

    def _plan_in(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        index: int,
        stroke_max_m: float,
        bounds: Any,
        beat: float | None = None,
    ) -> _Release:
        """The throw's plan in release `bounds` and its release (`_release_q`, which need
        not time a release whose cycle cannot beat `beat` [s]): steep enough for the grip
        to hold the item at its release first; where the arm reaches no such release, as
        the bounds are (`_steep_enough`). UnreachableTarget or IKFailed."""
        err: IKFailed | None = None
        for steep in (True, False):
            self.bounds_now = bounds
            self._steepened = False
            plan, delta = self._plan_once(obj, goal, index, stroke_max_m, steep)
            stroke = plan.stroke_m + delta
            centre = np.array([plan.x_m, plan.y_m, plan.z_m])
            try:
                q_release, cost = self._release_q(
                    self._tcp_for_item_centre(
                        centre, plan.elevation_rad, plan.azimuth_rad, stroke, obj
                    ),
                    plan,
                    stroke,
                    obj,
                    beat,
                )
            except IKFailed as exc:
                err = err or exc
                if not self._steepened:
                    break
                continue
            return _Release(cost, plan, delta, q_release, bounds, self._aim, self._model_obj)
        assert err is not None
        raise err

    @staticmethod
    def _soonest_of(found: list[_Release]) -> _Release:
        """Of the plans `found` in the release bounds in `_release_bounds`' order, the
        first, unless a later one's cycle estimate is sooner and its route asks no more of
        the grip than the first's; the first where an estimate is missing."""
        first = best = found[0]
        for r in found[1:]:
            if first.cost is None or r.cost is None or best.cost is None:
                continue
            if r.cost[0] <= first.cost[0] and r.cost < best.cost:
                best = r
        return best

    def _beat(self, found: list[_Release]) -> float | None:
        """The cycle estimate [s] a plan in the next release bounds must beat to be kept
        (`_soonest_of` of the plans `found` so far), where one that asks no more of the
        grip than it holds has it; None (nothing to beat: every release is timed) without
        `cycle_search`, or where there is none."""
        if not self.cycle_search or not found or found[0].cost is None:
            return None
        cost = self._soonest_of(found).cost
        return None if cost is None or cost[0] else cost[1]

    @classmethod
    def _soonest_release(cls, obj: ObjectParams, found: list[_Release]) -> _Release:
        """`_soonest_of` the plans `found`, logged where it is not the first."""
        first, best = found[0], cls._soonest_of(found)
        if best is not first:
            log.info(
                "%s: released %.2f m high, %.2f s sooner a cycle than in the cell's bounds",
                obj.name or obj.shape,
                best.plan.z_m,
                first.cost[1] - best.cost[1],  # type: ignore[index]
            )
        return best

    def _release_q(
        self,
        tcp: np.ndarray,
        plan: Any,
        stroke: float,
        obj: ObjectParams,
        beat: float | None = None,
    ) -> tuple[np.ndarray, tuple[bool, float] | None]:
        """The release configuration for a throw's `plan` at `tcp` [m, W], and its cycle
        estimate (None where none was made; `_plan` compares facings by it): of the two rolls
        that put the item's weight on a pad (0 and π, `solve_release_ik`), the one whose
        cycle estimate is the shorter (`_release_costs`). The pick is
        gripped at the release's roll (`_pick_frame`), so the roll chooses the pick's,
        the lift's and the swing's configurations too. Each roll's release is solved from
        the lift and from where the arm is (IK keeps the solution nearest its seed: two
        branches, the second the one `solve_release_ik` gives; with `cycle_search` from
        the pick too). Where no item is
        presented, or no candidate's moves are found, the roll nearer where the arm is
        (`solve_release_ik`); so too with the physical pick, which grips the item as it
        lies, headed by the release's roll (`_carry_heading`), not in the frame timed
        here: on the UR5 copy of the demo the roll chosen so cost four grasps (19/24 in
        bin against 23/24). A release whose route would ask more of the grip than it must
        (`_release_costs`: a tall item's swing that rolls the grip) ranks after the others.
        With `cycle_search`, the candidates are timed as the cell makes the cycle, soonest
        bound first, and `beat` [s] is a cycle estimate another release bounds' plan has
        (`_release_search`). IKFailed when the pose has no configuration."""
        from cell.robot.ik import WEIGHT_ROLLS_RAD

        e, a = plan.elevation_rad, plan.azimuth_rad
        best: tuple[tuple[bool, float], np.ndarray] | None = None
        if self._presented is not None and self.pick_mode != "physical" and abs(math.cos(e)) > 1e-6:
            kept = self._frame
            try:
                if self.cycle_search:
                    best = self._release_search(tcp, plan, stroke, obj, beat)
                else:
                    for roll in WEIGHT_ROLLS_RAD:
                        self._frame = (float(a), roll)  # the pick is gripped at this roll
                        for cost, q_rel in self._release_costs(tcp, plan, roll, stroke, obj):
                            log.debug("release roll %.2f rad: (slips, estimate) %s", roll, cost)
                            if best is None or cost < best[0]:
                                best = (cost, q_rel)
            finally:
                self._frame = kept
        if best is not None:
            return best[1], best[0]
        return self._ik(tcp, e, a), None

    def _release_search(
        self, tcp: np.ndarray, plan: Any, stroke: float, obj: ObjectParams, beat: float | None
    ) -> tuple[tuple[bool, float], np.ndarray] | None:
        """`_release_q` with `cycle_search`: ((asks more of the grip than it holds, cycle
        estimate [s]), release configuration) of the soonest release at either roll, or
        None where none is found. IK is seeded from the lift, from where the arm is and
        from the pick (the configuration a carry solved again from the pick would go to);
        the estimate is the item's pick-to-pick cycle as the cell makes it
        (`_static_cycle_s`) plus APPROACH_WEIGHT of the approach from where the arm is;
        a release whose route would ask more of the grip than it holds (`_swing_holds`)
        ranks after every one that does not, as in `_release_costs`.

        Every candidate (both rolls, each seed's IK) is bounded first (`_cycle_bound_s`
        plus APPROACH_WEIGHT of the approach) and timed in ascending order of that bound:
        the soonest found early, a candidate whose bound cannot beat it (nor `beat` [s], a
        cycle another release bounds' plan already has, `_plan_facing`) is not timed, nor
        is any after it. Where candidates were left out so and none timed is found, the
        first one's configuration with the estimate (False, ∞): it cannot be chosen
        (`_soonest_release`). Ties go to the candidate first in the rolls' order
        (WEIGHT_ROLLS_RAD) and then the seeds', so the choice is the one the search timing
        every candidate makes (tests/test_release_search_cost.py)."""
        from cell.robot.ik import WEIGHT_ROLLS_RAD, ReleasePose

        level = self._turns_if_rolled(obj, stroke)
        a = float(plan.azimuth_rad)
        # (lower bound on the estimate [s], order, roll, release, (pick, lift), approach [s])
        found: list[tuple[float, int, float, np.ndarray, Any, float]] = []
        for roll in WEIGHT_ROLLS_RAD:
            self._frame = (a, roll)  # the pick is gripped at this roll
            try:
                over = self._over_item(self._presented, stroke, obj)
                t_approach = self._approach_s(self.q, over, stroke, obj)
            except (IKFailed, TrajectoryError):
                continue
            pose = ReleasePose.from_angles(tcp, plan.elevation_rad, a, roll)
            mine: list[np.ndarray] = []
            for seed in (over[1], self.q, over[0]):
                try:
                    q_rel = self._release_ik(self.robot, pose, seed).q
                except IKFailed:
                    continue
                if any(joint_gap(q_rel, q) < 1e-3 for q in mine):
                    continue
                mine.append(q_rel)
                low = self._cycle_bound_s(over[0], q_rel) + APPROACH_WEIGHT * t_approach
                found.append((low, len(found), roll, q_rel, over, t_approach))
        best: tuple[tuple[tuple[bool, float], int], np.ndarray] | None = None
        soonest = math.inf if beat is None else beat
        pruned = False
        for low, order, roll, q_rel, over, t_approach in sorted(found, key=lambda c: c[:2]):
            if low >= soonest:
                pruned = True
                break  # nor can any after it
            self._frame = (a, roll)
            try:
                way = self._swing(over[1], q_rel, plan, (obj, stroke)) if level else []
                t_cycle = self._static_cycle_s(obj, plan, stroke, q_rel, over)
            except (IKFailed, TrajectoryError):
                continue
            t = t_cycle + APPROACH_WEIGHT * t_approach
            slips = level and not self._swing_holds(
                [over[1], *way, q_rel], (obj, stroke), plan.elevation_rad
            )
            log.debug("release roll %.2f rad: (slips, cycle estimate) (%s, %.3f)", roll, slips, t)
            if best is None or ((slips, t), order) < best[0]:
                best = (((slips, t), order), q_rel)
            if not slips:
                soonest = min(soonest, t)
        if best is not None:
            return best[0][0], best[1]
        if pruned:
            return (False, math.inf), found[0][3]
        return None

    def _release_costs(
        self, tcp: np.ndarray, plan: Any, roll: float, stroke: float, obj: ObjectParams
    ) -> list[tuple[tuple[bool, float], np.ndarray]]:
        """((asks more of the grip than it holds, cycle estimate [s]), release
        configuration) of each release at `roll` [rad] (`_release_q` without
        `cycle_search`; with it, `_release_search`), with the pick in the frame
        `self._frame`; none when the pick, the approach, the release or the carry is not
        found. A carry whose route, held still anywhere, would ask more of the grip than
        the carry's bound (`_swing_holds`: a tall item on a swing that rolls the grip)
        ranks after every one that does not. IK is seeded from the lift and from where the
        arm is, and keeps the solution nearest its seed.

        The estimate: the empty arm to the pick of the presented item (as `_approach_s`
        times it), plus twice the carry from its lift along the twist-free swing to the
        release, timed as `_move_plan` times a carry of this item (the next approach
        comes back about as far; with `turn_release`, the empty arm's way back from the
        release to the same pick instead: a release turned toward the station winds the
        wrist round, and the way back unwinds it)."""
        from cell.robot.ik import ReleasePose

        try:
            q_pick, q_lift = self._over_item(self._presented, stroke, obj)
            t_approach = self._approach_s(self.q, (q_pick, q_lift), stroke, obj)
        except (IKFailed, TrajectoryError):
            return []
        pose = ReleasePose.from_angles(tcp, plan.elevation_rad, plan.azimuth_rad, roll)
        out: list[tuple[tuple[bool, float], np.ndarray]] = []
        level = self._turns_if_rolled(obj, stroke)
        for seed in (q_lift, self.q):
            try:
                q_rel = self._release_ik(self.robot, pose, seed).q
                if any(joint_gap(q_rel, q) < 1e-3 for _, q in out):
                    continue
                way = self._swing(q_lift, q_rel, plan, (obj, stroke))
                carry = self._move_plan(q_lift, [*way, q_rel], SETTLE_S, (obj, stroke))
                t_carry = _plan_time(carry, SETTLE_S)
                t_back = t_carry
                if self.turn_release:
                    t_back = self._approach_s(q_rel, (q_pick, q_lift), stroke, obj)
                t = t_approach + t_carry + t_back
            except (IKFailed, TrajectoryError):
                continue
            slips = level and not self._swing_holds(
                [q_lift, *way, q_rel], (obj, stroke), plan.elevation_rad
            )
            out.append(((slips, t), q_rel))
        return out

    def _cycle_bound_s(self, q_pick: np.ndarray, q_rel: np.ndarray) -> float:
        """A lower bound [s] on `_static_cycle_s` for the release q_rel [rad] of the item
        picked at q_pick [rad]: each way, from rest to rest, no joint can be quicker than
        at its full velocity and acceleration limits along the straight line (the
        bang-bang time; the carry's and the approach's limits are these or a fraction of
        them, their routes no shorter), plus the settle at the release and the push."""
        from cell.robot.moving_release import COAST_S

        lim = self.robot.limits
        v, a = lim.velocity * (1 + 1e-3), lim.acceleration * (1 + 1e-3)
        d = np.abs(np.asarray(q_rel, float) - np.asarray(q_pick, float))
        t = np.where(d <= v * v / a, 2.0 * np.sqrt(d / a), d / v + v / a)
        return 2.0 * float(np.max(t)) + SETTLE_S + COAST_S

    def _approach_s(
        self,
        q_from: np.ndarray,
        over: tuple[np.ndarray, np.ndarray],
        stroke: float,
        obj: ObjectParams,
    ) -> float:
        """How long [s] the empty arm takes from rest at q_from [rad] to the pick of the
        presented item, `over` its (pick, lift) configurations: without stopping over it
        (`_approach_plan`), else through the lift (`_pick_kinematic`; jerk-limited
        rest-to-rest moves at the full limits, `move_time`). TrajectoryError or IKFailed
        where neither is found."""
        from cell.robot.motion import move_time

        q_pick, q_lift = over
        key = (
            *(np.asarray(q, float).tobytes() for q in (q_from, q_pick, q_lift)),
            self.scene.item_position(self._presented).tobytes(),
            stroke,
            obj,
            self._frame,
        )
        if key in self._approach_memo:  # until the next decision, as `_solve_ik`
            return self._approach_memo[key]
        approach, _ = self._approach_plan(self._presented, stroke, obj, q_pick, q_from)
        if approach is not None:
            t = float(approach.duration)
        else:
            t = move_time(q_from, q_lift, self.robot) + move_time(q_lift, q_pick, self.robot)
        self._approach_memo[key] = t
        return t

    def _release_bounds(self, target: Any) -> tuple[list[Any], list[Any]]:
        """The release bounds a plan is made in (`_plan_facing`): the cell's, then lower
        and flatter (RELEASE_FALLBACKS); and each of those in a release box shrunk about
        its centre (each of RELEASE_BOX_SHRINKS in turn), tried where none of the first is
        reached. One that would leave no elevation range is skipped.

        Tried and left out: into a bin with a low rim (0.05 m), steep throws first
        (elevation ≥ 50°): of 10 throws of 5 objects, 4 landed against 8 with the least
        energy throw (a cube slides out either way, coming down at 49° or at 52°). Nor
        does aiming short of the centre help: with the aim half-way to the near wall, 138
        of 168 throws into 0.05 and 0.08 m rims 1.3-2.7 m out stayed in, against 139
        aimed at the centre (a 50 mm cube slides out of half of them either way)."""
        from dataclasses import replace as dc_replace

        b = self.bounds
        ordinary = [b] + [
            dc_replace(b, elevation_max=min(b.elevation_max, e_max), release_height=h)
            for e_max, h in RELEASE_FALLBACKS
        ]
        lo, hi = np.asarray(b.position_min, float), np.asarray(b.position_max, float)
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        inner = [
            dc_replace(x, position_min=tuple(mid - k * half), position_max=tuple(mid + k * half))
            for k in RELEASE_BOX_SHRINKS
            for x in ordinary
        ]
        return (
            [x for x in ordinary if x.elevation_min <= x.elevation_max],
            [x for x in inner if x.elevation_min <= x.elevation_max],
        )

    def _plan_once(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        index: int,
        stroke_max_m: float,
        steep: bool = True,
    ) -> tuple[Any, float]:
        # Identified η_o where the parameter file has them (seen objects), else the
        # catalogue's; with a residual, only those the residual was trained with, so
        # that L_s + ΔL_s means what it meant in training.
        use_identified = self.residual is None or obj.name in self.residual.identified_objects
        model_obj = self.params.model_object(obj) if use_identified else obj
        self._model_obj = model_obj  # what the plan assumed (for an observer)
        bounds = self.bounds_now
        plan = plan_clean(self.params, obj, model_obj, goal, bounds)
        if plan.stroke_m > stroke_max_m:  # the grip would not hold it there: plan within it
            bounds = grip_bounds(bounds, self.params, stroke_max_m, obj.name or obj.shape)
            plan = plan_clean(self.params, obj, model_obj, goal, bounds)
        if steep:
            plan, bounds = self._steep_enough(obj, model_obj, goal, plan, bounds)
        self._aim = np.asarray(goal, float)
        if self.learn:
            aim = self._corrected_aim(obj, plan, np.asarray(goal, float))
            if aim is not None:
                try:
                    plan = plan_clean(self.params, obj, model_obj, tuple(aim), bounds)
                    self._aim = aim
                except UnreachableTarget:
                    log.info(
                        "learned aim for %s is out of reach: the model's aim is kept", obj.name
                    )
        if self.residual is None:
            return plan, 0.0
        from cell.residual.model import residual_for_plan

        corrected = residual_for_plan(self.residual, obj, plan)  # clipping is logged there
        return plan, corrected.stroke_m - plan.stroke_m

    def _steep_enough(
        self, obj: ObjectParams, model_obj: ObjectParams, goal: Any, plan: Any, bounds: Any
    ) -> tuple[Any, Any]:
        """The plan, re-planned with its elevation raised where holding the item still at
        its release would ask more of the grip than a carry may (`release_elevation_min`:
        a tall item whose weight on a pad tilts it out, a 200 mm bottle below 37° at a
        58 mm stroke), and the bounds it was planned in. Up to three times, as the stroke
        of the steeper plan changes the grip; the plan kept when no steeper one reaches
        the goal."""
        from dataclasses import replace as dc_replace

        for _ in range(3):
            e_min = release_elevation_min(
                self.params, obj, plan.stroke_m, plan.elevation_rad, bounds.elevation_max
            )
            if e_min is None:
                break
            steep = dc_replace(bounds, elevation_min=max(bounds.elevation_min, e_min))
            try:
                plan, bounds = plan_clean(self.params, obj, model_obj, goal, steep), steep
                self._steepened = True
            except UnreachableTarget:
                log.info("%s: no release steep enough for the grip reaches the goal", obj.name)
                break
            log.info(
                "%s: released at %.0f° or steeper so the grip holds it still there",
                obj.name or obj.shape,
                math.degrees(e_min),
            )
        return plan, bounds

    # -- the flywheel ------------------------------------------------------------
    @staticmethod
    def _class_key(obj: ObjectParams) -> str:
        return f"class:{obj.shape}"

    def _corrected_aim(self, obj: ObjectParams, plan: Any, goal: np.ndarray) -> np.ndarray | None:
        """The aim point that the object's (or its class's) correction asks for, or None."""
        own = self.corrections.get(obj.name or "")
        if own is not None and own.n:
            lr = _clip(own.log_ratio, LEARN_MAX_LOG_RATIO)
            turn = _clip(own.turn_rad, LEARN_MAX_TURN_RAD)
        else:
            cls = self.corrections.get(self._class_key(obj))
            if cls is None or not cls.n:
                return None
            lr = _clip(cls.log_ratio, LEARN_CLASS_MAX_LOG_RATIO)
            turn = _clip(cls.turn_rad, LEARN_CLASS_MAX_TURN_RAD)
        p0 = np.array([plan.x_m, plan.y_m])
        v = goal[:2] - p0
        c, s = math.cos(-turn), math.sin(-turn)
        v = np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]]) / math.exp(lr)
        return np.array([*(p0 + v), goal[2]])

    def _learn_from(self, obj: ObjectParams, plan: Any, cross: Any, aim: np.ndarray) -> None:
        """Average this landing (aimed at `aim`) into the object's and its class's
        corrections."""
        p0 = np.array([plan.x_m, plan.y_m])
        aimed = aim[:2] - p0
        seen = np.asarray(cross[:2], float) - p0
        ra, rs = float(np.hypot(*aimed)), float(np.hypot(*seen))
        if ra < 0.05 or rs < 0.05:
            return  # too short a throw to say anything about its reach
        lr = math.log(rs / ra)
        turn = math.atan2(aimed[0] * seen[1] - aimed[1] * seen[0], float(aimed @ seen))
        for key in (obj.name or "", self._class_key(obj)):
            self.corrections.setdefault(key, LandingCorrection()).add(lr, turn)

    def close(self) -> None:
        """Close the scene and any hardware end-effector."""
        self.scene.close()
        self.effector.close()
