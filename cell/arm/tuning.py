"""The arm's constants, in one typed and documented object: what was chosen, and where.

Every value here is a choice the arm's parts make with (`Orchestrator(tuning=...)`), not a
fact of the scene's physics (those stay with the model: `cell.arm.grip_limits`). Each says
where it was measured. "Random layouts" are the jobs `cell job random --seed N` draws;
the constants were chosen on random layouts 0-19 (`cell bench sort --layouts 20 --seed 0`),
the `tune` set: a figure measured on those layouts is in-sample, one on other seeds is not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["ArmTuning", "TUNING"]


@dataclass(frozen=True)
class ArmTuning:
    """The arm's constants (SI units; angles in radians). Frozen: a run that wants other
    values makes its own with `dataclasses.replace(TUNING, ...)`.

    The carry and its routes:
        settle_s: [s] wait after a move so the end-effector and item come to rest: none
            (0.05 s before; on random layouts 0-5 with the release search and the turn,
            190 -> 189 of 198 in their bins and 1,420 -> 1,430 items per hour).
        pick_stroke_m: [m] stroke a placed item is carried at: grip force enough to hold
            items through arm moves.
        lift_m: [m] lift above the pick pose before moving to the release.
        lift_max_dq_rad: [rad] a lift's configuration farther than this from the pick's, in
            any joint, is on another IK branch: the straight lift would swing the arm round
            (a UR5 grip folded back over the station took 3.4 s to come up 0.15 m, 1.2 s to
            come up 0.075 m on its own branch).
        departure_lifts_m: [m] the carry from the pick leaves through the lowest of these
            lifts (0: straight from the pick) whose path keeps the item rising out of the
            station, at least as far as it moves sideways, up to departure_clear_m; else
            through lift_m. 1-2 cm lifts dropped nothing on random layout 3 (README, Limits).
        departure_clear_m: [m] how far the item rises out of the station before it may move
            sideways as far (the rise to 2 cm: random layouts 0-19, 1,474 -> 1,507 items/h).
        pick_over_clearance_m: [m] the empty arm's approach to a kinematic pick passes,
            without stopping, the point where the open pads' tips are this far over the
            item's top, and goes straight down from there (random layout 3, README).
        place_clearance_m: [m] the item's lowest point above the bin floor when a place
            starts.
        place_spots_tried: place spots tried, best first, for one the arm reaches (IK):
            random layouts 3 (UR5) and 18 (Panda), tests/test_place_reach.py.
        swing_waypoints: waypoints that keep the carry's swing free of twist.
        swing_waypoints_max: doubled up to this while the spline between them rolls the grip.
        swing_check_samples: configurations along the swing's spline its grip use is
            checked at.
        grip_use_tie: grip uses this close are taken as equal, and a route or a carry that
            asks this little over the carry's bound (0.741) is taken as within it (the pads
            held 0.74-0.78 of their static limit accelerated, slid at 0.80; in the scene,
            tests/test_carry.py).
        swing_max_detour: a level swing whose joints travel farther than this x the ends'
            gap goes round (the demo's swings travel 1.5-1.8 x the gap; a UR5's that flung
            its items, 3.4 x; random layout 5).
        ik_out_of_reach_m: [m] a release pose IK's whole search misses by this much is out
            of reach from any seed: 5 x POSITION_TOL_M (the demo: 207 -> 81 failed searches,
            nothing chosen changed).
        ik_give_up: (seeds, score): with the release search, a release pose none of whose
            first `seeds` IK seeds came within `score` (position error / 1 mm + angle error
            / 0.5°) is given up as out of reach, unpolished (`solve_ik`'s `give_up`; None:
            all 32 seeds and the polish). Chosen by counting, seed by seed, every release
            IK search of the demo (2,685) and of tune layout 1's first 12 items (UR5,
            1,435): no search that found a solution had its first 6 seeds all over 30
            (30 mm or 15°), and the rule leaves out 10 % and 23 % of their descents; the
            failed searches' best seeds end at 3-40 (docs/HISTORY.md, 2026-11-29,
            decision-changing).
        ik_reach_kept: with the release search, a release pose missed by ik_out_of_reach_m
            or more (from the seeds ik_give_up leaves) is kept as out of reach for the
            rest of the run, not only the decision (`Kinematics._solve_ik`): the same pose
            (position, axis and roll, bit for bit) recurs in a later item's plan where
            the same object is thrown to the same spot, and its search differs there only
            in its first seed (where the arm is; home and the random seeds are the same).
            The same decisions on the demo and tune layout 0's first 14 items; on the demo
            the second and third sphere40's and duck's failed searches 0.14-0.19 s ->
            0.02-0.05 s of CPU (docs/HISTORY.md, 2026-11-29, fifth round).
        ik_solutions: with the release search, a release pose its first seed (the lift,
            where the arm is, the pick) does not reach is searched from home and random
            seeds until this many converge, the one nearest the first seed kept
            (`solve_ik`'s `solutions`; 3 without the release search). 1 with `ik_polish`
            0: the demo's decisions 23 % fewer DLS iterations, 24/24 and 1,533 items per
            hour (1,506); tune layouts 0-3 128/136, tune layout 0 29/33 against 31/33 (four
            cube60 missed): kept at 3 (docs/HISTORY.md, 2026-11-29, eighth round).
        ik_polish: with the release search, a release pose no seed reaches is refined from
            this many of the seeds' closest ends with a bounded solve before it is given up
            (`solve_ik`'s `polish`; 3 without the release search). 0 against 3: the same
            decisions on tune layouts 0-3 (132/136 in their bins, 303.42 s simulated,
            layout by layout) and on the demo (`sig` fa68a371528e): the polish rescued none
            of their release searches; its 81 bounded solves on the demo, 5 % of tune
            layout 0's decisions' CPU (docs/HISTORY.md, 2026-11-29, eighth round).
        ik_warm: ([m], [rad]) with the release search, a release pose within this distance
            and angle of one solved earlier in the same decision, at the same roll, is
            searched from that pose's solution (the one nearest the search's seed) right
            after the seed, before home and the random seeds (`solve_ik`'s `warm`;
            `cell.robot.ik_warm`); None: the cold search. On the demo, 113 of the 210
            release searches whose first seed missed had such a pose within 1 mm and 0.5°
            (no more within 10 mm and 5°), 1.75 of their 4.27 s of CPU. With
            `ik_reach_kept` too, a release pose this close to one kept as out of reach
            (missed by ik_out_of_reach_m or more) is refused unsearched (`FarPoses`). The
            demo's IK 33 % fewer DLS iterations, its decisions' CPU 17.06 -> 14.38 s, 24/24
            in their bins and 1,506 items per hour as before (docs/HISTORY.md, 2026-11-30,
            ninth round).

    The release:
        release_fallbacks: (largest elevation [rad], release height [m]) tried in turn when
            the arm cannot reach a plan's release pose (the demo and random layouts 0-19).
        release_box_shrinks: then each of those with the release box shrunk to these
            fractions about its centre: a 174 g disc to a bin 2.5 m out was 15 mm short in
            the full box; the 0.75 box left random layout 0's disc aimed 0.1 m farther out
            of reach; the 0.9 box reaches both (tests/test_release_box.py).
        approach_weight: with the release search, how much of the empty arm's approach from
            where it is a release's cycle estimate counts (random layouts 0 and 3: counted
            in full, layout 0 kept a branch 0.8 s slower a cycle; left out, layout 3's UR5
            alternated wrist rolls, 0.4-0.6 s a pick).
        release_timed_max: with the release search, at most this many of a search's
            candidates are timed as the cell makes the cycle, soonest lower bound first
            (0: every one whose bound can beat the soonest timed). Timing a candidate
            (toppra's carries) is half of a throw's decision; the soonest release was the
            soonest-bounded candidate in 43 of the demo's 66 searches, among the first
            three in 57 of 66. On tune layouts 0-3 against every candidate timed: 130 ->
            131 of 136 in their bins, 1,533 -> 1,551 items per hour (the demo, not a tune
            layout: 1,525 -> 1,505); the decisions' CPU on the demo 29.5 -> 22.7 s, p95
            3.72 -> 2.12 s an item with `ik_give_up` (docs/HISTORY.md, 2026-11-29,
            decision-changing). Then 3 -> 2 with `release_rank_way`: the demo's decisions'
            CPU p95 2.14 -> 1.45 s an item (1.11 s with 1), 1,515 -> 1,506 items per hour,
            24/24 in their bins; tune layouts 0-3 134 -> 135 of 136 in their bins, 1,581
            -> 1,598 items per hour (with 1: 133, 1,552, three layouts of four slower)
            (docs/HISTORY.md, 2026-11-29, branch plan5).
        release_rank_way: with the release search, candidates are ranked (and left out)
            by `_way_bound_s`, the way back to the pick as the cycle times it, instead of
            twice the carry's bang-bang bound (`_cycle_bound_s`): a lower bound no looser,
            for one more approach planned a candidate. Counted over the demo's 64
            searches with every candidate timed, the soonest was first by it in 41,
            first by the bang-bang bound in 39: hardly a better ranking, a tighter cut.
        release_timed_max_lower: with the release search, `release_timed_max` in the lower
            release bounds (release_fallbacks; None: the same as in the cell's): there
            only the soonest-bounded candidate is timed. On tune layouts 0-3 against 2
            (main at aeaa149): 132 -> 133 of 136 in their bins, 1,553 -> 1,569 items per
            hour (305.99 -> 305.23 s simulated); the demo decides the same (`sig`
            fa68a371528e), its decisions' CPU 13.44 -> 12.41 s, p95 1.25 -> 1.11 s an item
            (the duck's 1.27 -> 0.99 s); tune layout 0's first 14 items 11.87 -> 11.20 s,
            30.35 -> 30.77 s simulated (docs/HISTORY.md, 2026-11-29, seventh round).
        release_lower_room_s: [s] with the release search, the lower release bounds
            (release_fallbacks) are searched after a plan in the cell's bounds only where
            that plan's carry is at least this much slower than its lower bound (the
            arm's limits: `Planner._lower_bounds_wanted`), or it has no estimate that
            holds (None: always, as before). With every bounds searched, the lower ones
            took 13.0 of the demo's 18.1 s of release searches and were sooner in 1 of 18
            throws (0.06 s, at a room of 0.13 s); where they were sooner by 0.16-0.53 s
            (tune layouts 0 and 3) the room was 0.43-1.0 s. The demo's decisions' CPU
            18.9 -> 11.5 s, 1,506 -> 1,499 items per hour; tune layouts 0-3 132 -> 131
            of 136 in their bins (within main's interval), 1,553 -> 1,548 items per hour
            (docs/HISTORY.md, 2026-11-29, fifth round). Over all 20 tune layouts at 0.5:
            612/638, 1,472 items per hour, 1,386 in real time; at None 616/638, 1,499 and
            1,420: None, every bounds searched, is the default; 0.5 is kept to measure.
        release_budget: with the release search, a decision's work budget: once it has
            timed this many release candidates (each a carry timed as the cell makes it,
            counted over every grip side, facing and release bounds it searches) and has
            a release that holds, it times no more and searches no further facing, release
            bounds or grip side, keeping the soonest release it timed; before it has one
            it goes on as without a budget, so no item is left without a throw it would
            have had. A count, not a clock: the same decisions on any machine. None: no
            budget (every search as before). The demo's throws time 2-7 candidates a
            decision, the chosen one first timed 1st-7th; tune layout 0's 1-12. At 3 the
            demo's decide CPU p95 2.09 -> 1.34 s (24/24, 1,508 -> 1,538 items per hour),
            but tune layout 0 (Panda and UR5) 1,401 -> 1,278 items per hour (65/66 both);
            at 5 the demo's p95 2.02 s, tune layout 0's Panda 1,435 -> 1,369: None is the
            default, the constant kept to measure (docs/HISTORY.md, 2026-12-01, branch
            plan21).
        face_turn_max_rad: [rad] a throw's release turns from its bin toward the pick station
            at most this far (random layout 16: turned up to 90°, six 60 mm cylinders
            bounced out of a 55 mm rim bin),
        face_min_off_rad: [rad] for a bin at least this far round from the station (70°
            before; from 30° with the release search: random layouts 0-19, 1,474 -> 1,507
            items per hour with the 2 cm rise),
        face_throw_stretch: lengthening the throw at most this much (random layout 16).
        steep_rim_m: [m] a throw into a bin whose rim is lower than this is planned first
            with the throw axis at least steep_elevation_rad up (`cell.arm.steep.
            steep_tiers`; the ordinary bounds where the band does not reach so
            steeply). On the tune layouts, 15 of the 22 items that missed their bin had
            landed within 3 cm of their aim in a bin with a 0.050-0.068 m rim (nearly
            always empty), coming down at 50-58°, and skipped off its floor over the far
            rim (their centres rose to 0.09-0.15 m); none missed so over a higher rim (the
            next, 0.086 and 0.088 m, missed off a pile). Chosen above the highest of those.
        steep_elevation_rad: [rad] the least throw-axis elevation of those throws: at 60°
            those of layouts 8, 14 and 16 came down at 69-74° and stayed in their bins.
            Tune layouts 0, 2, 8, 10, 14, 16: 183 -> 194 of 201 in their bins; tune 0-3
            132 -> 133 of 136, 303.5 -> 320.2 s simulated (a near low bin thrown at
            steeply is slower to reach; docs/HISTORY.md, branch grip8).
        steep_twist_max_rad: [rad] a steep plan for an item held at points (a sphere, a
            mesh) is kept only where its carry turns the grip at most this far off the one
            rotation between its ends (`cell.arm.steep.steep_shortfall`; a box's is judged
            by its grip use held still, as an ordinary plan's): on random layout 4 a 43 mm
            sphere's steep releases behind the arm were reached only off the level swing
            (112-121° so measured; 52° and 132° in the scene), its ordinary ones 21-31°
            (tests/test_swing_twist.py); the tune layouts' steep sphere and rock carries
            that fell short turned it 47-132° (docs/HISTORY.md, branch grip9).

    The flywheel (`learn`): an object's correction stays within x1/1.5 … x1.5 of reach and
    ±10° of turn; a class's (shape's, for objects never thrown before) within ±15 % and ±3°.

    The grip (`cell.arm.grip_limits.carry_safety`):
        point_hold_margin: the multiple of its weight the pads must hold an item they hold
            at points (a sphere, a mesh) with, to carry it at all (a box or a cylinder,
            held by its faces, needs the carry's bound, CARRY_MARGIN = 1.35, and is carried
            as slowly as its grip asks). Measured in the scene: an 88 mm, 182 g sphere the
            pads hold with 1.4 x its weight at the shortest stroke (at their edges below
            its equator, `cell.model.grip.grip_friction`) left the pads on all four of its
            carries of random layout 7, accepted under 1.35 (tests/test_envelope_edges.py);
            the meshes carried at 1.6 (eggs, teddies, rocks: random layouts 0-19) held.

    The physical pick (`pick="physical"`), measured on the demo's objects in the scene
    (tests/test_physical_pick.py):
        pick_scatter_m: [m] items come to rest within ± this of the station's centre.
        approach_m: [m] the carriage's face this far above the item's top ends the approach.
        descent_mps: [m/s] speed of the guarded descent onto the item.
        finger_clearance_m: [m] each open pad this far outside the item's gripping width.
        press_m: [m] the guarded descent ends this far into the item's box (it stops at
            contact; a mesh whose top lies lower is gripped there).
        grip_ik_tol: ([m], [rad]) the grip's pose over the item (pads a fraction of a degree
            off the item's sides close on its edges).
        replan_m, replan_rad: an item found this far from where the approach aimed gets a
            new approach before the descent.
        max_tilt_rad: [rad] the grip's approach leans at most this far from vertical.
        grip_leans: fractions of an item's tilt the approach follows, tried in turn.
        touch_gap_m: [m] the pads close with the carriage's face this far above the top.
        pad_tip_clearance_m: [m] … or with the pads' tips this far above the station.
        lift_check_m, lift_check_s: the first lift, [m] in [s], shows whether the pads hold.
        pick_attempts: a failed grasp is tried again while the item is on the station.
    """

    settle_s: float = 0.0
    pick_stroke_m: float = 0.045
    lift_m: float = 0.15
    lift_max_dq_rad: float = 1.0
    departure_lifts_m: tuple[float, ...] = (0.0, 0.01, 0.02, 0.04)
    departure_clear_m: float = 0.02
    pick_over_clearance_m: float = 0.01
    place_clearance_m: float = 0.02
    place_spots_tried: int = 8
    swing_waypoints: int = 2
    swing_waypoints_max: int = 8
    swing_check_samples: int = 60
    grip_use_tie: float = 0.02
    swing_max_detour: float = 2.5
    ik_out_of_reach_m: float = 5e-3
    ik_give_up: tuple[int, float] | None = (6, 30.0)
    ik_reach_kept: bool = True
    ik_solutions: int = 3
    ik_polish: int = 0
    ik_warm: tuple[float, float] | None = (1e-3, math.radians(0.5))
    release_fallbacks: tuple[tuple[float, float], ...] = (
        (math.radians(45.0), 0.7),
        (math.radians(30.0), 0.6),
    )
    release_box_shrinks: tuple[float, ...] = (0.75, 0.9)
    approach_weight: float = 0.25
    release_timed_max: int = 2
    release_rank_way: bool = True
    release_timed_max_lower: int | None = 1
    release_lower_room_s: float | None = None
    release_budget: int | None = None
    face_turn_max_rad: float = math.radians(90.0)
    face_min_off_rad: float = math.radians(30.0)
    face_throw_stretch: float = 1.10
    steep_rim_m: float = 0.08
    steep_elevation_rad: float = math.radians(60.0)
    steep_twist_max_rad: float = math.radians(45.0)
    learn_max_log_ratio: float = math.log(1.5)
    learn_max_turn_rad: float = math.radians(10.0)
    learn_class_max_log_ratio: float = math.log(1.15)
    learn_class_max_turn_rad: float = math.radians(3.0)
    point_hold_margin: float = 1.6
    pick_scatter_m: float = 0.03
    approach_m: float = 0.02
    descent_mps: float = 0.1
    finger_clearance_m: float = 0.01
    press_m: float = 0.003
    grip_ik_tol: tuple[float, float] = (1e-4, math.radians(0.02))
    replan_m: float = 1e-3
    replan_rad: float = math.radians(1.0)
    max_tilt_rad: float = math.radians(25.0)
    grip_leans: tuple[float, ...] = (1.0, 0.8, 0.6, 0.4, 0.2, 0.0)
    touch_gap_m: float = 5e-4
    pad_tip_clearance_m: float = 5e-4
    lift_check_m: float = 0.03
    lift_check_s: float = 0.2
    pick_attempts: int = 2


TUNING = ArmTuning()  # the defaults: `cell run` and `cell bench sort` use these
