"""Throws as batches of arrays, the launch push, and the landing prediction.

A throw (MODEL.md): the object's centre of mass starts at the grip centre p0
[m, world W] with the base velocity v_b [m/s, W]; the push f_o u acts for
t in [0, Δt] together with gravity and quadratic drag; the flight continues
under gravity and drag until the centre of mass first crosses the landing
plane z = land_z [m] while descending. Flight time counts from the start of
the push.

The fast path (`predict_landing`) is exact where it can be and high-order
where it cannot:

* the push phase is a short 3-D RK4 integration (gravity and the constant
  push are integrated exactly by RK4; only the weak drag is approximated);
* after the push the only forces are gravity and drag along the velocity, so
  the motion stays in the vertical plane of the launch velocity and is
  integrated as a planar problem with RK4 steps sized to the drag's time scale;
* the plane crossing is located inside the step on the cubic Hermite
  interpolant of height and vertical velocity (exact for a drag-free parabola).

`reference_landing` is the fine-step 3-D integration the fast path is
checked against (and `cell bench` reports the worst deviation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.errors import InvalidParameter, NoLanding, plural
from cell.model.band import push_force
from cell.model.integrate import PUSH_STEPS, plane_crossing, push_steps, rk4_step
from cell.model.objects import ObjectParams, drag_area, drag_coefficient
from cell.model.params import EndEffectorParams, G, aero_factor_kg_per_m
from cell.model.planar import flight_planar, flight_planar_one

__all__ = [
    "ThrowBatch",
    "Landing",
    "throw_axis",
    "drag_constant",
    "launch_state",
    "longest_stroke_launching",
    "ride",
    "predict_landing",
    "reference_landing",
    "no_landing_error",
]

_PUSH_STEPS = PUSH_STEPS
_FLIGHT_STEP = 0.07  # [s] largest planar RK4 step after the push


def throw_axis(elevation: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """Unit throw axis u = (cos e cos a, cos e sin a, sin e) in W, shape (n, 3)."""
    e = np.asarray(elevation, float)
    a = np.asarray(azimuth, float)
    return np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=-1)


def drag_constant(shape: np.ndarray, mass: np.ndarray, size: np.ndarray) -> np.ndarray:
    """k = ½ ρ C_d A / m [1/m], so that drag acceleration is -k |v| v."""
    return aero_factor_kg_per_m(drag_coefficient(shape), drag_area(shape, size)) / np.asarray(
        mass, float
    )


def _as(n: int, value: object, name: str, width: int | None = None) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    target = (n,) if width is None else (n, width)
    try:
        arr = np.broadcast_to(arr, target).copy()
    except ValueError:
        raise InvalidParameter(f"{name}: shape {arr.shape} does not fit {target}") from None
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr.reshape(n, -1)).all(axis=1))[0])
        raise InvalidParameter(f"{name}: throw {bad} is not a finite number")
    return arr


@dataclass(frozen=True)
class ThrowBatch:
    """n throws as arrays (SI units, world frame W).

    Attributes:
        stroke: stroke L_s [m], shape (n,).
        position: release grip centre p0 [m], shape (n, 3).
        elevation: throw-axis elevation [rad], shape (n,).
        azimuth: throw-axis azimuth [rad], shape (n,).
        base_velocity: end-effector velocity at release [m/s], shape (n, 3).
        land_z: landing-plane height [m], shape (n,).
        shape: shape codes (index in objects.SHAPES), shape (n,).
        mass: object mass [kg], shape (n,).
        size: object extents [m], shape (n, 3); size[:, 0] is the grip width.
        roll: roll about the throw axis [rad], shape (n,).
    """

    stroke: np.ndarray
    position: np.ndarray
    elevation: np.ndarray
    azimuth: np.ndarray
    base_velocity: np.ndarray
    land_z: np.ndarray
    shape: np.ndarray
    mass: np.ndarray
    size: np.ndarray
    roll: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def build(
        cls,
        *,
        stroke: object,
        position: object,
        elevation: object,
        azimuth: object,
        shape: object,
        mass: object,
        size: object,
        base_velocity: object = 0.0,
        land_z: object = 0.0,
        roll: object = 0.0,
    ) -> ThrowBatch:
        """Broadcast and validate inputs into a batch.

        Raises:
            InvalidParameter: non-finite values, mass or size ≤ 0, unknown shape code.
        """
        n = max(
            np.asarray(stroke).size,
            np.asarray(position).size // 3,
            np.asarray(mass).size,
            np.asarray(shape).size,
            np.asarray(size).size // 3,
            np.asarray(elevation).size,
            np.asarray(azimuth).size,
        )
        codes = np.broadcast_to(np.asarray(shape, dtype=int), (n,)).copy()
        if np.any((codes < 0) | (codes > 4)):
            raise InvalidParameter(
                "shape: codes must be in 0..4 (cube, cuboid, cylinder, sphere, mesh)"
            )
        batch = cls(
            stroke=_as(n, stroke, "stroke"),
            position=_as(n, position, "position", 3),
            elevation=_as(n, elevation, "elevation"),
            azimuth=_as(n, azimuth, "azimuth"),
            base_velocity=_as(n, base_velocity, "base_velocity", 3),
            land_z=_as(n, land_z, "land_z"),
            shape=codes,
            mass=_as(n, mass, "mass"),
            size=_as(n, size, "size", 3),
            roll=_as(n, roll, "roll"),
        )
        if np.any(batch.mass <= 0):
            i = int(np.flatnonzero(batch.mass <= 0)[0])
            raise InvalidParameter(f"mass: throw {i} has mass {batch.mass[i]} kg; must be > 0")
        if np.any(batch.size <= 0):
            i = int(np.flatnonzero((batch.size <= 0).any(axis=1))[0])
            raise InvalidParameter(f"size: throw {i} has extents {batch.size[i]} m; must be > 0")
        return batch

    @classmethod
    def single(
        cls,
        obj: ObjectParams,
        *,
        stroke: float,
        position: tuple[float, float, float] | np.ndarray,
        elevation: float,
        azimuth: float,
        base_velocity: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
        land_z: float = 0.0,
        roll: float = 0.0,
    ) -> ThrowBatch:
        """A batch of one throw of a given object."""
        return cls.build(
            stroke=[stroke],
            position=[position],
            elevation=[elevation],
            azimuth=[azimuth],
            shape=[obj.code],
            mass=[obj.mass],
            size=[obj.size],
            base_velocity=[base_velocity],
            land_z=[land_z],
            roll=[roll],
        )

    def __len__(self) -> int:
        return int(self.stroke.shape[0])

    def take(self, idx: np.ndarray) -> ThrowBatch:
        """The sub-batch at the given indices or mask."""
        return ThrowBatch(
            **{k: getattr(self, k)[idx] for k in self.__dataclass_fields__}  # type: ignore[arg-type]
        )

    def stroke_out_of_range(self, ee: EndEffectorParams) -> np.ndarray:
        """Indices of the throws whose stroke is outside the end-effector's range."""
        bad = (self.stroke < ee.stroke_min - 1e-12) | (self.stroke > ee.stroke_max + 1e-12)
        return np.flatnonzero(bad)

    def check_stroke(self, ee: EndEffectorParams) -> None:
        """Raise InvalidParameter naming the first throw whose stroke is out of range."""
        bad = self.stroke_out_of_range(ee)
        if bad.size:
            i = int(bad[0])
            raise InvalidParameter(
                f"stroke: throw {i} has L_s = {self.stroke[i]:.4f} m; the end-effector allows "
                f"{ee.stroke_min:.3f} … {ee.stroke_max:.3f} m"
            )


@dataclass(frozen=True)
class Landing:
    """Predicted landings of a batch.

    Attributes:
        x, y: landing point on the plane z = land_z [m, W], shape (n,).
        t_flight: time from the start of the push to the crossing [s], shape (n,).
        launch_position: centre of mass at the end of the push [m, W], shape (n, 3).
        launch_velocity: velocity at the end of the push [m/s, W], shape (n, 3).
        landed: True where the throw crosses its landing plane, shape (n,).
        impact_velocity: velocity at the crossing [m/s, W], shape (n, 3).
    """

    x: np.ndarray
    y: np.ndarray
    t_flight: np.ndarray
    launch_position: np.ndarray
    launch_velocity: np.ndarray
    landed: np.ndarray
    impact_velocity: np.ndarray

    @property
    def xy(self) -> np.ndarray:
        """Landing points, shape (n, 2)."""
        return np.stack([self.x, self.y], axis=-1)


def launch_state(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    *,
    push: np.ndarray | None = None,
    push_mass: np.ndarray | None = None,
    axis: np.ndarray | None = None,
    steps: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate the push phase t ∈ [0, Δt] in 3-D.

    Args:
        batch: the throws.
        ee: end-effector parameters.
        push: f_o [N] per throw; computed from the band law when None.
        push_mass: the mass the push drives [kg]; the object's mass when None.
        axis: the throw axis per throw, shape (n, 3); from elevation/azimuth when None.
        steps: RK4 steps across the push; None: `_PUSH_STEPS`, more where the drag is
            stiff (`push_steps`).

    Returns:
        (position, velocity) at t = Δt, each shape (n, 3), world frame.
    """
    f_o = push_force(batch.stroke, batch.size[:, 0], ee) if push is None else push
    m_push = batch.mass if push_mass is None else push_mass
    u = throw_axis(batch.elevation, batch.azimuth) if axis is None else axis
    # drag acts on the object alone; the push drives m_push
    kk = drag_constant(batch.shape, batch.mass, batch.size) * batch.mass / m_push
    scale = np.asarray(f_o) / m_push
    ax, ay, az = u[:, 0] * scale, u[:, 1] * scale, u[:, 2] * scale - G
    px, py, pz = (batch.position[:, j].copy() for j in range(3))
    vx, vy, vz = (batch.base_velocity[:, j].copy() for j in range(3))
    if steps is None:
        steps = push_steps(kk, np.abs(scale) + G, batch.base_velocity, ee.dt)
    h = ee.dt / steps

    def acc(wx: np.ndarray, wy: np.ndarray, wz: np.ndarray) -> tuple[np.ndarray, ...]:
        c = kk * np.sqrt(wx * wx + wy * wy + wz * wz)
        return ax - c * wx, ay - c * wy, az - c * wz

    # Component arrays rather than (n, 3): several times faster in NumPy.
    def rates(_p: Any, v: Any) -> tuple[np.ndarray, ...]:
        return acc(*v)

    for _ in range(steps):
        (px, py, pz), (vx, vy, vz) = rk4_step(rates, (px, py, pz), (vx, vy, vz), h)
    p1, v1 = np.stack([px, py, pz], axis=-1), np.stack([vx, vy, vz], axis=-1)
    if ee.L_e > 0:
        p1, v1 = ride(p1, v1, u, batch.stroke + np.sum((p1 - batch.position) * u, axis=1), ee.L_e)
    return p1, v1


_RIDE_MIN_SPEED2 = 1e-6  # [m²/s²] floor of the speed² left after the ride (stalls at ~1 mm/s)


def ride(
    position: np.ndarray, velocity: np.ndarray, axis: np.ndarray, stroke: np.ndarray, L_e: float
) -> tuple[np.ndarray, np.ndarray]:
    """The item riding the carriage from where the push left it to L_e.

    The carriage carries it d = max(L_e − s, 0) along the throw axis u (s the carriage's
    position at the end of the push: the stroke L_s plus the push's travel along u); the
    pads hold it
    across u, and gravity's component along u does the work −m g u_z d, so the speed along
    u becomes √(w² − 2 g u_z d) (w its speed along u at the end of the push); the speed
    across u is kept. Drag over the few centimetres is neglected.

    Args:
        position, velocity: centre of mass and velocity at the end of the push, (n, 3).
        axis: the throw axis u per throw, (n, 3).
        stroke: s, the carriage position at the end of the push [m], (n,).
        L_e: carriage position where the item leaves [m].

    Returns:
        (position, velocity) where the item leaves the carriage, each (n, 3).
    """
    d = np.maximum(L_e - np.asarray(stroke, float), 0.0)
    w = np.sum(velocity * axis, axis=1)
    w2 = np.sqrt(np.maximum(w * w - 2 * G * axis[:, 2] * d, _RIDE_MIN_SPEED2))
    return position + d[:, None] * axis, velocity + (w2 - w)[:, None] * axis


def longest_stroke_launching(
    ee: EndEffectorParams, obj: ObjectParams, speed_min_mps: float, elevation_rad: float
) -> float | None:
    """The longest stroke [m] in the end-effector's range at which the model launches
    `obj` (its mass as the push drives it: the effective mass of the parameter file,
    `ModelParams.model_object`) at `speed_min_mps` or faster with the throw axis at
    `elevation_rad` (gravity along the axis slows a steep launch), or None when even
    the shortest stroke launches it slower.

    The launch speed falls as the stroke grows (less band stretch): the strokes are
    searched on a 0.5 mm grid.
    """
    strokes = np.arange(ee.stroke_min, ee.stroke_max + 1e-12, 5e-4)
    batch = ThrowBatch.build(
        stroke=strokes,
        position=np.zeros((strokes.size, 3)),
        elevation=elevation_rad,
        azimuth=0.0,
        shape=obj.code,
        mass=obj.mass,
        size=obj.size,
    )
    speed = np.linalg.norm(launch_state(batch, ee)[1], axis=1)
    ok = strokes[speed >= speed_min_mps]
    return float(ok.max()) if ok.size else None


def predict_landing(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    *,
    strict: bool = True,
    check_stroke: bool = True,
    push: np.ndarray | None = None,
    push_mass: np.ndarray | None = None,
    axis: np.ndarray | None = None,
) -> Landing:
    """Landing points of a batch of throws with the nominal model (fast path).

    Args:
        batch: the throws.
        ee: end-effector parameters.
        strict: raise NoLanding for a throw that never reaches its plane;
            otherwise mark it with `landed = False` and NaN coordinates.
        check_stroke: reject strokes outside the end-effector's range.
        push, push_mass, axis: overrides of the launch (see `launch_state`),
            used by model augmentations; None gives the nominal model.

    Returns:
        The landings.

    Raises:
        InvalidParameter: a stroke outside the end-effector's range.
        NoLanding: with strict, naming the first throw that never lands
            (its index is in the exception's `indices`).
    """
    if check_stroke:
        batch.check_stroke(ee)
    p1, v1 = launch_state(batch, ee, push=push, push_mass=push_mass, axis=axis)
    k = drag_constant(batch.shape, batch.mass, batch.size)
    vh = np.hypot(v1[:, 0], v1[:, 1])
    with np.errstate(invalid="ignore", divide="ignore"):
        dirx = np.where(vh > 0, v1[:, 0] / vh, 1.0)
        diry = np.where(vh > 0, v1[:, 1] / vh, 0.0)
    if len(batch) == 1:
        one = flight_planar_one(
            float(p1[0, 2]),
            float(vh[0]),
            float(v1[0, 2]),
            float(k[0]),
            float(batch.land_z[0]),
            _FLIGHT_STEP,
        )
        dist, t, vhi, vzi = (np.array([one[i]], dtype=float) for i in (0, 1, 3, 4))
        landed = np.array([one[2]])
    else:
        dist, t, landed, vhi, vzi = flight_planar(
            p1[:, 2], vh, v1[:, 2], k, batch.land_z, _FLIGHT_STEP
        )
    result = Landing(
        x=p1[:, 0] + dist * dirx,
        y=p1[:, 1] + dist * diry,
        t_flight=t + ee.dt,
        launch_position=p1,
        launch_velocity=v1,
        landed=landed,
        impact_velocity=np.stack([vhi * dirx, vhi * diry, vzi], axis=-1),
    )
    if strict and not np.all(landed):
        bad = np.flatnonzero(~landed)
        raise no_landing_error(bad, batch)
    return result


def no_landing_error(bad: np.ndarray, batch: ThrowBatch) -> NoLanding:
    """The NoLanding error for the throws at indices `bad` (kept in `.indices`)."""
    i = int(bad[0])
    err = NoLanding(
        f"throw {i} never crosses its landing plane z = {batch.land_z[i]:.3f} m while descending "
        f"(released at z = {batch.position[i, 2]:.3f} m); {plural(int(bad.size), 'throw')} in all. "
        "Lower the landing plane or raise the release."
    )
    err.indices = bad  # type: ignore[attr-defined]
    return err


def reference_landing(
    batch: ThrowBatch, ee: EndEffectorParams, *, step: float = 2e-4, t_max: float = 30.0
) -> Landing:
    """Fine-step 3-D RK4 integration of push and flight (the fast path's yardstick).

    The step is fixed; the push boundary t = Δt falls on a step boundary.
    Not strict: a throw that never lands gets `landed = False`.
    """
    n_push = max(1, math.ceil(ee.dt / step))
    p, v = launch_state(batch, ee, steps=n_push)
    p1, v1 = p.copy(), v.copy()
    k = drag_constant(batch.shape, batch.mass, batch.size)[:, None]
    lz = batch.land_z
    n = len(batch)
    out = np.full((n, 3), np.nan)
    out_v = np.full((n, 3), np.nan)
    out_t = np.full(n, np.nan)
    active = np.ones(n, bool)
    g = np.array([0.0, 0.0, -G])
    t = 0.0
    while active.any() and t < t_max:
        pa, va, ka = p[active], v[active], k[active]

        def acc(vel: np.ndarray, kk: np.ndarray = ka) -> np.ndarray:
            return g - kk * np.linalg.norm(vel, axis=1, keepdims=True) * vel

        def rates(_p: Any, vs: list[np.ndarray], f: Any = acc) -> list[np.ndarray]:
            return [f(vs[0])]

        (pn,), (vn,) = rk4_step(rates, [pa], [va], step)
        ids = np.flatnonzero(active)
        cross = (pa[:, 2] > lz[ids]) & (pn[:, 2] <= lz[ids])
        if cross.any():
            c = cross
            s, out[ids[c]], out_v[ids[c]] = plane_crossing(
                pa[c], pn[c], va[c], vn[c], step, lz[ids][c]
            )
            out_t[ids[c]] = t + s * step
        gone = cross | ((pn[:, 2] <= lz[ids]) & (vn[:, 2] < 0))
        p[ids], v[ids] = pn, vn
        active[ids[gone]] = False
        t += step
    landed = np.isfinite(out_t)
    return Landing(
        x=out[:, 0],
        y=out[:, 1],
        t_flight=out_t + n_push * (ee.dt / n_push),
        launch_position=p1,
        launch_velocity=v1,
        landed=landed,
        impact_velocity=out_v,
    )
