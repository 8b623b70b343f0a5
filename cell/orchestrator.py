"""The sort loop: pick, decide, plan, move, release, observe, record.

For each item of a job the orchestrator spawns it at the pick station, moves
the arm over it (Pinocchio IK + a toppra path), grasps it, decides to place
(bin within reach) or throw (beyond), plans the release (throw optimisation
plus the learned ΔL_s when a residual model is given), moves to the release
configuration (toppra through pick → lift → release), commands the
end-effector, watches the item to rest in the PyBullet plant, scores it and
appends the throw to the log store, each in its own transaction.

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
import time
import uuid
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from cell.errors import (
    CannotGrip,
    CellError,
    GraspLost,
    HardwareError,
    IKFailed,
    TrajectoryError,
    UnreachableTarget,
)
from cell.jobs import ItemSpec, Job
from cell.log.records import throw_record
from cell.model.objects import ObjectParams
from cell.params import ModelParams, load_params

__all__ = [
    "FAILURES",
    "InFlight",
    "failure_of",
    "ItemResult",
    "RunSummary",
    "Orchestrator",
    "run_items",
    "sorted_throw_record",
    "summarise",
]

log = logging.getLogger(__name__)

PICK_STROKE_M = (
    0.045  # [m] stroke while carrying: grip force enough to hold items through arm moves
)
SWING_WAYPOINTS = 2  # waypoints that keep the carry's swing free of twist (see _swing)
SETTLE_S = 0.05  # [s] wait after a move so the end-effector and item come to rest
LIFT_M = 0.15  # [m] lift above the pick pose before moving to the release
PLACE_CLEARANCE_M = 0.02  # [m] item's lowest point above the bin floor when the place starts
ARM_SPEED_SCALE = 1.0  # fraction of the joint velocity/acceleration limits used


# Why an item did not end in its bin: one of these, always (ItemResult.failure).
FAILURES = (
    "unreachable",  # no release within the cell's bounds lands it in the bin
    "cannot_grip",  # too wide, too thin or too heavy for the pads, refused before the pick
    "grasp_failed",  # the fingers did not close on it
    "dropped_while_carried",  # it left the grip between the pick and the release
    "ik",  # no arm configuration or move reaches the planned pose
    "missed_bin",  # released, but it came to rest outside its bin
)


@dataclass
class InFlight:
    """A released item the loop is not waiting for: `score(outcome)` makes its
    ItemResult (and records the throw) once the plant says where it came to rest.

    Attributes:
        base: the result's index, object_id and target_bin.
        obj: the item's parameters.
        item: the scene's item.
        score: Outcome → (ItemResult, landing point [m, W]).
    """

    base: dict[str, Any]
    obj: ObjectParams
    item: Any
    score: Callable[[Any], tuple[Any, Any]]

    @property
    def index(self) -> int:
        return int(self.base["index"])


def failure_of(exc: BaseException) -> str:
    """The FAILURES entry for an error that stopped an item before its release."""
    if isinstance(exc, UnreachableTarget):
        return "unreachable"
    if isinstance(exc, CannotGrip):
        return "cannot_grip"
    if isinstance(exc, GraspLost):
        return "grasp_failed" if exc.stage == "grasp" else "dropped_while_carried"
    if isinstance(exc, (IKFailed, TrajectoryError)):
        return "ik"
    return "missed_bin"


@dataclass(frozen=True)
class ItemResult:
    """What became of one item.

    Attributes:
        index: item number in the job (0-based).
        object_id: catalogue id (or ad-hoc name).
        target_bin: where the job wanted it.
        action: "place", "throw" or "failed".
        failure: why it is not in its bin, one of FAILURES ("" when it is).
        reason: the full message of that failure ("" when there is none).
        bin_id: the bin it came to rest in ("" for none).
        in_bin: True when that is the target bin.
        landing_error_m: throws: distance of the crossing of the rim plane from the
            bin centre; places: distance of the rest point from the bin centre [m].
        stroke_m: commanded stroke at release [m] (NaN for failures before planning).
        delta_stroke_m: learned correction ΔL_s included in stroke_m [m].
        cycle_time_s: simulated arm time for this item [s].
        throw_id: the log id of the throw ("" for places and failures).
    """

    index: int
    object_id: str
    target_bin: str
    action: str
    failure: str = ""
    reason: str = ""
    bin_id: str = ""
    in_bin: bool = False
    landing_error_m: float = math.nan
    stroke_m: float = math.nan
    delta_stroke_m: float = 0.0
    cycle_time_s: float = 0.0
    throw_id: str = ""


@dataclass(frozen=True)
class RunSummary:
    """The closing table of a run (JSON keys as `cell run --json`)."""

    items: int
    placed: int
    thrown: int
    failed: int
    in_bin: int
    in_bin_rate: float
    mean_landing_error_m: float
    p95_landing_error_m: float
    mean_cycle_time_s: float
    items_per_hour: float
    sim_time_s: float
    wall_time_s: float
    results: list[ItemResult] = field(default_factory=list)
    failures: dict[str, int] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """Plain values, item results as a list of dicts."""
        d = asdict(self)
        d["results"] = [asdict(r) for r in self.results]
        return d


def summarise(results: list[ItemResult], wall_time_s: float) -> RunSummary:
    """The closing figures of a list of item results."""
    n = len(results)
    errs = np.array([r.landing_error_m for r in results if np.isfinite(r.landing_error_m)])
    cyc = np.array([r.cycle_time_s for r in results])
    sim_time = float(np.sum([r.cycle_time_s for r in results]))
    in_bin = sum(r.in_bin for r in results)
    return RunSummary(
        items=n,
        placed=sum(r.action == "place" for r in results),
        thrown=sum(r.action == "throw" for r in results),
        failed=sum(r.action == "failed" for r in results),
        in_bin=in_bin,
        in_bin_rate=in_bin / n if n else 0.0,
        mean_landing_error_m=float(errs.mean()) if errs.size else math.nan,
        p95_landing_error_m=float(np.percentile(errs, 95)) if errs.size else math.nan,
        mean_cycle_time_s=float(cyc.mean()) if cyc.size else math.nan,
        items_per_hour=3600.0 * in_bin / sim_time if sim_time > 0 else 0.0,
        sim_time_s=sim_time,
        wall_time_s=wall_time_s,
        results=list(results),
        failures={k: c for k in FAILURES if (c := sum(r.failure == k for r in results))},
    )


def sorted_throw_record(
    session: str,
    throw_id: str,
    obj: ObjectParams,
    plan: Any,
    stroke_m: float,
    released_at: np.ndarray,
    target: Any,
    out: Any,
    cross: Any,
    *,
    platform: str = "arm",
    rotor_rpm: float = 0.0,
) -> dict[str, Any]:
    """The throw-log row of a sort throw: the release as planned and observed, the
    crossing of the target bin's rim plane, and which bin it came to rest in (shared by
    the arm orchestrator and the platform runner)."""
    return throw_record(
        throw_id,
        obj,
        stroke_m=stroke_m,
        position_m=released_at,
        elevation_rad=plan.elevation_rad,
        azimuth_rad=plan.azimuth_rad,
        roll_rad=plan.roll_rad,
        base_velocity_mps=(plan.vx_mps, plan.vy_mps, plan.vz_mps),
        platform=platform,
        rotor_rpm=rotor_rpm,
        land_z_m=target.rim_height,
        landed_xy_m=cross[:2],
        session=session,
        time_s=time.time(),
        t_flight_s=float(cross[2]),
        target_bin=target.id,
        bin_id=out.bin_id or "",
    )


def missed_bin(bin_id: str | None, target_id: str, landing_error_m: float) -> tuple[str, str]:
    """(failure, reason) of a released item; both empty when it rests in its bin."""
    if bin_id == target_id:
        return "", ""
    where = f"in bin {bin_id!r}" if bin_id else "outside every bin"
    return (
        "missed_bin",
        f"came to rest {where}, not in {target_id!r} (landing error {landing_error_m:.3f} m)",
    )


def run_items(
    job: Job,
    run_item: Callable[[int, ItemSpec], ItemResult],
    on_item: Callable[[ItemResult], None] | None = None,
) -> RunSummary:
    """Run every item of a job through `run_item`, reporting each to `on_item`, and
    summarise (shared by the arm orchestrator and the platform runner)."""
    t_wall = time.perf_counter()
    results: list[ItemResult] = []
    for i, spec in enumerate(job.expanded_items()):
        res = run_item(i, spec)
        results.append(res)
        if on_item is not None:
            on_item(res)
    return summarise(results, time.perf_counter() - t_wall)


def as_gripped(obj: ObjectParams) -> ObjectParams:
    """The item as the pads see it: a mesh is as wide as it is where the pads meet it."""
    from dataclasses import replace as dc_replace

    from cell.catalogue import pad_width_m

    width = pad_width_m(obj)
    if width < obj.width:
        return dc_replace(obj, size=(width, *obj.size[1:]))
    return obj


def carry_hold(params: ModelParams, obj: ObjectParams, stroke_m: float) -> Any:
    """What the pads hold `obj` with at stroke L_s [m] (a `cell.robot.carry.GripHold`):
    the friction force of the grip model, the couple of the pads' contact patches (as
    long as the pads and the item overlap along the throw axis, as wide as both along
    y), and where the item's centre of mass sits above that patch."""
    from cell.model.grip import holding_mass_kg
    from cell.model.params import G
    from cell.robot.carry import GripHold, patch_torsion_radius_m
    from cell.sim import EE_TO_TCP_M
    from cell.sim.mechanism import DEFAULT_GEOMETRY as GEO

    gripped = as_gripped(obj)
    height = obj.size[2]
    length = min(GEO.pad_length_m, height)
    force = holding_mass_kg(params.ee, stroke_m, gripped.width) * G
    half_y = min(GEO.pad_half_width_m, obj.size[1] / 2)
    # a mesh meets the flat pads at points, not over a face: no couple to count on (a
    # duck pinched at its neck turned 110-130° in the pads while carried)
    radius = 0.0 if obj.shape == "mesh" else patch_torsion_radius_m(half_y, length / 2)
    return GripHold(
        force_n=force,
        torque_nm=force * radius,
        mass_kg=obj.mass,
        inertia_xx=float(obj.inertia[0]),
        offset_tcp_m=(0.0, 0.0, stroke_m + height / 2 - EE_TO_TCP_M),
        lever_m=(height - length) / 2,
        base_half_m=obj.size[1] / 2,
    )


def grip_stroke_limit(params: ModelParams, obj: ObjectParams) -> float:
    """The longest stroke [m] the pads hold `obj` at (cell.model.grip).

    Raises:
        CannotGrip: the item is too wide for the pads, or too heavy for its width at
            every stroke; the message says what the cell can hold instead.
    """
    from cell.model.grip import GRIP_SAFETY, holding_mass_kg, max_grip_stroke
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    ee = params.ee
    name = obj.name or obj.shape
    obj = as_gripped(obj)
    widest = 2 * DEFAULT_GEOMETRY.finger_open_m
    if obj.width > widest:
        raise CannotGrip(
            f"{name} is {obj.width * 1000:.0f} mm wide across the pads; they open to "
            f"{widest * 1000:.0f} mm: turn it so a narrower side faces the pads, or sort it by hand"
        )
    s_max = max_grip_stroke(ee, obj)
    if s_max is None:
        hold = holding_mass_kg(ee, ee.stroke_min, obj.width) / GRIP_SAFETY
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
        raise CannotGrip(
            f"{name} ({obj.mass * 1000:.0f} g, {obj.width * 1000:.0f} mm across the pads) "
            f"cannot be held: {why}; grip it across a wider side, or sort it by hand"
        )
    return s_max


def grip_bounds(bounds: Any, params: ModelParams, stroke_max_m: float) -> Any:
    """`bounds` with the stroke capped at what the grip holds the item at [m]."""
    from dataclasses import replace as dc_replace

    lo = params.ee.stroke_min if bounds.stroke_min is None else bounds.stroke_min
    return dc_replace(bounds, stroke_min=lo, stroke_max=min(stroke_max_m, params.ee.stroke_max))


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
    from cell.optimize.plan import plan_facing

    s_max = grip_stroke_limit(params, obj)
    dist = math.hypot(*bin_spec.position)
    if policy == "place" or (policy == "auto" and dist <= place_reach_m):
        return
    b = bounds or ThrowBounds()
    if b.stroke_max is None or s_max < b.stroke_max:
        b = grip_bounds(b, params, s_max)
    goal = (*bin_spec.position, bin_spec.rim_height)
    plan_facing(params.model_object(obj), goal, params.ee, b)


def scene_params_path() -> str | None:
    """The scene's calibrated parameter file (robots/cell_scene/ee_params.yaml), if present."""
    from cell.robot.paths import robots_dir

    p = robots_dir() / "cell_scene" / "ee_params.yaml"
    return str(p) if p.is_file() else None


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
        learn: correct the planner from each observed landing (the flywheel): an
            object's next throw aims where its earlier landings say it must
            (LandingCorrection), and an object never thrown before takes its
            class's (shape's) correction, bounded more tightly.
        speed_scale: fraction of the joint velocity and acceleration limits the arm's
            moves use, in (0, 1] (a carry may go slower, as its grip allows).
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
    ) -> None:
        from cell.endeffector.pybullet_backend import PyBulletEndEffector
        from cell.optimize.bounds import ThrowBounds
        from cell.robot.model import load_robot
        from cell.sim import BinSpec, CellScene

        if not (0.0 < speed_scale <= 1.0):
            from cell.errors import InvalidInput

            raise InvalidInput(f"speed_scale {speed_scale!r}: give a fraction in (0, 1]")
        self.speed_scale = float(speed_scale)
        self.job = job
        self.params = params or load_params(job.params or scene_params_path())
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
        self.ee = PyBulletEndEffector(self.scene)
        self.hardware = end_effector
        self.bounds = ThrowBounds()
        self.bounds_now = self.bounds  # the bounds of the plan being made (see _plan)
        self._q_release = np.zeros(0)
        self.residual = None
        if job.residual:
            from cell.residual.model import ResidualModel

            self.residual = ResidualModel.load(job.residual)
        self._check_job()
        self.q = np.asarray(self.scene.ready_q, float)
        self.rng = np.random.default_rng(job.seed)
        self.observer = observer
        self.learn = learn
        self.corrections: dict[str, LandingCorrection] = {}
        self._frame: tuple[float, float] | None = None  # the grip's (azimuth, roll) now
        self._flying: list[InFlight] = []  # thrown, not yet at rest
        self._scored: dict[int, ItemResult] = {}  # scored, by index, not yet reported
        self._flights: dict[int, tuple[Any, Any]] = {}  # (Outcome, landing) for the observer
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
                raise JobError(
                    f"{job.path}, line {spec.line}: item {spec.obj.name or spec.obj.shape} "
                    f"to bin {spec.bin!r}: {exc}"
                ) from None

    # -- motion ----------------------------------------------------------------
    def _tcp_for_item_centre(
        self, centre: np.ndarray, elevation: float, azimuth: float, stroke: float, obj: ObjectParams
    ) -> np.ndarray:
        """TCP position [m, W] that puts the gripped item's centre at `centre`."""
        from cell.sim import EE_TO_TCP_M
        from cell.sim.scene import release_orientation

        u = release_orientation(elevation, azimuth)[:, 2]
        return np.asarray(centre, float) + u * (EE_TO_TCP_M - stroke - obj.size[2] / 2)

    def _ik(self, tcp: np.ndarray, elevation: float, azimuth: float) -> np.ndarray:
        from cell.robot.ik import solve_release_ik

        return solve_release_ik(self.robot, tcp, elevation, azimuth, self.q).q

    def _swing(self, q_lift: np.ndarray, q_rel: np.ndarray, plan: Any) -> list[np.ndarray]:
        """Waypoints between the lift and the release that keep the grip on the twist-free
        swing (`_pick_frame`): the throw axis turns up about one horizontal axis, the
        pads' y axis stays level. A joint-space spline between the two ends alone rolls
        the grip sideways on the way, and a tall item hanging from the pads turns in
        them (cell.robot.carry). None when the grip was not taken twist-free, or when
        a waypoint has no IK (the spline between the ends is used then)."""
        if self._frame is None or SWING_WAYPOINTS < 1 or not self._turns_if_rolled():
            return []
        az, roll = self._frame
        rb = self.robot
        p0, p1 = rb.tcp_pose(q_lift)[0], rb.tcp_pose(q_rel)[0]
        e0, e1 = -math.pi / 2, plan.elevation_rad
        out: list[np.ndarray] = []
        q = q_lift
        from cell.robot.ik import ReleasePose, solve_ik

        for k in range(1, SWING_WAYPOINTS + 1):
            f = k / (SWING_WAYPOINTS + 1)
            pose = ReleasePose.from_angles(p0 + f * (p1 - p0), e0 + f * (e1 - e0), az, roll)
            try:
                q = solve_ik(rb, pose, q, random_seeds=0, solutions=1).q
            except IKFailed:
                return []
            out.append(q)
        return out

    def _turns_if_rolled(self) -> bool:
        """Would the carried item turn in the pads if the grip rolled its y axis up while
        it hangs (gravity along the pads' faces)? Then the swing is kept level."""
        from cell.model.params import G
        from cell.robot.carry import CARRY_MARGIN

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
        """
        if plan is None:
            return None
        roll = self._roll_of(self._q_release, plan.elevation_rad, plan.azimuth_rad)
        return (float(plan.azimuth_rad), roll)

    def _ik_frame(self, tcp: np.ndarray) -> np.ndarray:
        """IK for the grip pointing down at `tcp` [m, W], in the item's frame
        (`self._frame`: (azimuth, roll), else the roll is free)."""
        from cell.robot.ik import ReleasePose, solve_ik

        if self._frame is not None:
            az, roll = self._frame
            try:
                pose = ReleasePose.from_angles(tcp, -math.pi / 2, az, roll)
                return solve_ik(self.robot, pose, self.q).q
            except IKFailed:
                log.info("no IK for the twist-free grip at %s: the roll is left free", tcp)
        return self._ik(tcp, -math.pi / 2, 0.0)

    def _ik_release(self, tcp: np.ndarray, elevation: float, azimuth: float) -> np.ndarray:
        """IK for the release, at the roll the item was gripped for (`self._frame`)."""
        from cell.robot.ik import ReleasePose, solve_ik

        if self._frame is not None:
            pose = ReleasePose.from_angles(tcp, elevation, azimuth, self._frame[1])
            try:
                return solve_ik(self.robot, pose, self.q).q
            except IKFailed:
                pass
        return self._ik(tcp, elevation, azimuth)

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
        """
        from cell.robot.motion import plan_path

        settle_s = SETTLE_S if settle_s is None else settle_s
        try:
            if self.ee.item is None:
                traj = plan_path(
                    [self.q, *waypoints],
                    self.robot,
                    velocity_scale=self.speed_scale,
                    acceleration_scale=self.speed_scale,
                )
            else:
                traj = self._carry_path(waypoints)
        except TrajectoryError:
            if len(waypoints) < 2:
                raise
            # The spline through the waypoints leaves the joint limits between them: stop
            # at each instead (a straight joint-space segment stays inside the limit box).
            return sum(self._move([w], settle_s) for w in waypoints)
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        ts = np.arange(sc.dt_s, traj.duration + sc.dt_s, sc.dt_s)
        qs, _, _ = traj.sample_many(ts)
        for q in qs:
            sc.set_arm(q)
            sc.step()
        if settle_s > 0:
            sc.run_for(settle_s)
        self.q = np.asarray(waypoints[-1], float)
        self._land()
        return float(traj.duration) + settle_s

    def _carry_path(self, waypoints: list[np.ndarray]) -> Any:
        """The fastest path through the waypoints that the grip holds the item along."""
        from cell.robot.carry import plan_carry

        obj, stroke = self._carried
        traj, _ = plan_carry(
            [self.q, *waypoints],
            self.robot,
            carry_hold(self.params, obj, stroke),
            velocity_scale=self.speed_scale,
            acceleration_scale=self.speed_scale,
        )
        return traj

    # -- one item --------------------------------------------------------------
    def run_item(self, index: int, spec: ItemSpec) -> ItemResult:
        """Pick, decide, plan, move, release, observe and record one item, and wait
        for it to come to rest.

        Its `cycle_time_s` is the simulated time from the start of its pick until it
        is scored (`run` instead goes on with the next pick while a thrown item flies).
        """
        from dataclasses import replace as dc_replace

        t0 = self.scene.t
        res = self._run_item(index, spec)
        if isinstance(res, InFlight):
            res = self._wait_for(res)
        if self.observer is not None and index in self._flights:
            self.observer.on_flight(index, *self._flights.pop(index))
        return dc_replace(res, cycle_time_s=self.scene.t - t0)

    def _run_item(self, index: int, spec: ItemSpec) -> ItemResult | InFlight:
        obj = spec.obj
        target = self.job.bin(spec.bin)
        sc = self.scene
        t0 = sc.t
        item = sc.spawn_item(obj if obj.shape != "mesh" else obj.name)
        sc.run_for(0.05)  # let it settle on the station
        if self.observer is not None:
            self.observer.on_item_start(index, obj, target, item)
        base: dict[str, Any] = dict(
            index=index, object_id=obj.name or obj.shape, target_bin=spec.bin
        )
        flying: InFlight | None = None
        try:
            dist = math.hypot(*target.position)
            place = self.job.policy == "place" or (
                self.job.policy == "auto" and dist <= self.job.place_reach_m
            )
            # Plan before the pick: the end-effector grasps at the stroke it will throw
            # with, so the item sits on the band carriage as the plan assumes.
            s_grip = grip_stroke_limit(self.params, obj)
            plan, delta = (None, 0.0) if place else self._plan(obj, target, index, s_grip)
            stroke = min(PICK_STROKE_M, s_grip) if plan is None else plan.stroke_m + delta
            p_item = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
            down = (-math.pi / 2, 0.0)
            # Grip it turned as the release will hold it: the carry then only swings the
            # throw axis up, it does not twist the item about it (a twist in the grip
            # spoils the launch, see _pick_frame).
            self._frame = self._pick_frame(plan)
            q_pick = self._ik_frame(self._tcp_for_item_centre(p_item, *down, stroke, obj))
            lift = p_item + np.array([0, 0, LIFT_M])
            q_lift = self._ik_frame(self._tcp_for_item_centre(lift, *down, stroke, obj))
            self._move([q_lift, q_pick])
            self.ee.grasp(stroke, item)
            self._carried = (obj, stroke)
            if self.hardware is not None:
                self.hardware.grasp(stroke)
            if plan is None:
                return self._place(base, item, obj, target, q_lift, t0, stroke)
            flying = self._throw(base, item, obj, target, q_lift, t0, plan, delta)
            return flying
        except HardwareError:
            raise  # the end-effector failed: the run stops (torque off), not just this item
        except CellError as exc:
            log.info("item %d (%s) failed: %s", index, obj.name, exc)
            return ItemResult(
                **base,
                action="failed",
                failure=failure_of(exc),
                reason=f"{type(exc).__name__}: {exc}",
                cycle_time_s=sc.t - t0,
            )
        finally:
            # Bins keep what lands in them, as real bins do (later items land on earlier
            # ones); an item anywhere else (on the floor, still on the station, in the
            # grip) is taken away, as an operator would before the next pick.
            self.ee.item = None
            if flying is None:  # a thrown item is tidied once it is scored (_settle)
                self._tidy(item)

    def _place(
        self,
        base: dict,
        item: Any,
        obj: ObjectParams,
        target: Any,
        q_lift: np.ndarray,
        t0: float,
        stroke: float,
    ) -> ItemResult:
        sc = self.scene
        down = (-math.pi / 2, 0.0)
        bx, by = target.position
        # a spot on the bin's floor clear of what it holds (its centre while it is empty)
        sx, sy, surface_z = sc.place_spot(target.id, obj)
        centre = np.array([sx, sy, obj.size[2] / 2 + PLACE_CLEARANCE_M + surface_z])
        above = centre + np.array([0, 0, max(LIFT_M, target.rim_height + 0.05)])
        q_above = self._ik_frame(self._tcp_for_item_centre(above, *down, stroke, obj))
        q_down = self._ik_frame(self._tcp_for_item_centre(centre, *down, stroke, obj))
        self._move([q_lift, q_above])
        # Down into the bin on its own short move: a spline through q_above and q_down
        # would cut the corner and sweep the item through the bin's wall.
        self._move([q_down])
        self._check_held(obj)
        self.ee.place()
        if self.hardware is not None:
            self.hardware.place()
        t_release = sc.t
        out = sc.watch_until_rest(item, timeout_s=self.job.item_time_limit_s)
        err = math.hypot(out.rest_xyz[0] - bx, out.rest_xyz[1] - by)
        cyc = t_release - t0
        self._flights[base["index"]] = (out, out.rest_xyz)  # for the observer, in order
        self._move([q_above])
        return ItemResult(
            **base,
            action="place",
            bin_id=out.bin_id or "",
            in_bin=out.bin_id == target.id,
            failure=missed_bin(out.bin_id, target.id, err)[0],
            reason=missed_bin(out.bin_id, target.id, err)[1],
            landing_error_m=err,
            stroke_m=stroke,
            cycle_time_s=cyc,
        )

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

        When IK finds no configuration for the plan's release pose, the plan is made
        again with the release lower and the throw axis flatter (RELEASE_FALLBACKS):
        the arm cannot point steeply up at shoulder height close to its base.
        """
        from dataclasses import replace as dc_replace

        err: CellError | None = None
        for elevation_max, height in ((None, None), *RELEASE_FALLBACKS):
            self.bounds_now = self.bounds
            if elevation_max is not None and height is not None:
                self.bounds_now = dc_replace(
                    self.bounds,
                    elevation_max=min(self.bounds.elevation_max, elevation_max),
                    release_height=height,
                )
            try:
                plan, delta = self._plan_once(obj, target, index, stroke_max_m)
            except UnreachableTarget as exc:
                err = err or exc
                continue
            stroke = plan.stroke_m + delta
            centre = np.array([plan.x_m, plan.y_m, plan.z_m])
            try:
                self._q_release = self._ik(
                    self._tcp_for_item_centre(
                        centre, plan.elevation_rad, plan.azimuth_rad, stroke, obj
                    ),
                    plan.elevation_rad,
                    plan.azimuth_rad,
                )
            except IKFailed as exc:
                err = err or exc
                continue
            return plan, delta
        assert err is not None
        raise err

    def _plan_once(
        self, obj: ObjectParams, target: Any, index: int, stroke_max_m: float
    ) -> tuple[Any, float]:

        from cell.optimize.plan import plan_facing

        goal = (*target.position, target.rim_height)
        # Identified η_o where the parameter file has them (seen objects), else the
        # catalogue's; with a residual, only those the residual was trained with, so
        # that L_s + ΔL_s means what it meant in training.
        use_identified = self.residual is None or obj.name in self.residual.identified_objects
        model_obj = self.params.model_object(obj) if use_identified else obj
        self._model_obj = model_obj  # what the plan assumed (for an observer)
        bounds = self.bounds_now
        plan = plan_facing(model_obj, goal, self.params.ee, bounds)
        if plan.stroke_m > stroke_max_m:  # the grip would not hold it there: plan within it
            bounds = grip_bounds(bounds, self.params, stroke_max_m)
            plan = plan_facing(model_obj, goal, self.params.ee, bounds)
        self._aim = np.asarray(goal, float)
        if self.learn:
            aim = self._corrected_aim(obj, plan, np.asarray(goal, float))
            if aim is not None:
                try:
                    plan = plan_facing(model_obj, tuple(aim), self.params.ee, bounds)
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

    def _throw(
        self,
        base: dict,
        item: Any,
        obj: ObjectParams,
        target: Any,
        q_lift: np.ndarray,
        t0: float,
        plan: Any,
        delta: float,
    ) -> InFlight:
        sc = self.scene
        bx, by = target.position
        stroke = plan.stroke_m + delta
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = self._tcp_for_item_centre(centre, plan.elevation_rad, plan.azimuth_rad, stroke, obj)
        try:  # IK from the lift pose the arm is at; _plan checked one exists from before
            q_rel = self._ik_release(tcp, plan.elevation_rad, plan.azimuth_rad)
        except IKFailed:
            q_rel = self._q_release
        self._move([q_lift, *self._swing(q_lift, q_rel, plan), q_rel])
        self._check_held(obj)
        if self.hardware is not None:
            self.hardware.throw()
        released_at = np.asarray(sc.client.getBasePositionAndOrientation(item.body)[0])
        if self.observer is not None:
            self.observer.on_release(
                base["index"], plan, self._model_obj, self.params.ee, stroke, released_at
            )
        self.ee.throw()
        t_release = sc.t
        aim = self._aim

        def score(out: Any) -> tuple[ItemResult, Any]:
            cross = out.crossing(target.rim_height)
            err = math.hypot(cross[0] - bx, cross[1] - by)
            if self.learn:
                self._learn_from(obj, plan, cross, aim)
            throw_id = f"{self.session}-{base['index']:04d}"
            if self.store is not None:
                self.store.append(
                    sorted_throw_record(
                        self.session, throw_id, obj, plan, stroke, released_at, target, out, cross
                    ),
                    track=out.track,
                )
            failure, reason = missed_bin(out.bin_id, target.id, err)
            res = ItemResult(
                **base,
                action="throw",
                bin_id=out.bin_id or "",
                in_bin=out.bin_id == target.id,
                failure=failure,
                reason=reason,
                landing_error_m=err,
                stroke_m=stroke,
                delta_stroke_m=delta,
                cycle_time_s=t_release - t0,
                throw_id=throw_id,
            )
            return res, (cross[0], cross[1], target.rim_height)

        return InFlight(base, obj, item, score)

    # -- items in flight ---------------------------------------------------------
    def _tidy(self, item: Any) -> None:
        """Bins keep what lands in them, as real bins do (later items land on earlier
        ones); an item anywhere else (on the floor, still on the station, in the grip)
        is taken away, as an operator would."""
        if self.scene.in_bin(item) is not None:
            self.scene.keep(item)
        else:
            self.scene.remove_item(item)

    def _settle(self, f: InFlight, out: Any) -> ItemResult:
        """Score an item whose flight ended (`out`: its Outcome, or the NoLanding error)."""
        try:
            if isinstance(out, CellError):
                raise out
            res, landing = f.score(out)
            self._flights[f.index] = (out, landing)
        except CellError as exc:
            log.info("item %d (%s) failed: %s", f.index, f.obj.name, exc)
            res = ItemResult(
                **f.base,
                action="failed",
                failure=failure_of(exc),
                reason=f"{type(exc).__name__}: {exc}",
            )
        finally:
            self._tidy(f.item)
        return res

    def _poll(self, f: InFlight) -> ItemResult | None:
        """The item's result once its flight has ended, else None (non-blocking)."""
        try:
            out = self.scene.outcome_if_settled(f.item, timeout_s=self.job.item_time_limit_s)
        except CellError as exc:
            return self._settle(f, exc)
        return None if out is None else self._settle(f, out)

    def _wait_for(self, f: InFlight) -> ItemResult:
        """Step the scene until the item's flight has ended; its result."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        while (res := self._poll(f)) is None:
            sc.step()
        return res

    def _land(self) -> None:
        """Score every item in flight that has come to rest (called between moves)."""
        for f in list(self._flying):
            res = self._poll(f)
            if res is not None:
                self._flying.remove(f)
                self._scored[f.index] = res

    # -- the run ---------------------------------------------------------------
    def run(self, on_item: Callable[[ItemResult], None] | None = None) -> RunSummary:
        """Sort every item of the job; `on_item` is called after each, in job order.

        The next pick starts as soon as an item is thrown: the physics keeps stepping
        the thrown item while the arm moves on, and it is scored when it comes to
        rest. An item's `cycle_time_s` runs from the start of its pick to the start of
        the next one; the last item's, until everything thrown has come to rest.
        With `learn`, an item waits for the landing of an earlier throw of the same
        object (or class) that is still in flight, so that it learns from it.
        """
        from dataclasses import replace as dc_replace

        t_wall = time.perf_counter()
        sc = self.scene
        starts: list[float] = []
        results: list[ItemResult] = []
        self._flying, self._scored, self._flights = [], {}, {}

        def emit(t_end: float | None = None) -> None:
            while (i := len(results)) in self._scored and (i + 1 < len(starts) or t_end):
                t_next = starts[i + 1] if i + 1 < len(starts) else float(t_end or sc.t)
                res = dc_replace(self._scored.pop(i), cycle_time_s=t_next - starts[i])
                results.append(res)
                if self.observer is not None:
                    if i in self._flights:
                        self.observer.on_flight(i, *self._flights.pop(i))
                    self.observer.on_item_done(res)
                if on_item is not None:
                    on_item(res)

        try:
            for i, spec in enumerate(self.job.expanded_items()):
                if self.learn:
                    self._wait_for_kin(spec.obj)
                starts.append(sc.t)
                emit()
                res = self._run_item(i, spec)
                if isinstance(res, InFlight):
                    self._flying.append(res)
                else:
                    self._scored[i] = res
                self._land()
            self._land_all()
        except HardwareError:
            # the run stops; what was thrown before the fault still lands and is recorded
            self._land_all()
            emit(t_end=sc.t)
            raise
        except BaseException:
            emit(t_end=sc.t)  # report what was scored; an item still in flight is lost
            raise
        emit(t_end=sc.t)
        return summarise(results, time.perf_counter() - t_wall)

    def _land_all(self) -> None:
        """Step the scene until every thrown item has come to rest, scoring each."""
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        while self._flying:
            sc.step()
            self._land()

    def _wait_for_kin(self, obj: ObjectParams) -> None:
        """Let in-flight throws of the same object or class land first (learning)."""
        keys = {obj.name or "", self._class_key(obj)}
        sc = self.scene
        sc.set_timestep(sc.dt_s)
        while any({f.obj.name or "", self._class_key(f.obj)} & keys for f in self._flying):
            sc.step()
            self._land()

    def close(self) -> None:
        """Close the scene and any hardware end-effector."""
        self.scene.close()
        if self.hardware is not None:
            self.hardware.close()
