"""The grip's hold on an item and the carry's use of it: the specific force and couple at
the item's centre of mass from the joint state, and their share of what the pads hold
(the laws are set out in `cell.robot.carry`)."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cell.model.params import G
from cell.robot.kept import Kept, array_key
from cell.robot.model import Robot
from cell.robot.trajectory import Trajectory

# The grip's static friction force over what a carry may ask of it. Measured in the scene
# (tests/test_carry.py): accelerated, the pads hold 0.74-0.78 of what they hold at rest
# (a 30 mm box at 0.06 m stroke held at 0.74 of the static limit, slid 15 mm at 0.80).
CARRY_MARGIN = 1.35


_GRAVITY = np.array([0.0, 0.0, -G])


# Where a carry's path held still already asks more of the pads' tilt than the carry's
# bound (a level swing past the horizontal), its accelerations may add this much to it
# (`carry_use`): else the bisection on the carry's time scale, whose slowest is 0.02, finds
# none within it, and the carry goes at GENTLE_SCALE. Boxes and cylinders turn in the
# pads at 1.02-1.23 of T_y (tests/test_grip_probe.py).
TILT_HEADROOM = 0.05


# A carry timed by the force-and-twist use alone is slowed for the grip's tilt only where
# its use with the tilt (`uses`, the tilt in quadrature, not scaled by the carry's margin)
# is over this, what the pads hold at all (`cell.robot.carry_plan.plan_carry`). Timed so,
# the routes of tests/test_departure.py's level carry (cuboid_c, UR5) asked 0.67-0.91 with
# the tilt and its boxes stayed unturned in the pads; the tall box of
# tests/test_grip_side.py asked 1.03 and left them, the bottles of random layout 3 left
# them at 1.02-1.06, the carries of issue 59 at 1.23. Slowed from 0.9, carries that
# landed their items before on tune layout 1 (UR5) were slowed too.
TILT_SLOWS_OVER = 1.0


GENTLE_SCALE = 0.3  # time scale of a carry no scaling keeps within the grip (see plan_carry)


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
    return _in_tcp(*_point_motion(robot, qs, dqs, ddqs, offset_tcp_m))


def _in_tcp(
    a: np.ndarray, alpha: np.ndarray, rots: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`item_motion` from `_point_motion`'s (a, α, rotations): f = R⊤(a − g) and R⊤α."""
    rt = np.transpose(rots, (0, 2, 1))
    f = np.einsum("kij,kj->ki", rt, a - _GRAVITY)
    return f, np.einsum("kij,kj->ki", rt, alpha), rots


def sampled_motion(
    traj: Trajectory, robot: Robot, hold: GripHold, n: int = 201
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_point_motion` of the item's centre of mass at n instants evenly spread over the
    trajectory, its ends included: what `grip_use` reads the grip's use from."""
    ts = np.linspace(0.0, traj.duration, n)
    qs, dqs, ddqs = traj.sample_many(ts)
    return _point_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)


def grip_use(
    traj: Trajectory, robot: Robot, hold: GripHold, n: int = 201, margin: float | None = None
) -> float:
    """The largest use of the grip along a trajectory, sampled at n instants: without
    `margin`, m |f| / F + |τ_x| / T (the tilt about y not counted); with it, the carry's
    use with the tilt (`carry_use`), which a carry keeps within 1/margin. ≤ 1 is within
    what the pads hold."""
    return motion_use(sampled_motion(traj, robot, hold, n), hold, margin)


def motion_use(
    motion: tuple[np.ndarray, np.ndarray, np.ndarray], hold: GripHold, margin: float | None
) -> float:
    """`grip_use` from the samples `sampled_motion` gives."""
    f, alpha, rots = _in_tcp(*motion)
    if margin is None:
        return float(np.max(uses(f, alpha, hold, tilt=False)))
    return carry_use(f, alpha, rest_force(rots), hold, margin)


def tilt_use(traj: Trajectory, robot: Robot, hold: GripHold, n: int = 201) -> float:
    """The largest use of the grip along a trajectory with the tilt about y counted
    (`uses`), sampled at n instants; ≤ 1 is within what the pads hold."""
    ts = np.linspace(0.0, traj.duration, n)
    qs, dqs, ddqs = traj.sample_many(ts)
    f, alpha, _ = item_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)
    return float(np.max(uses(f, alpha, hold)))


def rest_force(rots: np.ndarray) -> np.ndarray:
    """The specific force −g [m/s²] in ee_tcp axes of each rotation of `rots` (k, 3, 3):
    what the item feels held still there, shape (k, 3)."""
    return np.asarray(-np.einsum("kji,j->ki", rots, _GRAVITY))


def carry_use(
    f: np.ndarray, alpha: np.ndarray, f_rest: np.ndarray, hold: GripHold, margin: float
) -> float:
    """The carry's use of the grip, the tilt about y counted (`uses`), on the scale of its
    bound 1/margin: the force-and-twist use m |f| / F + |τ_x| / T, and the use with the
    tilt scaled so that the most the path asks held still (`f_rest`, at each of its
    samples) is at the bound where it is over it. So a carry whose accelerations would
    tip a tall item in the pads is slowed until they ask no more than the bound, or than
    the path's own geometry does at rest (a level swing past the horizontal, with a tall
    item's weight on a pad, which the routes choose and check: `_swing_holds`).

    Before, the carry kept the force-and-twist use alone within the bound: a carry that
    asked 0.73 of it, 1.23 with the tilt counted, dropped its item (5 of 638 items on the
    random layouts, issue 59). f, α, f_rest: [m/s²], [rad/s²], [m/s²] in ee_tcp axes,
    shape (k, 3)."""
    plain = float(np.max(uses(f, alpha, hold, tilt=False)))
    if hold.torque_y_nm <= 0.0:
        return plain
    bound = 1.0 / margin
    at_rest = float(np.max(uses(f_rest, np.zeros_like(f_rest), hold)))
    tilt = float(np.max(uses(f, alpha, hold)))
    return max(plain, tilt * bound / max(bound, at_rest + TILT_HEADROOM))


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


# `_point_motion`'s answers by the bytes of its inputs (the robot's, kept with its answer):
# the carries' plans ask again for the same samples, within a decision and across them
# (331 of tune layout 0's 2,565 calls, counted on `4645969`). A function of the inputs'
# bits (Pinocchio's kinematics are deterministic), and its arrays are read-only: nothing
# writes into one. Bounded: cleared when full.
_MOTIONS: Kept[tuple[Robot, tuple[np.ndarray, np.ndarray, np.ndarray]]] = Kept(256)


def _point_motion(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(acceleration of the point [m/s², W], ee_tcp's angular acceleration [rad/s², W],
    ee_tcp's rotations in W), shapes (k, 3), (k, 3), (k, 3, 3):
    a = a_o + α × r + ω × (ω × r), from Pinocchio's frame kinematics; the same inputs'
    answer made once (`_MOTIONS`: the same read-only arrays)."""
    qs, dqs, ddqs = (np.asarray(x, dtype=float) for x in (qs, dqs, ddqs))
    shapes = (id(robot), qs.shape, dqs.shape, ddqs.shape)
    key = repr(shapes).encode() + array_key(qs, dqs, ddqs, offset_tcp_m)

    def made() -> tuple[Robot, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        return robot, _point_motion_made(robot, qs, dqs, ddqs, offset_tcp_m)

    kept = _MOTIONS.get(key, made)
    if kept[0] is not robot:  # another robot at a reused id: made again for this one
        kept = made()
        _MOTIONS.put(key, kept)
    return kept[1]


def _point_motion_made(
    robot: Robot,
    qs: np.ndarray,
    dqs: np.ndarray,
    ddqs: np.ndarray,
    offset_tcp_m: Sequence[float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """`_point_motion` worked out, its arrays read-only."""
    import pinocchio as pin

    m, d, fr = robot.model, robot.data, robot.tcp_frame
    r_local = np.asarray(offset_tcp_m, float)
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    k = len(qs)
    out = np.empty((3, k, 3))  # a_o, α, ω
    rots = np.empty((k, 3, 3))
    kinematics, place = pin.forwardKinematics, pin.updateFramePlacement
    classical, twist = pin.getFrameClassicalAcceleration, pin.getFrameVelocity
    a_o, alphas, ws = out
    # The grip's frame alone placed (`updateFramePlacement`, as `Robot.tcp_positions`),
    # not the model's 28, and r = R r_local for all instants at once: the same floats as
    # placing every frame and one product per instant, bit for bit
    # (tests/test_grip_hold_bits.py), in 0.7 of the time. α is the classical
    # acceleration's angular part: Pinocchio's `getFrameClassicalAcceleration` is
    # `getFrameAcceleration` with ω × v added to its linear part alone, so its angular
    # part is the spatial acceleration's, the same floats, one frame call fewer a sample
    for i, (q, dq, ddq) in enumerate(zip(qs, dqs, ddqs, strict=True)):
        kinematics(m, d, q, dq, ddq)
        rots[i] = place(m, d, fr).rotation
        classical_acc = classical(m, d, fr, lwa)
        a_o[i] = classical_acc.linear
        alphas[i] = classical_acc.angular
        ws[i] = twist(m, d, fr, lwa).angular
    r = rots @ r_local
    # the cross products over all instants at once (one np.cross per row cost 3x the
    # kinematics: np.cross's axis handling dominates for single 3-vectors)
    acc = a_o + np.cross(alphas, r) + np.cross(ws, np.cross(ws, r))
    for a in (acc, alphas, rots):
        a.setflags(write=False)  # kept and shared (`_MOTIONS`)
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
