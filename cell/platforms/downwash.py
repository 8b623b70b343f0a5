"""Rotor downwash below a hovering multirotor, and throws that fly through it.

The air pushed down by the rotors is modelled as one merged slipstream (the
far wake of a multirotor merges into a single column) below the rotor plane,
shaped by momentum theory:

* induced speed at the rotor disc [m/s]: v_i = c · max(rpm − rpm_0, 0) / 1000.
  Momentum theory gives v_i = sqrt(T / (2 ρ A)) with the thrust T = C_T ρ n² D⁴
  (n the rotor speed [rev/s], D its diameter), so v_i = n D sqrt(2 C_T / π) is
  linear in the rotor speed: c is the one calibrated constant, and
  `thrust_coefficient` turns it back into C_T for a plausibility check.
  rpm_0 (default 0, pure momentum theory) is an optional threshold below
  which the wake does not reach the item (a phenomenological extension the
  repeatability study tests; it is not momentum theory).
* axial speed at the depth s ≥ 0 below the disc [m/s]: the ideal actuator disc
  accelerates the slipstream from v_i at the disc to 2 v_i far below,
  w_ideal(s) = v_i (1 + s / sqrt(s² + R²)), and contracts it so that the mass
  flux is conserved, r_ideal(s) = R sqrt(v_i / w_ideal(s)) (R/√2 far below).
  Far below, the jet mixes with the still air like a turbulent round jet: the
  speed decays and the column widens with f(s) = 1 / (1 + s / L), w = w_ideal·f,
  r = r_ideal / f, which keeps the momentum flux w² r² constant.
* across the column: a smooth top hat, 0.5 (1 + tanh((r(s) − ρ) / edge)), with
  ρ the horizontal distance from the column's axis.
* no downwash above the rotor plane (s < 0).

The item's drag uses the air-relative velocity (MODEL.md eq. 3.10 with
v − v_air): m dv/dt = m g − ½ ρ C_d A |v − v_air| (v − v_air).

Pure NumPy (no simulator): the PyBullet scene (cell.platforms.drone) applies
the same law as a force field.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cell.errors import InvalidParameter
from cell.model.flight3d import Rows, column_fraction, fly
from cell.model.params import RHO_AIR, EndEffectorParams
from cell.model.throw import (
    Landing,
    ThrowBatch,
    drag_constant,
    launch_state,
    no_landing_error,
    throw_axis,
)

__all__ = [
    "IRIS_ROTOR_RADIUS_M",
    "IRIS_ROTORS",
    "DEFAULT_DRONE_LAW",
    "DownwashLaw",
    "air_velocity",
    "predict_drone_landing",
]

IRIS_ROTOR_RADIUS_M = 0.128  # [m] propeller radius of example-robot-data's iris
IRIS_ROTORS = 4  # rotors of the iris quadrotor
_EXIT_EDGE_M = 0.005  # [m] smoothing of the grip exit (keeps the RK4 right-hand side smooth)
_MERGED_RADIUS_M = IRIS_ROTOR_RADIUS_M * math.sqrt(IRIS_ROTORS)  # disc of the same total area


@dataclass(frozen=True)
class DownwashLaw:
    """Parameters of the downwash law (see the module docstring).

    Attributes:
        induced_mps_per_krpm: c, induced speed at the disc per 1000 rpm [m/s].
        threshold_rpm: rpm_0, rotor speed below which there is no wake at the item [rpm].
        wake_radius_m: R, radius of the merged rotor disc [m] (iris: 0.128·√4).
        edge_m: width of the column's smooth edge [m].
        decay_m: L, turbulent-jet decay length below the disc [m].
    """

    induced_mps_per_krpm: float = 0.0
    threshold_rpm: float = 0.0
    wake_radius_m: float = _MERGED_RADIUS_M
    edge_m: float = 0.03
    decay_m: float = 2.0

    def __post_init__(self) -> None:
        checks = (
            ("induced_mps_per_krpm", self.induced_mps_per_krpm, 0.0, 20.0),
            ("threshold_rpm", self.threshold_rpm, 0.0, 30000.0),
            ("wake_radius_m", self.wake_radius_m, 1e-3, 5.0),
            ("edge_m", self.edge_m, 1e-3, 1.0),
            ("decay_m", self.decay_m, 0.05, 100.0),
        )
        for name, v, lo, hi in checks:
            if not (isinstance(v, (int, float)) and math.isfinite(v) and lo <= v <= hi):
                raise InvalidParameter(
                    f"downwash law: {name}={v!r} must be a number in [{lo}, {hi}]"
                )

    def induced_speed(self, rotor_rpm: np.ndarray | float) -> np.ndarray:
        """v_i at the rotor disc [m/s] for rotor speeds [rpm]."""
        rpm = np.clip(np.asarray(rotor_rpm, float) - self.threshold_rpm, 0.0, None)
        return self.induced_mps_per_krpm * rpm / 1000.0

    def thrust_coefficient(self, rotor_radius_m: float = IRIS_ROTOR_RADIUS_M) -> float:
        """C_T in T = C_T ρ n² D⁴ per rotor implied by c (momentum theory, rpm_0 = 0) [-]."""
        per_rev = self.induced_mps_per_krpm / 1000.0 * 60.0  # v_i per (rev/s) [m]
        return math.pi / 2 * (per_rev / (2 * rotor_radius_m)) ** 2

    def thrust_n(self, rotor_rpm: float) -> float:
        """Total thrust T = 2 ρ A v_i² [N] of the merged disc at a rotor speed (momentum theory)."""
        area = math.pi * self.wake_radius_m**2  # the merged disc holds every rotor's area
        v_i = float(self.induced_speed(rotor_rpm))
        return 2 * RHO_AIR * area * v_i**2

    def with_params(self, **changes: float) -> DownwashLaw:
        """A copy with some parameters changed."""
        d = {k: getattr(self, k) for k in self.__dataclass_fields__}
        d.update(changes)
        return DownwashLaw(**d)


DEFAULT_DRONE_LAW = DownwashLaw(induced_mps_per_krpm=0.694)
"""The momentum-theory law identified from the thesis' Table 5.2 (`cell study repeatability`:
c = 0.694 m/s per 1000 rpm, least squares on the drone means at 8900, 13900 and 14860 rpm)."""


def air_velocity(
    points: np.ndarray,
    rotor_centre: np.ndarray,
    rotor_rpm: np.ndarray | float,
    law: DownwashLaw,
) -> np.ndarray:
    """Air velocity of the downwash at points [m/s, W].

    Args:
        points: positions [m, W], shape (n, 3).
        rotor_centre: centre of the (level) rotor plane [m, W], shape (3,) or (n, 3).
        rotor_rpm: rotor speed [rpm], scalar or shape (n,).
        law: the downwash law.

    Returns:
        Air velocity [m/s, W], shape (n, 3): (0, 0, −w) inside the column, 0 outside.
    """
    p = np.asarray(points, float).reshape(-1, 3)
    c = np.broadcast_to(np.asarray(rotor_centre, float), p.shape)
    v_i = np.broadcast_to(law.induced_speed(rotor_rpm), (p.shape[0],))
    return _column_air(p, (c[:, 0], c[:, 1], c[:, 2]), v_i, law)


def _column_air(
    p: np.ndarray, centre: tuple[np.ndarray, ...], v_i: np.ndarray, law: DownwashLaw
) -> np.ndarray:
    """`air_velocity` at points p (n, 3) [m, W] below rotor-plane centres given as their
    columns (x, y, z) [m, W], each shape (n,), with induced speeds v_i (n,) [m/s]: the same
    operations element by element. Where every point is below its disc and spun, the
    masks' `np.where` would hand back its own operand: it is left out (the same bits)."""
    out = np.zeros_like(p)
    s = centre[2] - p[:, 2]  # depth below the disc [m]
    below = (s > 0) & (v_i > 0)
    every = bool(below.all())
    if not every:
        if not below.any():
            return out
        s = np.where(below, s, 0.0)
    r0 = law.wake_radius_m
    accel = 1.0 + s / np.sqrt(s * s + r0 * r0)  # w_ideal / v_i, 1 → 2
    f = 1.0 / (1.0 + s / law.decay_m)
    radius = r0 / np.sqrt(accel) / f
    rho = np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1])
    inside = column_fraction(rho, radius, law.edge_m)
    w = v_i * accel * f * inside
    out[:, 2] = -(w if every else np.where(below, w, 0.0))
    return out


def _drone_inputs(
    n: int,
    rotor_rpm: np.ndarray | float,
    drone_pose: Sequence[float] | np.ndarray,
    exit_distance_m: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rotor speeds [rpm] (n,), rotor-plane centres [m, W] (n, 3), exit distances [m]
    (n,)) of n throws from `predict_drone_landing`'s arguments; InvalidParameter naming
    the one that is not finite, negative or of the wrong shape."""
    rpm = np.broadcast_to(np.asarray(rotor_rpm, float), (n,)).copy()
    if not np.all(np.isfinite(rpm)) or np.any(rpm < 0):
        raise InvalidParameter(f"rotor_rpm: {rotor_rpm!r} must be finite and ≥ 0 rpm")
    try:
        centre = np.broadcast_to(np.asarray(drone_pose, float), (n, 3)).copy()
    except ValueError:
        raise InvalidParameter(
            f"drone_pose: shape {np.shape(drone_pose)} must be (3,) or ({n}, 3) [m]"
        ) from None
    if not np.all(np.isfinite(centre)):
        raise InvalidParameter("drone_pose: must be finite numbers [m]")
    exit_m = np.broadcast_to(np.asarray(exit_distance_m, float), (n,)).copy()
    if not np.all(np.isfinite(exit_m)) or np.any(exit_m < 0):
        raise InvalidParameter(f"exit_distance_m: {exit_distance_m!r} must be finite and ≥ 0 m")
    return rpm, centre, exit_m


def predict_drone_landing(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    rotor_rpm: np.ndarray | float,
    drone_pose: Sequence[float] | np.ndarray,
    params: DownwashLaw,
    *,
    exit_distance_m: float | np.ndarray = 0.0,
    step: float = 0.002,
    strict: bool = True,
    check_stroke: bool = True,
) -> Landing:
    """Landing points of throws from under a hovering drone, through its downwash.

    The push (MODEL.md, eqs. 3.1–3.9) is the nominal one (`launch_state`); the
    flight after it is integrated in 3-D (RK4, `cell.model.flight3d.fly`) with
    the drag on the air-relative velocity in the downwash column.

    Args:
        batch: the throws (release grip centres below the drone).
        ee: end-effector parameters.
        rotor_rpm: rotor speed [rpm], scalar or shape (n,).
        drone_pose: centre of the level rotor plane [m, W], shape (3,) or (n, 3).
        params: the downwash law.
        exit_distance_m: how far along the throw axis from its release point the
            item travels before it leaves the grip [m], scalar or shape (n,); the
            pads hold it against the cross-flow until then. 0: from the end of
            the push (the nominal model's push travel); the PyBullet mechanism's
            is `cell.platforms.drone.scene_exit_distance_m`.
        step: RK4 step [s].
        strict: raise NoLanding for a throw that never reaches its plane;
            otherwise `landed = False` with NaN coordinates.
        check_stroke: reject strokes outside the end-effector's range.

    Returns:
        The landings (flight time from the start of the push).

    Raises:
        InvalidParameter: a stroke out of range, a negative rotor speed, or a
            malformed drone pose.
        NoLanding: with strict, a throw that never crosses its landing plane.
    """
    rpm, centre, exit_m = _drone_inputs(len(batch), rotor_rpm, drone_pose, exit_distance_m)
    if check_stroke:
        batch.check_stroke(ee)
    p1, v1 = launch_state(batch, ee)
    k = drag_constant(batch.shape, batch.mass, batch.size)
    p0 = batch.position
    u = throw_axis(batch.elevation, batch.azimuth)
    gated = exit_m > 0
    any_gated = bool(gated.any())
    # the rotor planes' centres and the induced speeds at the rows being integrated, taken
    # once per set of rows (`Rows`); v_i elementwise, so its rows are induced_speed(rpm[idx])
    rows = Rows(
        {
            "cx": centre[:, 0],
            "cy": centre[:, 1],
            "cz": centre[:, 2],
            "v_i": params.induced_speed(rpm),
        }
    )

    def accel(p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, None]:
        del v
        r = rows(idx)
        w = _column_air(p, (r["cx"], r["cy"], r["cz"]), r["v_i"], params)
        if any_gated:
            along = np.einsum("ij,ij->i", p - p0[idx], u[idx])
            out = 0.5 * (1.0 + np.tanh((along - exit_m[idx]) / _EXIT_EDGE_M))
            w *= np.where(gated[idx], out, 1.0)[:, None]
        return w, None

    res = fly(p1, v1, k, batch.land_z, accel=accel, t0=ee.dt, step=step)
    if strict and not np.all(res.landed):
        raise no_landing_error(np.flatnonzero(~res.landed), batch)
    return Landing(
        x=res.position[:, 0],
        y=res.position[:, 1],
        t_flight=res.t,
        launch_position=p1,
        launch_velocity=v1,
        landed=res.landed,
        impact_velocity=res.velocity,
    )
