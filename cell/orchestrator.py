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
import uuid
from collections.abc import Callable
from typing import Any

import numpy as np

from cell.arm.base import check_speed_scale
from cell.arm.flywheel import Flywheel, LandingCorrection
from cell.arm.fork import PlanFork
from cell.arm.grip_limits import GripUse
from cell.arm.grip_side import GripSideChoice, holding_sides, throw_sides
from cell.arm.kinematics import Kinematics
from cell.arm.launch import check_sortable
from cell.arm.mover import Mover
from cell.arm.pick import Pick
from cell.arm.place import Place
from cell.arm.planner import Planner
from cell.arm.release import ReleaseChoice
from cell.arm.release_moving import MovingRelease
from cell.arm.routes import Routes
from cell.arm.state import ArmState
from cell.arm.tuning import TUNING, ArmTuning
from cell.decision import Decision
from cell.errors import (
    CannotGrip,
    IKFailed,
    InvalidInput,
    UnreachableTarget,
)
from cell.jobbins import places
from cell.jobs import ItemSpec, Job, check_order
from cell.kinds import PICKS, RELEASES
from cell.loop import ItemLoop
from cell.model.objects import ObjectParams
from cell.parallel import one_blas_thread
from cell.params import ModelParams, load_params, scene_params_path
from cell.results import FAILURES, ItemResult, RunSummary
from cell.robot.ik_warm import FarPoses, WarmStarts

__all__ = [
    "FAILURES",  # re-exported from cell.results, where it is defined
    "ItemResult",
    "RunSummary",
    "Orchestrator",
]

log = logging.getLogger(__name__)

ARM_SPEED_SCALE = 1.0  # fraction of the joint velocity/acceleration limits used


def _check_options(speed_scale: float, pick: str, release: str, order: str, arm: str) -> None:
    """InvalidInput naming the option and what would be valid (`arm`: the job's robot)."""
    check_speed_scale(speed_scale, arm)
    if pick not in PICKS:
        raise InvalidInput(f"pick {pick!r}: valid are {list(PICKS)}")
    if release not in RELEASES:
        raise InvalidInput(f"release {release!r}: valid are {list(RELEASES)}")
    check_order(order)


def _load_planning_libraries() -> None:
    """Import what the planning of an item uses (toppra, ruckig, SciPy's least squares:
    2 s of CPU time here) when the arm is built, not in the first item's planning: a
    cell loads its libraries once, and an item's `plan_s` is its own planning."""
    import scipy.optimize  # noqa: F401
    import toppra  # noqa: F401

    import cell.robot.carry  # noqa: F401
    import cell.robot.motion  # noqa: F401
    import cell.robot.moving_release  # noqa: F401


class Orchestrator(
    Kinematics,
    Routes,
    Mover,
    Pick,
    Place,
    Planner,
    ReleaseChoice,
    MovingRelease,
    GripUse,
    GripSideChoice,
    Flywheel,
    PlanFork,
):
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
        plan_workers: processes a throw is planned on, 1 or 2 (`cell.arm.fork`; None: 2 on 2 cores).
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
        tuning: ArmTuning = TUNING,
        plan_workers: int | None = None,
    ) -> None:
        from cell.endeffector.factory import make_in_step
        from cell.optimize.bounds import ThrowBounds
        from cell.robot.model import load_robot
        from cell.sim import BinSpec, CellScene

        _check_options(speed_scale, pick, release, order, job.robot)  # before the scene
        _load_planning_libraries()
        self.tuning = tuning
        self._init_forks(plan_workers)  # `cell.arm.fork`
        self.speed_scale = float(speed_scale)
        self.job = job
        self.params = params or load_params(job.params or scene_params_path())
        self.bounds = ThrowBounds()
        self._check_job()  # before the scene is built: a refused job leaves nothing open
        self._probe_meshes()
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
        self.pick_mode, self.release_mode = pick, release
        self.turn_release = bool(turn_release)  # `_facing_toward_station`
        self.cycle_search = bool(cycle_search)  # `_release_costs`, `_plan_facing`
        # `floor`: per item, (its approach's and carry's seconds, as direct moves)
        self.floor = bool(floor)
        self.floors: dict[int, tuple[float, float]] = {}
        # the kinematic pick moves the item into the grip: the pads, longer than a flat
        # item, must not jam on the station's top while the fingers close
        self.scene.ee_collides_with_station(pick == "physical")
        self.effector = make_in_step(self.scene, end_effector)  # commands, in step
        self.ee = self.effector.sim  # the plant's end-effector: the physical pick's steps
        self.residual = None
        if job.residual:
            from cell.residual.model import ResidualModel

            self.residual = ResidualModel.load(job.residual)
        self.q = np.asarray(self.scene.ready_q, float)
        self.observer = observer
        self.learn = learn
        self.corrections: dict[str, LandingCorrection] = {}
        self._init_working_state()
        self.loop = ItemLoop(
            job,
            self,
            self.scene,
            store=store,
            session=self.session,
            observer=observer,
            wait_for=self._same_kind if learn else None,
            order=order,
            on_landed=self.landed,
        )
        self.on_moved = self.loop.land  # the loop's hook: the mover calls it after each move
        if observer is not None:
            observer.on_scene(self.scene, job)

    def _init_working_state(self) -> None:
        """What the parts keep while an item is handled (see `cell.arm.base.ArmBase`)."""
        self._index = -1  # the item being handled (`present`)
        self._presented: Any = None  # the item the plant presented last
        self._frame: tuple[float, float] | None = None  # the grip's (azimuth, roll) now
        # IK solved and approaches timed since the decision began (`_solve_ik`,
        # `_approach_s`; `decide` clears them)
        self._ik_memo: dict[tuple[bytes, ...], Any] = {}
        # release poses out of reach, kept across decisions (`_solve_ik`, `ik_reach_kept`)
        self._out_of_reach: dict[tuple[bytes, ...], Any] = {}
        # IK searches kept across decisions (`Kinematics._solved`)
        self._ik_solved: dict[tuple[bytes, ...], Any] = {}
        # release poses solved in this decision, warm starts for nearby ones
        # (`Kinematics._solved`, `ik_warm`; `decide` clears it)
        self._ik_warm = WarmStarts()
        # kept across decisions (`Kinematics._solve_ik`, `MovingRelease._choose_release`):
        self._far_poses = FarPoses()  # poses out of reach (`ik_reach_kept`, `ik_warm`)
        self._moving_kept: dict[bytes, Any] = {}  # release-on-the-move searches
        self._approach_memo: dict[tuple[Any, ...], float] = {}
        self._approach_plans: dict[tuple[Any, ...], tuple[Any, str]] = {}  # `_approach_plan`
        self._plan_memo: dict[tuple[Any, ...], Any] = {}  # paths and carries (`_planned`)
        self._placing = False  # the item carried is to be placed (carry_hold)

    def _probe_meshes(self) -> None:
        """Probe the grip of each kind of mesh or sphere item the run will handle once, as
        the job is loaded (`mesh_grip`: the scene's grip probe, remembered per object and
        stroke), not in the first such item's planning (1.7 s of CPU time a kind here; a
        sphere's hold is measured for `point_hold_use`, 1.2-2.7 s in the first sphere's
        decision of each kind on the demo and on tune layout 0): a cell measures what it
        will handle before it starts. The same probe, the same hold; none for the kinds
        limits.max_items leaves unsorted."""
        from cell.arm.grip_limits import mesh_grip

        probed = ("mesh", "sphere")
        handled = self.job.expanded_items()
        for obj in dict.fromkeys(s.obj for s in handled if s.obj.shape in probed):
            if obj.shape != "mesh":
                mesh_grip(self.params, obj)
                continue
            try:  # each side it may be gripped across (`_check_job` refuses the rest)
                sides = holding_sides(self.params, obj)
            except CannotGrip:
                continue
            for side in sides:
                mesh_grip(self.params, side.obj)

    def _check_job(self) -> None:
        """Refuse the job before it starts if an item cannot be gripped or its bin is
        out of its reach (by the planner's model of the scene): every such item in one
        report, one a line."""
        from cell.errors import JobError
        from cell.yamltree import Errors

        job = self.job
        errors = Errors(job.path)
        for spec in job.items:
            try:
                check_sortable(
                    self.params,
                    spec.obj,
                    job.bin(spec.bin),
                    policy=job.policy,
                    place_reach_m=job.place_reach_m,
                    bounds=self.bounds,
                    thrown_bins=job.thrown_bins,
                )
            except (CannotGrip, UnreachableTarget) as exc:
                instead = (
                    ""
                    if isinstance(exc, CannotGrip)
                    else f"; move bin {spec.bin!r} within the reach above, or send the item "
                    "to another bin"
                )
                errors.add(
                    JobError(
                        f"{job.path}, line {spec.line}: item {spec.obj.name or spec.obj.shape} "
                        f"to bin {spec.bin!r}: {str(exc).rstrip('.')}{instead}"
                    )
                )
        errors.raise_all()

    # -- motion ----------------------------------------------------------------

    # -- the platform's steps (cell.loop.Platform) -----------------------------
    name = "arm"
    overlaps = True  # the next pick starts while a thrown item flies
    rotor_rpm = 0.0

    def run_item(self, index: int, spec: ItemSpec) -> ItemResult:
        """Pick, decide, plan, move, release, observe and record one item, and wait
        for it to come to rest (`cell.loop.ItemLoop.run_item`)."""
        return self.loop.run_item(index, spec)

    def run(self, on_item: Callable[[ItemResult], None] | None = None) -> RunSummary:
        """Sort every item of the job (`cell.loop.ItemLoop.run`: the next pick as soon as an
        item is thrown), on one BLAS thread as `cell run` does (`one_blas_thread`)."""
        with one_blas_thread():  # two BLAS threads in each planning process fight for cores
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
        """Place (`cell.jobbins.places`: a bin within the job's place reach the arm can place
        into, or the job's policy) or throw, and
        the throw's plan, made before the pick: the end-effector grasps at the stroke it
        will throw with, so the item sits on the band carriage as the plan assumes."""
        self._new_decision()
        job = self.job  # its policy, place reach and the near bins it throws into
        place = places(job.policy, job.place_reach_m, target, job.thrown_bins)
        sides = holding_sides(self.params, obj)  # CannotGrip: none holds
        if place:
            stroke = min(self.tuning.pick_stroke_m, sides[0].stroke_max_m)
            if not sides[0].brisk:
                # held only slowly (its weight asks over 1/1.6 of the pads' friction at
                # every stroke): at the shortest, where the band closes them hardest, the
                # place's carry keeps the most of its bound for its accelerations (the
                # 220 g tetrapack: its weight 0.69 of the grip at 45 mm, 0.64 at 30 mm,
                # the bound 0.74)
                stroke = max(self.params.ee.stroke_min, self.ee.band.ee.stroke_min)
            return Decision(
                "place", stroke, state=ArmState(target, side=sides[0]), gripped=sides[0].obj
            )
        side, choice = self._throw_side(throw_sides(sides, obj, self.params), target, index)
        obj, s_grip = side.obj, side.stroke_max_m  # the item as gripped
        plan, delta = choice.plan, choice.delta
        assert choice.goal is not None
        state = ArmState(target, choice, choice.q_release, side=side)
        d = Decision(
            "throw",
            plan.stroke_m + delta,
            plan,
            delta,
            model_obj=choice.model_obj,
            ee_params=self.params.ee,
            goal_xy=(float(choice.goal[0]), float(choice.goal[1])),
            state=state,
            gripped=obj,
        )
        mt = None
        if self._may_release_moving(obj, d):
            mt = self._moving_choice(obj, choice, s_grip)
        if mt is not None:
            d.plan, d.stroke_m, d.moving = mt.plan, mt.plan.stroke_m + delta, True
            state.moving, state.q_release = mt, mt.motion.q_release
        return d

    def pick(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """Grip the item turned as the release will hold it: the carry then only swings
        the throw axis up, it does not twist the item about it (a twist in the grip
        spoils the launch, see `_pick_frame`)."""
        st: ArmState = d.state
        obj, yaw = st.gripped(obj), st.grip_yaw_rad
        self._frame = self._pick_frame(d.plan, st.q_release)
        if self.pick_mode == "physical":
            heading = self._carry_heading(d.plan, st.target, st.q_release)
            st.q_lift = self._pick(obj, item, d.stroke_m, *heading, side_yaw=yaw)
            self._frame = None  # gripped as the item lay: its own heading (_carry_heading)
        else:
            st.q_lift = self._pick_kinematic(obj, item, d.stroke_m, yaw)
        self.effector.grasp(d.stroke_m)  # held in the plant already: the hardware winds
        stroke = self._carry_stroke(obj, d)
        if stroke != d.stroke_m:  # the item held, the carriage draws it up off the station
            self.effector.set_stroke(stroke)
            self._grip_stroke = stroke

    def carry(self, d: Decision, obj: ObjectParams, item: Any) -> None:
        """To the release pose: over the bin and down into it (a place), or along the
        twist-free swing to the release configuration (a throw); the item still held."""
        st: ArmState = d.state
        obj = st.gripped(obj)
        q_lift = st.q_lift
        assert q_lift is not None
        if d.action == "place":
            self._carry_to_place(d, obj, q_lift)
        elif d.moving:
            # the move is the release's own (approach, latch on the move, coast, stop),
            # planned from where the pick left the arm: the grip round the item, the item
            # on the station. Where that move would not lift it clear first (ruckig's move
            # need not go straight up: it can sweep the item out of the pads across the
            # station's top, `tests/test_moving_station.py`), or leaves the joint limits,
            # the arm goes up to the lift, where `_moving_choice` timed the release from
            lifted, motion = self._moving_route(st.moving, obj, d.stroke_m, self.q, q_lift)
            if lifted:
                log.info("%s: up to the lift, then the release on the move", obj.name or obj.shape)
                self.move([q_lift])
            st.motion = motion
        else:
            plan = d.plan
            centre = np.array([plan.x_m, plan.y_m, plan.z_m])
            tcp = self._tcp_for_item_centre(
                centre, plan.elevation_rad, plan.azimuth_rad, d.stroke_m, obj
            )
            try:  # IK from the lift pose the arm is at; _plan checked one exists before
                q_rel = self._ik_gripped(tcp, plan.elevation_rad, plan.azimuth_rad)
            except IKFailed:
                assert st.q_release is not None
                q_rel = st.q_release
            q_rel = self._release_branch(q_lift, q_rel, st.q_release, tcp, plan)
            q0, t0 = self.q, self.scene.t
            self.move(self._departure(q_lift, q_rel, plan))
            self._time_floor(q0, t0, settle_s=self.tuning.settle_s)
            if self._grip_stroke != d.stroke_m:  # carried at a shorter one (`_carry_stroke`)
                self._check_held(obj)
                self.effector.set_stroke(d.stroke_m)
                self._grip_stroke = d.stroke_m
                self._run_for(self.tuning.settle_s)
        self._check_held(obj)

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
        return self._release_on_the_move(d.state.motion)

    def after_place(self, d: Decision) -> None:
        """Back up out of the bin; no settle: nothing is held, and the next move starts
        from rest."""
        self.move(d.state.rise or [d.state.q_above], settle_s=0.0)

    def finish(self, d: Decision | None) -> None:
        """Nothing of the item is held any more."""
        self.ee.item = None

    def landed(self, d: Decision, obj: ObjectParams, crossing: Any) -> None:
        """The flywheel: learn from the throw's observed crossing."""
        if self.learn:
            self._learn_from(obj, d.plan, crossing, d.state.choice.aim)

    # -- the pick ----------------------------------------------------------------

    # -- the flywheel ------------------------------------------------------------

    def close(self) -> None:
        """Close the scene and any hardware end-effector."""
        self.scene.close()
        self.effector.close()
