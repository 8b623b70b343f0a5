"""What every part of the arm shares: the state of one arm in one scene.

The parts (`cell.arm.kinematics`, `routes`, `mover`, `pick`, `place`, `planner`, `release`,
`grip_limits`, `flywheel`) are put together by the facade `cell.orchestrator.Orchestrator`,
which sets this state up; each part reads it and calls the others through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from cell.arm.tuning import ArmTuning
from cell.model.objects import ObjectParams
from cell.params import ModelParams

__all__ = ["ArmBase", "check_speed_scale"]


def check_speed_scale(scale: float, robot: str | None, option: str = "speed_scale") -> None:
    """InvalidInput unless `scale` (the fraction of its joint velocity and acceleration
    limits the arm's moves use) is in (0, 1] and, for the arm `robot` (a name or a mount
    file; None: not checked), leaves its slowest joint's acceleration limit at
    `cell.robot.mount.MIN_ACCELERATION` or more: what a mount file may give at the least.
    Slower, a move's timing and stepping grow as 1/scale (at 1e-9 the first move asked for
    a 5.8 TiB array; at 1e-3 a one-item run took minutes and gigabytes)."""
    from cell.errors import InvalidInput

    if not 0.0 < scale <= 1.0:
        raise InvalidInput(f"{option} {scale}: give a fraction in (0, 1]")
    if robot is None:
        return
    from cell.robot.mount import MIN_ACCELERATION, load_mount

    slowest = min(load_mount(robot).acceleration_limits)
    least = MIN_ACCELERATION / slowest
    if scale < least:
        raise InvalidInput(
            f"{option} {scale:g}: the {robot} arm's slowest joint (an acceleration limit of "
            f"{slowest:g} rad/s²) would accelerate at {scale * slowest:.3g} rad/s², under the "
            f"{MIN_ACCELERATION:g} rad/s² a mount file may give at the least (docs/arms.md); "
            f"give {math.ceil(least * 1e4) / 1e4:g} to 1 for this arm"
        )


class ArmBase:
    """The arm's shared state (set up by `Orchestrator.__init__`).

    Attributes:
        tuning: the arm's constants (`cell.arm.tuning.ArmTuning`).
        params: the model parameters plans are made with.
        robot: the arm's kinematic model (`cell.robot.model.Robot`).
        scene: the plant (`cell.sim.CellScene`).
        ee: the plant's end-effector; `effector` commands it (and any hardware in step).
        q: where the arm is [rad].
        speed_scale: fraction of the joint limits the arm's moves use.
        pick_mode, release_mode: "kinematic" or "physical"; "auto" or "static".
        turn_release, cycle_search, learn, floor: the run's options (`Orchestrator`).
        on_moved: called after every move the mover makes (the loop's landing hook).
    """

    tuning: ArmTuning
    params: ModelParams
    robot: Any
    scene: Any
    ee: Any
    effector: Any
    q: np.ndarray
    speed_scale: float
    pick_mode: str
    release_mode: str
    turn_release: bool
    cycle_search: bool
    learn: bool
    floor: bool
    bounds: Any
    residual: Any
    on_moved: Callable[[], None]
    job: Any
    floors: dict[int, tuple[float, float]]
    corrections: dict[str, Any]
    _carried: tuple[ObjectParams, float]
    _grip_stroke: float
    _frame: tuple[float, float] | None
    _presented: Any
    _index: int
    _placing: bool
    _ik_memo: dict[tuple[bytes, ...], Any]
    _out_of_reach: dict[tuple[bytes, ...], Any]
    _ik_solved: dict[tuple[bytes, ...], Any]
    _ik_warm: Any
    _far_poses: Any
    _moving_kept: dict[bytes, Any]
    _approach_memo: dict[tuple[Any, ...], float]
    _approach_plans: dict[tuple[Any, ...], tuple[Any, str]]
    _plan_memo: dict[tuple[Any, ...], Any]
    _timed_n: int = 0  # release candidates timed in this decision (`_new_decision`)
    # what IK searches asked and kept while a forked branch is searched (`cell.arm.fork`,
    # `Kinematics._ik_keep`); None: not recorded
    _ik_log: list[tuple[Any, ...]] | None = None

    def _new_decision(self) -> None:
        """Forget what a decision keeps only for itself (`Orchestrator.decide` calls it
        first): its IK answers and warm starts, approaches timed, paths and carries planned,
        and the release candidates it has timed (`release_budget`)."""
        self._ik_memo.clear()
        self._ik_warm.clear()
        self._approach_memo.clear()
        self._approach_plans.clear()
        self._plan_memo.clear()
        self._timed_n = 0

    def _budget_spent(self) -> bool:
        """Has this decision timed `ArmTuning.release_budget` release candidates or more
        (`ReleaseChoice._release_search`)? Never where the budget is None."""
        most = self.tuning.release_budget
        return most is not None and self._timed_n >= most

    if TYPE_CHECKING:  # the parts call each other through the facade that joins them

        def __getattr__(self, name: str) -> Any: ...
