"""Bounds of the release state σ for throw planning (thesis eq. 4.5).

σ = [x, y, z, ẋ, ẏ, ż, φ, θ, ψ, L_s] (thesis eq. 4.2) is stored in the order
and under the names of the docs/throw_log.md columns: the release grip centre
(x_m, y_m, z_m) [m, world W], the base velocity (vx_mps, vy_mps, vz_mps)
[m/s, W], the end-effector's roll about the throw axis and the throw axis'
elevation and azimuth (roll_rad, elevation_rad, azimuth_rad) [rad], and the
stroke L_s (stroke_m) [m].

The defaults describe an arm whose base sits at the world origin: the release
point lies in the box x ∈ [0.2, 0.6], |y| ≤ 0.4, z ∈ [0.4, 0.9] m, the base is
fixed (velocities zero) and the stroke range is the end-effector's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from cell.errors import InvalidParameter
from cell.model.params import EndEffectorParams

__all__ = ["SIGMA_COLUMNS", "ThrowBounds", "DEFAULT_BOUNDS"]

# σ in docs/throw_log.md column names, in the order of the thesis' eq. 4.2.
SIGMA_COLUMNS = (
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "roll_rad",
    "elevation_rad",
    "azimuth_rad",
    "stroke_m",
)


def _vec3(name: str, value: object) -> tuple[float, float, float]:
    try:
        v = tuple(float(x) for x in value)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InvalidParameter(f"bounds: {name}={value!r} must be three numbers") from None
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise InvalidParameter(f"bounds: {name}={value!r} must be three finite numbers")
    return (v[0], v[1], v[2])


@dataclass(frozen=True)
class ThrowBounds:
    """The box σ_L ≤ σ ≤ σ_U a throw plan must respect, and the fast path's pose family.

    Attributes:
        position_min: lower corner of the release-point box [m, W].
        position_max: upper corner of the release-point box [m, W].
        elevation_min: smallest throw-axis elevation [rad].
        elevation_max: largest throw-axis elevation [rad].
        azimuth_min: smallest azimuth [rad] (-π: free).
        azimuth_max: largest azimuth [rad] (π: free).
        stroke_min: smallest stroke L_s [m]; None: the end-effector's.
        stroke_max: largest stroke L_s [m]; None: the end-effector's.
        base_velocity_min: lower corner of the base-velocity box [m/s, W].
        base_velocity_max: upper corner of the base-velocity box [m/s, W]; both
            zero (the default) is a fixed base.
        roll: roll about the throw axis the plan uses [rad]; it does not move the
            nominal landing point.
        release_radius: the fast path's release point lies this far from the
            base (the world origin) toward the target, inside the box [m].
        release_height: the fast path's release height [m, W].
        n_elevations: how many elevations, evenly spaced over the elevation
            range, the fast path considers.
        facing_rad: the azimuth [rad, W] an arm that turns to face its target
            (`plan_facing`) faces at the release: its release point lies
            `release_radius` from the base along it, and the throw axis turns from
            there to the target; None faces the target itself.
    """

    position_min: tuple[float, float, float] = (0.2, -0.4, 0.4)
    position_max: tuple[float, float, float] = (0.6, 0.4, 0.9)
    elevation_min: float = 0.0
    elevation_max: float = math.radians(65.0)
    azimuth_min: float = -math.pi
    azimuth_max: float = math.pi
    stroke_min: float | None = None
    stroke_max: float | None = None
    base_velocity_min: tuple[float, float, float] = (0.0, 0.0, 0.0)
    base_velocity_max: tuple[float, float, float] = (0.0, 0.0, 0.0)
    roll: float = 0.0
    release_radius: float = 0.4
    release_height: float = 0.8
    n_elevations: int = 14
    facing_rad: float | None = None

    def __post_init__(self) -> None:
        for name in ("position_min", "position_max", "base_velocity_min", "base_velocity_max"):
            object.__setattr__(self, name, _vec3(name, getattr(self, name)))
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not math.isfinite(v):
                raise InvalidParameter(f"bounds: {f.name}={v} must be finite")
        for lo, hi, unit in (
            ("position_min", "position_max", "m"),
            ("base_velocity_min", "base_velocity_max", "m/s"),
        ):
            a, b = getattr(self, lo), getattr(self, hi)
            if any(x > y for x, y in zip(a, b, strict=True)):
                raise InvalidParameter(f"bounds: {lo}={a} {unit} must be ≤ {hi}={b} {unit}")
        if not -math.pi / 2 <= self.elevation_min <= self.elevation_max <= math.pi / 2:
            raise InvalidParameter(
                f"bounds: elevation range [{self.elevation_min}, {self.elevation_max}] rad must "
                "satisfy -π/2 ≤ elevation_min ≤ elevation_max ≤ π/2"
            )
        if not -2 * math.pi <= self.azimuth_min <= self.azimuth_max <= 2 * math.pi:
            raise InvalidParameter(
                f"bounds: azimuth range [{self.azimuth_min}, {self.azimuth_max}] rad must "
                "satisfy -2π ≤ azimuth_min ≤ azimuth_max ≤ 2π"
            )
        if (self.stroke_min is None) != (self.stroke_max is None):
            raise InvalidParameter("bounds: give both stroke_min and stroke_max, or neither")
        if self.stroke_min is not None and not 0 < self.stroke_min < self.stroke_max:  # type: ignore[operator]
            raise InvalidParameter(
                f"bounds: stroke range [{self.stroke_min}, {self.stroke_max}] m must satisfy "
                "0 < stroke_min < stroke_max"
            )
        if self.release_radius < 0:
            raise InvalidParameter(f"bounds: release_radius={self.release_radius} m must be ≥ 0")
        if not isinstance(self.n_elevations, int) or self.n_elevations < 1:
            raise InvalidParameter(f"bounds: n_elevations={self.n_elevations} must be an int ≥ 1")

    @classmethod
    def from_dict(cls, values: dict[str, Any], *, where: str = "throw bounds") -> ThrowBounds:
        """Build from a configuration mapping (e.g. a YAML section), keys named as the fields.

        Raises:
            InvalidParameter: an unknown key (the valid ones are listed) or a bad value.
        """
        if not isinstance(values, dict):
            raise InvalidParameter(f"{where}: expected a mapping of bound names to values")
        valid = [f.name for f in fields(cls)]
        unknown = sorted(set(values) - set(valid))
        if unknown:
            raise InvalidParameter(f"{where}: unknown key(s) {unknown}; valid: {', '.join(valid)}")
        try:
            return cls(**values)
        except InvalidParameter as exc:
            raise InvalidParameter(f"{where}: {exc}") from None
        except (TypeError, ValueError) as exc:
            raise InvalidParameter(f"{where}: {exc}") from None

    @property
    def fixed_base(self) -> bool:
        """True when the base velocity box is the single point zero."""
        return not any(self.base_velocity_min) and not any(self.base_velocity_max)

    def with_base_velocity(self, limit: float) -> ThrowBounds:
        """The same bounds for a moving base with |v_i| ≤ limit [m/s] per axis."""
        if not (math.isfinite(limit) and limit >= 0):
            raise InvalidParameter(f"bounds: base velocity limit {limit} m/s must be ≥ 0")
        return replace(
            self, base_velocity_min=(-limit, -limit, -limit), base_velocity_max=(limit,) * 3
        )

    def stroke_range(self, ee: EndEffectorParams) -> tuple[float, float]:
        """The allowed stroke range [m]: these bounds' inside the end-effector's.

        Raises:
            InvalidParameter: the bounds' stroke range leaves the end-effector's.
        """
        if self.stroke_min is None or self.stroke_max is None:
            return ee.stroke_min, ee.stroke_max
        if self.stroke_min < ee.stroke_min - 1e-12 or self.stroke_max > ee.stroke_max + 1e-12:
            raise InvalidParameter(
                f"bounds: stroke range [{self.stroke_min}, {self.stroke_max}] m leaves the "
                f"end-effector's [{ee.stroke_min}, {ee.stroke_max}] m"
            )
        return self.stroke_min, self.stroke_max

    def vectors(self, ee: EndEffectorParams) -> tuple[np.ndarray, np.ndarray]:
        """(σ_L, σ_U), each shape (10,), in SIGMA_COLUMNS order."""
        s_lo, s_hi = self.stroke_range(ee)
        lo = np.array(
            [
                *self.position_min,
                *self.base_velocity_min,
                self.roll,
                self.elevation_min,
                self.azimuth_min,
                s_lo,
            ]
        )
        hi = np.array(
            [
                *self.position_max,
                *self.base_velocity_max,
                self.roll,
                self.elevation_max,
                self.azimuth_max,
                s_hi,
            ]
        )
        return lo, hi

    def violation(self, sigma: np.ndarray, ee: EndEffectorParams, tol: float = 1e-9) -> list[str]:
        """Names of the σ components outside the bounds (empty when σ is inside)."""
        lo, hi = self.vectors(ee)
        s = np.asarray(sigma, float)
        return [
            f"{SIGMA_COLUMNS[i]}={s[i]:.6g} not in [{lo[i]:.6g}, {hi[i]:.6g}]"
            for i in range(len(SIGMA_COLUMNS))
            if not lo[i] - tol <= s[i] <= hi[i] + tol
        ]

    def elevations(self) -> np.ndarray:
        """The fast path's candidate elevations [rad], shape (n_elevations,)."""
        if self.n_elevations == 1:
            return np.array([0.5 * (self.elevation_min + self.elevation_max)])
        return np.linspace(self.elevation_min, self.elevation_max, self.n_elevations)

    def clip_position(self, p: np.ndarray) -> np.ndarray:
        """A point moved into the release box [m, W], shape (3,)."""
        return np.clip(np.asarray(p, float), self.position_min, self.position_max)

    def nominal_release(self, target_xy: np.ndarray) -> np.ndarray:
        """The fast path's release point for a target [m, W], shape (3,).

        `release_radius` from the base toward the target at `release_height`,
        moved into the box.
        """
        tx, ty = float(target_xy[0]), float(target_xy[1])
        beta = math.atan2(ty, tx) if (tx or ty) else 0.0
        p = np.array(
            [
                self.release_radius * math.cos(beta),
                self.release_radius * math.sin(beta),
                self.release_height,
            ]
        )
        return self.clip_position(p)


DEFAULT_BOUNDS = ThrowBounds()
