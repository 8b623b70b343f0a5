"""The fastest carry that keeps the item in the grip (`plan_carry`): the path at the joint
limits, slowed uniformly (bisection on a time scale), or shaped by the grip as a toppra
constraint, or, where no time scaling holds it, gentle."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence

import numpy as np

from cell.errors import TrajectoryError
from cell.model.params import G
from cell.robot.grip_constraint import grip_constraint
from cell.robot.grip_hold import (
    _GRAVITY,
    CARRY_MARGIN,
    GENTLE_SCALE,
    TILT_SLOWS_OVER,
    GripHold,
    carry_use,
    grip_use,
    motion_use,
    rest_force,
    sampled_motion,
    tilt_use,
    uses,
)
from cell.robot.model import Robot
from cell.robot.trajectory import Trajectory

log = logging.getLogger(__name__)


def plan_carry(
    waypoints_q: Sequence[np.ndarray],
    robot: Robot,
    hold: GripHold,
    *,
    margin: float = CARRY_MARGIN,
    velocity_scale: float = 1.0,
    acceleration_scale: float = 1.0,
    iterations: int = 6,
    shape: bool = True,
    tie: float = 0.0,
    gentle_floor: bool = False,
) -> tuple[Trajectory, float]:
    """The fastest path through the waypoints that keeps the item in the grip: at the
    joint limits if the grip holds it there; else the faster of the path slowed
    uniformly (bisection on a time scale) and, with `shape`, the path slowed only where
    the grip asks it (toppra with `grip_constraint`).

    Args:
        waypoints_q: joint waypoints [rad] (the first is where the arm is).
        robot: the arm.
        hold: what the pads hold the item with (`GripHold`).
        margin: the grip's capacity over the most a carry may use of it (≥ 1).
        velocity_scale, acceleration_scale: the fastest scales to try, in (0, 1].
        iterations: bisection steps on the time scale s.
        shape: also try the path shaped by the grip as a toppra constraint.
        tie: where no time scaling keeps within 1/margin, the fastest within
            1/margin + tie is taken before a gentle carry (0: never).
        gentle_floor: never slower than the path at GENTLE_SCALE of the limits (where the
            path at rest asks nearly all the bound, a carry within it would crawl).

    The grip's tilt (an item held by its faces: `GripHold.torque_y_nm`) is counted after:
    where the path so timed asks more than TILT_SLOWS_OVER of the grip with the tilt
    (`tilt_use`), it is planned again keeping its use with the tilt within the bound
    (`carry_use`: or within what the path asks held still, a level swing past the
    horizontal), and the slower of the two is taken. Any other carry is timed as without
    the tilt (so are the routes `_soonest` compares by it); one the tilt binds is slowed,
    never sped up: left out, carries that asked 0.73 without the tilt and 1.23 with it
    dropped their items (issue 59).

    Returns:
        (the trajectory, its peak use of the grip, `grip_use`; the tilt counted where it
        was slowed for it): at most 1/margin (or 1/margin + tie), or, when
        no time scaling gets it there (the path asks too much), the path at GENTLE_SCALE
        of the limits (logged); with `gentle_floor`, that path wherever it is sooner.

    Raises:
        TrajectoryError: the grip cannot hold the weight within the margin; toppra fails.
    """
    args = (waypoints_q, robot, hold, margin, velocity_scale, acceleration_scale, iterations)
    plain = _plan(*args, shape, tie, gentle_floor, None)
    if hold.torque_y_nm <= 0.0:
        return plain
    # the grip's tilt counted: the carry is slowed only where it would tip the item
    tipping = tilt_use(plain[0], robot, hold)
    if tipping <= TILT_SLOWS_OVER:
        return plain
    log.info("the carry's use with the grip's tilt %.3f: slowed within its bound", tipping)
    tilted = _plan(*args, shape, tie, gentle_floor, margin)
    return tilted if tilted[0].duration > plain[0].duration else plain


def _plan(
    waypoints_q: Sequence[np.ndarray],
    robot: Robot,
    hold: GripHold,
    margin: float,
    velocity_scale: float,
    acceleration_scale: float,
    iterations: int,
    shape: bool,
    tie: float,
    gentle_floor: bool,
    tilt: float | None,
) -> tuple[Trajectory, float]:
    """`plan_carry`'s path within 1/margin of the grip's force-and-twist use (`tilt`
    None), or of its use with the tilt counted (`tilt`: the margin, `carry_use`)."""
    bound = _bound(hold, margin)
    scaled = _TimeScaled(
        waypoints_q, robot, hold, velocity_scale, acceleration_scale, iterations, tilt
    )
    best = _fastest_within(scaled, bound, shape, tie)
    if gentle_floor:
        # the path at GENTLE_SCALE is planned once (`attempt` remembers it): where no
        # time scaling held the item, the carry above is that same path already
        return _sooner(scaled.attempt(GENTLE_SCALE), best)
    return best


def _fastest_within(
    scaled: _TimeScaled, bound: float, shape: bool, tie: float
) -> tuple[Trajectory, float]:
    """`plan_carry` without its gentle floor: the fastest of `scaled`'s path within the
    grip's `bound` (with `tie`), shaped by the grip where that is sooner, else gentle."""
    waypoints_q, robot, hold = scaled.waypoints_q, scaled.robot, scaled.hold
    velocity_scale, acceleration_scale = scaled.velocity_scale, scaled.acceleration_scale
    tilt = scaled.margin
    best = scaled.attempt(1.0)
    if best[1] <= bound:
        return best
    scales = (velocity_scale, acceleration_scale)
    shaped = _shaped(waypoints_q, robot, hold, bound, tilt, *scales) if shape else None
    # the grip's use at full speed was read off the same samples the dilation scales
    dilated = _Dilated(best[0], robot, hold, margin=tilt, motion=scaled.motion(1.0))
    best = scaled.fastest(bound, best, dilated)
    if best[1] > bound and tie > 0.0:
        # Not even a slow move keeps within the bound. Where the path at rest asks no
        # more than `tie` over it, the fastest within bound + tie (the pads held 0.74-0.78
        # of their static limit accelerated, see CARRY_MARGIN), rather than gently
        best = scaled.fastest(bound + tie, best, dilated)
        if best[1] <= bound + tie:
            log.info("the carry's path asks %.3f of the grip at best (bound %.3f)", best[1], bound)
            return _sooner(shaped, best)
    if best[1] > bound:
        # Not even a slow move keeps within the bound: the path itself (not its speed)
        # asks too much, e.g. it rolls a tall hanging item sideways. Carry it gently.
        best = scaled.gentle(bound)
    if shaped is not None and (best[1] > bound or shaped[0].duration < best[0].duration):
        return shaped
    return best


def _bound(hold: GripHold, margin: float) -> float:
    """The most of the grip a carry may use, 1/margin; TrajectoryError if the item's weight
    alone asks more."""
    bound = 1.0 / margin
    if hold.mass_kg * G / hold.force_n > bound:
        raise TrajectoryError(
            f"the grip holds {hold.force_n:.2f} N; the item's weight alone asks "
            f"{hold.mass_kg * G:.2f} N, more than 1/{margin} of it: the item cannot be carried"
        )
    return bound


def _sooner(
    a: tuple[Trajectory, float] | None, b: tuple[Trajectory, float]
) -> tuple[Trajectory, float]:
    """a if there is one and it ends sooner than b, else b."""
    return a if a is not None and a[0].duration < b[0].duration else b


class _TimeScaled:
    """`plan_carry`'s path time-scaled by s (velocity limits × √s, acceleration limits × s)
    and the bisection on s for the fastest within a use of the grip."""

    slowest = 0.02  # the smallest time scale a bisection step tries

    def __init__(
        self,
        waypoints_q: Sequence[np.ndarray],
        robot: Robot,
        hold: GripHold,
        velocity_scale: float,
        acceleration_scale: float,
        iterations: int,
        margin: float | None = None,
    ) -> None:
        self.waypoints_q, self.robot, self.hold = waypoints_q, robot, hold
        self.margin = margin  # None: the force-and-twist use; else the tilt counted
        self.velocity_scale, self.acceleration_scale = velocity_scale, acceleration_scale
        self.iterations = iterations
        self._planned: dict[float, tuple[Trajectory, float]] = {}
        # each plan's `sampled_motion`, its use read off it (`_Dilated` scales 1.0's)
        self._motion: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def attempt(self, s: float) -> tuple[Trajectory, float]:
        """The path planned at time scale s, and its use of the grip (`grip_use`; with
        `margin`, the tilt counted: `carry_use`); remembered: the same scale is the same
        plan (toppra is deterministic)."""
        from cell.robot.motion import plan_path

        if s not in self._planned:
            tr = plan_path(
                self.waypoints_q,
                self.robot,
                velocity_scale=self.velocity_scale * math.sqrt(s),
                acceleration_scale=self.acceleration_scale * s,
            )
            motion = sampled_motion(tr, self.robot, self.hold)
            self._planned[s] = (tr, motion_use(motion, self.hold, self.margin))
            self._motion[s] = motion
        return self._planned[s]

    def motion(self, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`sampled_motion` of the path `attempt` planned at time scale s (planned first if
        it was not): the item's motion at `grip_use`'s 201 instants."""
        self.attempt(s)
        return self._motion[s]

    def gentle(self, bound: float) -> tuple[Trajectory, float]:
        """The path at GENTLE_SCALE of the limits and its use (logged: over `bound`)."""
        tr, use = self.attempt(GENTLE_SCALE)
        log.info(
            "no time scaling keeps the carry within the grip (use %.2f > %.2f even slowly): "
            "carrying at %.0f %% of the acceleration limits",
            use,
            bound,
            100 * GENTLE_SCALE,
        )
        return tr, use

    def bisect(self, fits: Callable[[float], bool]) -> float | None:
        """The largest time scale of `iterations` bisection steps that `fits`; None if none."""
        lo, hi, found = 0.0, 1.0, None
        for _ in range(self.iterations):
            mid = max(self.slowest, 0.5 * (lo + hi))
            if fits(mid):
                lo, found = mid, mid
            else:
                hi = mid
        return found

    def fastest(
        self, limit: float, best: tuple[Trajectory, float], dilated: _Dilated
    ) -> tuple[Trajectory, float]:
        """Bisection on the time scale for the fastest attempt within `limit` (else
        `best`). Each step's use is the full-speed path's, dilated (`_Dilated`: what
        `attempt` would plan and measure at that scale, without planning it); the scale
        found is then planned and measured as before, and where that plan's use is over
        the limit after all, the bisection is made again planning every step. Where no
        scale tried is within the limit (the path's geometry asks too much even slowly),
        `best`."""
        found = self.bisect(lambda s: dilated.use(s) <= limit)
        if found is None:
            return best
        tr, use = self.attempt(found)
        if use <= limit:
            return tr, use
        log.debug("the dilated use at scale %.4f was under %.4f, planned %.4f", found, limit, use)
        planned: dict[float, tuple[Trajectory, float]] = {}

        def fits(s: float) -> bool:
            planned[s] = self.attempt(s)
            return planned[s][1] <= limit

        found = self.bisect(fits)
        return best if found is None else planned[found]


class _Dilated:
    """The grip's use along a path time-scaled by s (`plan_carry`'s `attempt`), from one
    set of samples of it at full speed.

    `plan_path` at velocity limits × √s and acceleration limits × s is the full-speed
    path dilated in time: q_s(t) = q(√s t), so q̇ scales by √s and q̈ by s, and the
    item's acceleration a_c = a_o + α × r + ω × (ω × r) and the grip's angular
    acceleration α by s (centripetal terms included), gravity not at all. At the same
    n instants along it as `grip_use` samples the dilated path: f_s = s R⊤a_c − R⊤g,
    α_s = s α."""

    def __init__(
        self,
        traj: Trajectory,
        robot: Robot,
        hold: GripHold,
        n: int = 201,
        margin: float | None = None,
        motion: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> None:
        # `motion`: the path's `sampled_motion` at n instants, where it was read already
        a, alpha, rots = sampled_motion(traj, robot, hold, n) if motion is None else motion
        rt = np.transpose(rots, (0, 2, 1))
        self._motion = np.einsum("kij,kj->ki", rt, a)  # R⊤a_c, scales by s
        self._weight = np.einsum("kij,j->ki", rt, _GRAVITY)  # R⊤g, does not
        self._alpha = np.einsum("kij,kj->ki", rt, alpha)
        self._rest = rest_force(rots)  # −R⊤g: held still on the path
        self._hold, self._margin = hold, margin

    def use(self, s: float) -> float:
        """`grip_use` of the path at time scale s (velocity × √s, acceleration × s)."""
        f = s * self._motion - self._weight
        if self._margin is None:
            return float(np.max(uses(f, s * self._alpha, self._hold, tilt=False)))
        return carry_use(f, s * self._alpha, self._rest, self._hold, self._margin)


def _shaped(
    waypoints_q: Sequence[np.ndarray],
    robot: Robot,
    hold: GripHold,
    bound: float,
    tilt: float | None,
    velocity_scale: float,
    acceleration_scale: float,
) -> tuple[Trajectory, float] | None:
    """The path at the joint limits with the grip as a toppra constraint
    (`grip_constraint`): slow only where the grip asks it, where a uniform time scaling
    slows all of it. Its use of the grip, sampled densely between toppra's grid points,
    is checked against the bound; over it, the constraint is tightened (twice at most).
    None when toppra finds no parameterisation (the path asks too much at rest)."""
    from cell.robot.motion import plan_path

    # toppra logs a path it cannot parameterise as a warning; here that is an expected
    # answer (the uniformly slowed path is kept), not something for the user to see
    toppra_log = logging.getLogger("toppra")
    level = toppra_log.level
    toppra_log.setLevel(logging.ERROR)
    try:
        for tighten in (1.0, 0.9, 0.8):
            try:
                tr = plan_path(
                    waypoints_q,
                    robot,
                    velocity_scale=velocity_scale,
                    acceleration_scale=acceleration_scale,
                    constraints=[grip_constraint(robot, hold, bound * tighten)],
                )
            except TrajectoryError as exc:
                log.debug("no carry shaped by the grip: %s", exc)
                return None
            use = grip_use(tr, robot, hold, n=501, margin=tilt)
            if use <= bound:
                return tr, use
        return None
    finally:
        toppra_log.setLevel(level)
