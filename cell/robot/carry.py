"""Carrying an item without letting it slip: the grip's limit on the arm's motion.

The pads hold an item of mass m with a friction force of at most F = 2 μ f_g(L_s, a)
(`cell.model.grip`). In the end-effector's frame the item feels the specific force
f = a_c − g, a_c the acceleration of its centre of mass c in the world frame W and g
gravity (0, 0, −9.81) m/s²; it stays put while m |f| ≤ F. So the grip sets a bound
on |a_c − g| [m/s²], the same for every direction (the pads' normal direction is
held by the band, the two in-plane directions by friction: bounding the magnitude is
the conservative union).

The pads also hold the item against turning about their common normal (x): each
pad's contact patch resists a torque of at most μ f_g r_t (r_t the patch's torsional
radius, the mean distance of its points from its centre), two pads 2 μ f_g r_t. The
carry asks for τ_x = m (r × f)_x + I_xx α_x about the patch centre, r the centre of
mass seen from it (a tall item's centre of mass sits above the short pads). While the
item is pressed onto the carriage (f_z > 0 in the grip's axes: the throw axis tilted
up) its base face rights it as well, with up to m f_z times half its base. A carry
is within the grip while its use of the force and of the torque together stays under
1: m |f| / F + |τ_x| / T ≤ 1/margin (each used fraction takes from the same friction).

A tall item is also tilted about y (the pads' faces' other axis) by the specific force
along the pads' normal: τ_y = m (r × f)_y + I_yy α_y = m l f_x + I_yy α_y (l the lever).
The pads resist the tilt with their pressure (each pad's normal force f_g may move to
its patch's edge, ±L_p/2: f_g L_p for both) and with their friction along the throw
axis (μ f_g on each, w apart: F w / 2): T_y = F (L_p / (2 μ) + w / 2)
(`cell.orchestrator.carry_hold`), plus m f_z w / 2 while the item is pressed onto the
carriage. Measured in the scene (`cell.sim.grip_probe`, tests/test_grip_probe.py), a
torque about y turns boxes and cylinders at 1.02-1.23 T_y. The tilt's use is not
friction's alone (the pressure takes most of it), so it adds to the rest in quadrature:
use = √((m |f| / F + |τ_x| / T)² + (|τ_y| / T_y)²) (`uses`). Measured: pushed along x
at the centre of mass, the 200 mm bottle, a tetrapack and a 100 mm cuboid slid where
that use was 0.96-1.10 (the bottle: 0.49 by m |f| / F alone), nine boxes and cylinders
where it was up to 1.8; the linear sum of the three said 1.34-2.41. A spherical or mesh
item has no T_y (held at points) and keeps the first law.

Where the tilt is counted: held still (`static_grip_use`; the orchestrator's release
elevation and swing route, `cell.orchestrator.release_grip_use`). The carry's time
scaling (`grip_use`, `grip_constraint`, `plan_carry`) keeps the force-and-twist law and
its measured margin: with the tilt there as well, the level swing of the demo's cuboid_b
(its weight on a pad as it passes horizontal) went at GENTLE_SCALE and the demo fell from
1,505 to 1,399 items per hour, where no item had slipped.

`plan_carry` finds the fastest toppra path through the waypoints whose use of the
grip stays under that bound, evaluating a_c exactly from the joint state with Pinocchio
(a_c = a_o + α × r + ω × (ω × r), o the grip centre). Two ways, the sooner is taken:
- a uniform slow-down: it time-scales the path (velocity limits × √s, acceleration
  limits × s, so that every acceleration scales by s, centripetal terms included) by
  bisection on s;
- the path shaped by the grip: toppra with the grip's bound as a second-order path
  constraint (`grip_constraint`, a polytope inside the bound), which slows the path only
  where the grip asks it. A tall box hung from the pads and carried sideways: 1.11 s
  against 1.36 s uniformly slowed (tests/test_carry.py).
"""

from __future__ import annotations

import functools
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import TrajectoryError
from cell.model.params import G
from cell.robot.model import Robot
from cell.robot.trajectory import Trajectory

__all__ = [
    "CARRY_MARGIN",
    "GripHold",
    "grip_use",
    "item_accelerations",
    "item_motion",
    "patch_torsion_radius_m",
    "peak_specific_force",
    "plan_carry",
    "static_grip_use",
    "uses",
]

# The grip's static friction force over what a carry may ask of it. Measured in the scene
# (tests/test_carry.py): accelerated, the pads hold 0.74-0.78 of what they hold at rest
# (a 30 mm box at 0.06 m stroke held at 0.74 of the static limit, slid 15 mm at 0.80).
CARRY_MARGIN = 1.35
_GRAVITY = np.array([0.0, 0.0, -G])
GENTLE_SCALE = 0.3  # time scale of a carry no scaling keeps within the grip (see plan_carry)
log = logging.getLogger(__name__)


@dataclass(frozen=True)
class GripHold:
    """What the pads hold an item with, and where the item sits.

    Attributes:
        force_n: the friction force the pads hold with, F = 2 μ f_g [N].
        torque_nm: the friction couple they resist a turn about x with, T = F r_t [N·m].
        mass_kg: the item's mass [kg].
        inertia_xx: its moment of inertia about x through its centre of mass [kg·m²].
        offset_tcp_m: its centre of mass in ee_tcp coordinates [m].
        lever_m: its centre of mass above the pads' patch centre, along z [m].
        base_half_m: half its extent along y where it stands on the carriage [m]: pressed
            onto the carriage (f_z > 0) it is kept from tipping by that face as well.
        torque_y_nm: the couple the pads resist a tilt about y with, T_y [N·m]; 0: not
            counted (a sphere or a mesh, held at points).
        inertia_yy: its moment of inertia about y through its centre of mass [kg·m²].
        base_half_x_m: half its extent along x (across the pads) on the carriage [m].
    """

    force_n: float
    torque_nm: float
    mass_kg: float
    inertia_xx: float
    offset_tcp_m: tuple[float, float, float]
    lever_m: float
    base_half_m: float = 0.0
    torque_y_nm: float = 0.0
    inertia_yy: float = 0.0
    base_half_x_m: float = 0.0


def patch_torsion_radius_m(half_y_m: float, half_z_m: float, n: int = 41) -> float:
    """Mean distance [m] of a rectangular contact patch's points from its centre: the
    arm of its friction against a turn about its normal, under even pressure."""
    y, z = np.meshgrid(np.linspace(-half_y_m, half_y_m, n), np.linspace(-half_z_m, half_z_m, n))
    return float(np.mean(np.hypot(y, z)))


def item_motion(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The specific force f = a − g [m/s²] at a point fixed in ee_tcp, and the frame's
    angular acceleration [rad/s²], both in ee_tcp axes, and ee_tcp's rotations in W.

    Returns:
        (f, alpha, rotations), shapes (k, 3), (k, 3), (k, 3, 3).
    """
    a, alpha, rots = _point_motion(robot, qs, dqs, ddqs, offset_tcp_m)
    rt = np.transpose(rots, (0, 2, 1))
    f = np.einsum("kij,kj->ki", rt, a - _GRAVITY)
    return f, np.einsum("kij,kj->ki", rt, alpha), rots


def grip_use(traj: Trajectory, robot: Robot, hold: GripHold, n: int = 201) -> float:
    """The largest use of the grip along a trajectory: m |f| / F + |τ_x| / T (the tilt
    about y is not counted here, see the module docstring), sampled at n instants; ≤ 1 is
    within what the pads hold."""
    ts = np.linspace(0.0, traj.duration, n)
    qs, dqs, ddqs = traj.sample_many(ts)
    f, alpha, _ = item_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)
    return float(np.max(uses(f, alpha, hold, tilt=False)))


def static_grip_use(robot: Robot, hold: GripHold, qs: np.ndarray) -> np.ndarray:
    """The use of the grip (`uses`, the tilt about y included) at each configuration of
    qs [rad], shape (k, dof), held still: what gravity alone asks of the pads there,
    shape (k,). A path whose slowest carry would still ask more than the grip holds has
    it over 1/margin somewhere."""
    zeros = np.zeros_like(qs)
    f, alpha, _ = item_motion(robot, qs, zeros, zeros, hold.offset_tcp_m)
    return uses(f, alpha, hold)


def uses(f: np.ndarray, alpha: np.ndarray, hold: GripHold, tilt: bool = True) -> np.ndarray:
    """The grip's use at each instant (the module docstring), from the specific force f
    [m/s²] and the angular acceleration α [rad/s²], both in ee_tcp axes, shape (k, 3)."""
    force = hold.mass_kg * np.linalg.norm(f, axis=1) / hold.force_n
    # (r × m f)_x with r = (0, 0, lever): −lever · m f_y; plus I_xx α_x
    tau = -hold.lever_m * hold.mass_kg * f[:, 1] + hold.inertia_xx * alpha[:, 0]
    # pressed onto the carriage, the item's base face rights it too
    press = hold.mass_kg * np.maximum(f[:, 2], 0.0)
    cap = hold.torque_nm + press * hold.base_half_m
    # Pads without a couple (a mesh the probe does not hold as a face, a large sphere held
    # at points) give an unbounded use wherever the path turns the item: such carries go
    # at GENTLE_SCALE. Tried and left out: bounding them by the force alone (3-4 s faster
    # per carry); on random layout 4 four teddy throws then missed their bins by
    # 0.17-0.20 m (0.01-0.12 m before), and on layout 3 two 72 mm, 102 g spheres left the
    # pads (UR5). A mesh the kinematic pick seated is given the couple the scene measures
    # (cell.orchestrator.carry_hold).
    turn = np.abs(tau) / np.maximum(cap, 1e-12)
    if not tilt or hold.torque_y_nm <= 0.0:
        return np.asarray(force + turn)
    # (r × m f)_y = lever · m f_x; plus I_yy α_y; the base face rights this tilt as well
    tip = np.abs(hold.lever_m * hold.mass_kg * f[:, 0] + hold.inertia_yy * alpha[:, 1])
    tip = tip / (hold.torque_y_nm + press * hold.base_half_x_m)
    return np.asarray(np.hypot(force + turn, tip))


def item_accelerations(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
) -> np.ndarray:
    """World accelerations [m/s², W] of a point fixed in the ee_tcp frame.

    Args:
        robot: the arm.
        qs, dqs, ddqs: joint states, each shape (k, dof) [rad, rad/s, rad/s²].
        offset_tcp_m: the point in ee_tcp coordinates [m] (the item's centre of mass).

    Returns:
        Shape (k, 3).
    """
    return _point_motion(robot, qs, dqs, ddqs, offset_tcp_m)[0]


def _point_motion(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(acceleration of the point [m/s², W], ee_tcp's angular acceleration [rad/s², W],
    ee_tcp's rotations in W), shapes (k, 3), (k, 3), (k, 3, 3):
    a = a_o + α × r + ω × (ω × r), from Pinocchio's frame kinematics."""
    import pinocchio as pin

    m, d, fr = robot.model, robot.data, robot.tcp_frame
    r_local = np.asarray(offset_tcp_m, float)
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    k = len(qs)
    a_o, alphas, ws, r = np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 3))
    rots = np.empty((k, 3, 3))
    for i, (q, dq, ddq) in enumerate(zip(qs, dqs, ddqs, strict=True)):
        pin.forwardKinematics(m, d, q, dq, ddq)
        pin.updateFramePlacements(m, d)
        a_o[i] = pin.getFrameClassicalAcceleration(m, d, fr, lwa).linear
        alphas[i] = pin.getFrameAcceleration(m, d, fr, lwa).angular
        ws[i] = pin.getFrameVelocity(m, d, fr, lwa).angular
        rots[i] = d.oMf[fr].rotation
        r[i] = rots[i] @ r_local
    # the cross products over all instants at once (one np.cross per row cost 3x the
    # kinematics: np.cross's axis handling dominates for single 3-vectors)
    acc = a_o + np.cross(alphas, r) + np.cross(ws, np.cross(ws, r))
    return acc, alphas, rots


def peak_specific_force(
    traj: Trajectory,
    robot: Robot,
    offset_tcp_m: Sequence[float] = (0.0, 0.0, 0.0),
    n: int = 201,
) -> float:
    """The largest |a_c − g| [m/s²] along a trajectory, sampled at n instants."""
    ts = np.linspace(0.0, traj.duration, n)
    qs, dqs, ddqs = traj.sample_many(ts)
    acc = item_accelerations(robot, qs, dqs, ddqs, offset_tcp_m)
    return float(np.max(np.linalg.norm(acc - _GRAVITY, axis=1)))


@functools.lru_cache(maxsize=4)
def _sphere_directions(n: int = 128) -> tuple[np.ndarray, float]:
    """n unit vectors spread over the sphere (a Fibonacci lattice) and their cover c:
    every unit vector u has max_k n_k·u ≥ c, so |f| ≤ max_k n_k·f / c (checked on a
    dense sample of directions)."""
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(1.0 - z * z)
    dirs = np.c_[r * np.cos(phi), r * np.sin(phi), z]
    dirs.setflags(write=False)  # cached and shared by every carry in the process
    u = _sphere_sample(20000)
    # less a margin for the directions between the samples (the cover's error is below
    # the sample's spacing squared, about 1e-3)
    return dirs, float(np.min(np.max(u @ dirs.T, axis=1))) - 0.005


def _sphere_sample(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    v = rng.normal(size=(n, 3))
    return np.asarray(v / np.linalg.norm(v, axis=1, keepdims=True))


def grip_constraint(robot: Robot, hold: GripHold, bound: float) -> Any:
    """The grip as a toppra path constraint: w = (f [m/s², ee_tcp], τ_x [N·m]) at the
    item's centre of mass, affine in q̈ and quadratic in q̇ as toppra's second-order
    constraints are, kept inside a polytope within m |f| / F + |τ_x| / T ≤ bound: for
    every direction n_k of `_sphere_directions` and sign σ,
    m (n_k·f) / (c F) + σ τ_x / T ≤ bound. Inner, so conservative: the couple the
    item's base adds when pressed onto the carriage is left out, and the force's share
    by the cover c (≈ 0.97). With no couple to count on (T = 0) the item must not be
    asked to turn at all, which no path does: toppra then finds no parameterisation.
    """
    import toppra.constraint as constraint

    dirs, cover = _sphere_directions()
    rows = [np.r_[hold.mass_kg * d / (cover * hold.force_n), sg] for d in dirs for sg in (1, -1)]
    coef = np.array(rows)
    if hold.torque_nm > 0.0:
        coef[:, 3] /= hold.torque_nm
    else:
        coef[:, 3] *= 1e6  # [1/(N·m)]: no couple, no turn (a stiff stand-in for τ_x = 0)
    g = np.full(len(rows), bound)

    def inv_dyn_many(qs: np.ndarray, dqs: np.ndarray, ddqs: np.ndarray) -> np.ndarray:
        f, alpha, _ = item_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)
        tau = -hold.lever_m * hold.mass_kg * f[:, 1] + hold.inertia_xx * alpha[:, 0]
        return np.c_[f, tau]

    def inv_dyn(q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> np.ndarray:
        return inv_dyn_many(q[None], dq[None], ddq[None])[0]

    return _grip_constraint_class()(
        inv_dyn,
        lambda q: coef,
        lambda q: g,
        dof=robot.dof,
        discretization_scheme=constraint.DiscretizationType.Interpolation,
        inv_dyn_many=inv_dyn_many,
    )


@functools.cache
def _grip_constraint_class() -> type:
    """toppra's SecondOrderConstraint with its coefficients computed over all grid points
    at once (`inv_dyn_many`), where toppra calls the inverse dynamics once a grid point
    (three times over): the same a, b, c (tests/test_carry.py), a third of the time of a
    carry's planning shaped by the grip before (toppra 0.6's
    `compute_constraint_params`, whose discretisation this keeps)."""
    import toppra.constraint as constraint
    from toppra.constraint.linear_constraint import canlinear_colloc_to_interpolate

    class GripConstraint(constraint.SecondOrderConstraint):  # type: ignore[misc]
        def __init__(self, *args: Any, inv_dyn_many: Any, **kw: Any) -> None:
            super().__init__(*args, **kw)
            self.inv_dyn_many = inv_dyn_many

        def compute_constraint_params(self, path: Any, gridpoints: np.ndarray) -> Any:
            if path.dof != self.dof:
                raise ValueError(f"constraint dof {self.dof} is not the path's {path.dof}")
            p_vec = path(gridpoints)
            ps_vec = path(gridpoints, 1)
            pss_vec = path(gridpoints, 2)
            zeros = np.zeros_like(p_vec)
            f_vec = np.array(list(map(self.constraint_F, p_vec)))
            g_vec = np.array(list(map(self.constraint_g, p_vec)))
            c_vec = self.inv_dyn_many(p_vec, zeros, zeros)
            a_vec = self.inv_dyn_many(p_vec, zeros, ps_vec) - c_vec
            b_vec = self.inv_dyn_many(p_vec, ps_vec, pss_vec) - c_vec
            return canlinear_colloc_to_interpolate(
                a_vec, b_vec, c_vec, f_vec, g_vec, None, None, gridpoints
            )

    return GripConstraint


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
        gentle_floor: never slower than the path at GENTLE_SCALE of the limits (a hold
            that only speeds up what was a gentle carry: where the path at rest asks
            nearly all the bound allows, the fastest uniform carry within it crawls).

    Returns:
        (the trajectory, its peak use of the grip, `grip_use`): at most 1/margin (or
        1/margin + tie), or, when no time scaling gets it there (the path's geometry
        asks too much), the path at GENTLE_SCALE of the limits and its use (logged);
        with `gentle_floor`, that path wherever it is sooner.

    Raises:
        TrajectoryError: the grip cannot hold the item's weight alone within the
            margin, or toppra fails.
    """
    from cell.robot.motion import plan_path

    bound = 1.0 / margin
    if hold.mass_kg * G / hold.force_n > bound:
        raise TrajectoryError(
            f"the grip holds {hold.force_n:.2f} N; the item's weight alone asks "
            f"{hold.mass_kg * G:.2f} N, more than 1/{margin} of it: the item cannot be carried"
        )

    def attempt(s: float) -> tuple[Trajectory, float]:
        tr = plan_path(
            waypoints_q,
            robot,
            velocity_scale=velocity_scale * math.sqrt(s),
            acceleration_scale=acceleration_scale * s,
        )
        return tr, grip_use(tr, robot, hold)

    if gentle_floor:
        best = plan_carry(
            waypoints_q,
            robot,
            hold,
            margin=margin,
            velocity_scale=velocity_scale,
            acceleration_scale=acceleration_scale,
            iterations=iterations,
            shape=shape,
            tie=tie,
        )
        gentle = attempt(GENTLE_SCALE)
        return gentle if gentle[0].duration < best[0].duration else best

    best = attempt(1.0)
    if best[1] <= bound:
        return best
    shaped = None
    if shape:
        shaped = _shaped(waypoints_q, robot, hold, bound, velocity_scale, acceleration_scale)
    slowest = 0.02

    dilated = _Dilated(best[0], robot, hold)

    def bisect(fits: Callable[[float], bool]) -> float | None:
        """The largest time scale of `iterations` bisection steps that `fits`; None if none."""
        lo, hi, found = 0.0, 1.0, None
        for _ in range(iterations):
            mid = max(slowest, 0.5 * (lo + hi))
            if fits(mid):
                lo, found = mid, mid
            else:
                hi = mid
        return found

    def fastest(limit: float, best: tuple[Trajectory, float]) -> tuple[Trajectory, float]:
        """Bisection on the time scale for the fastest attempt within `limit` (else
        `best`). Each step's use is the full-speed path's, dilated (`_Dilated`: what
        `attempt` would plan and measure at that scale, without planning it); the scale
        found is then planned and measured as before, and where that plan's use is over
        the limit after all, the bisection is made again planning every step. Where no
        scale tried is within the limit (the path's geometry asks too much even slowly),
        `best`."""
        found = bisect(lambda s: dilated.use(s) <= limit)
        if found is None:
            return best
        tr, use = attempt(found)
        if use <= limit:
            return tr, use
        log.debug("the dilated use at scale %.4f was under %.4f, planned %.4f", found, limit, use)
        planned: dict[float, tuple[Trajectory, float]] = {}

        def fits(s: float) -> bool:
            planned[s] = attempt(s)
            return planned[s][1] <= limit

        found = bisect(fits)
        return best if found is None else planned[found]

    best = fastest(bound, best)
    if best[1] > bound and tie > 0.0:
        # Not even a slow move keeps within the bound. Where the path at rest asks no
        # more than `tie` over it, the fastest within bound + tie (the pads held 0.74-0.78
        # of their static limit accelerated, see CARRY_MARGIN), rather than gently
        best = fastest(bound + tie, best)
        if best[1] <= bound + tie:
            log.info("the carry's path asks %.3f of the grip at best (bound %.3f)", best[1], bound)
            if shaped is not None and shaped[0].duration < best[0].duration:
                return shaped
            return best
    if best[1] > bound:
        # Not even a slow move keeps within the bound: the path itself (not its speed)
        # asks too much, e.g. it rolls a tall hanging item sideways. Carry it gently.
        tr, use = attempt(GENTLE_SCALE)
        log.info(
            "no time scaling keeps the carry within the grip (use %.2f > %.2f even slowly): "
            "carrying at %.0f %% of the acceleration limits",
            use,
            bound,
            100 * GENTLE_SCALE,
        )
        best = (tr, use)
    if shaped is not None and (best[1] > bound or shaped[0].duration < best[0].duration):
        return shaped
    return best


class _Dilated:
    """The grip's use along a path time-scaled by s (`plan_carry`'s `attempt`), from one
    set of samples of it at full speed.

    `plan_path` at velocity limits × √s and acceleration limits × s is the full-speed
    path dilated in time: q_s(t) = q(√s t), so q̇ scales by √s and q̈ by s, and the
    item's acceleration a_c = a_o + α × r + ω × (ω × r) and the grip's angular
    acceleration α by s (centripetal terms included), gravity not at all. At the same
    n instants along it as `grip_use` samples the dilated path: f_s = s R⊤a_c − R⊤g,
    α_s = s α."""

    def __init__(self, traj: Trajectory, robot: Robot, hold: GripHold, n: int = 201) -> None:
        ts = np.linspace(0.0, traj.duration, n)
        qs, dqs, ddqs = traj.sample_many(ts)
        a, alpha, rots = _point_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)
        rt = np.transpose(rots, (0, 2, 1))
        self._motion = np.einsum("kij,kj->ki", rt, a)  # R⊤a_c, scales by s
        self._weight = np.einsum("kij,j->ki", rt, _GRAVITY)  # R⊤g, does not
        self._alpha = np.einsum("kij,kj->ki", rt, alpha)
        self._hold = hold

    def use(self, s: float) -> float:
        """`grip_use` of the path at time scale s (velocity × √s, acceleration × s)."""
        f = s * self._motion - self._weight
        return float(np.max(uses(f, s * self._alpha, self._hold, tilt=False)))


def _shaped(
    waypoints_q: Sequence[np.ndarray],
    robot: Robot,
    hold: GripHold,
    bound: float,
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
            use = grip_use(tr, robot, hold, n=501)
            if use <= bound:
                return tr, use
        return None
    finally:
        toppra_log.setLevel(level)
