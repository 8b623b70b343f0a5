"""End-effector parameters η_ee (MODEL.md reference defaults).

All lengths in [m], forces in [N], times in [s], angles in [rad].
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from cell.errors import InvalidParameter, plural

__all__ = ["EndEffectorParams", "G", "RHO_AIR", "DEFAULT_EE", "aero_factor_kg_per_m"]

G = 9.81  # [m/s^2] gravity magnitude; world frame W has z up
RHO_AIR = 1.225  # [kg/m^3] air density


def aero_factor_kg_per_m(coefficient: Any, area: Any) -> Any:
    """½ ρ C A [kg/m]: the air force on a body is this times |v|² (MODEL.md eq. 3.10).

    With C = C_d it is the drag factor c (force −c |v| v [N]); divided by the mass,
    the drag constant k [1/m] of the model (`cell.model.throw.drag_constant`); with a
    lift coefficient, the lift factor. Floats or arrays alike.
    """
    return 0.5 * RHO_AIR * coefficient * area


@dataclass(frozen=True)
class EndEffectorParams:
    """The end-effector's parameters η_ee.

    Attributes:
        r_r: roller radius [m].
        l1: clamp to roller tangent [m].
        phi: band wrap angle on the roller [rad].
        d: hoop width [m].
        L_t: base plate to band origin [m].
        L0: free half-length of the band [m].
        Ke3: cubic band coefficient [N/m^3].
        Ke2: quadratic band coefficient [N/m^2].
        Ke1: linear band coefficient [N/m].
        C: band force offset [N].
        dt: duration of the launch push [s].
        stroke_min: smallest allowed stroke L_s [m].
        stroke_max: largest allowed stroke L_s [m].
        L_e: where the item leaves the carriage [m, carriage position like L_s], or 0 (the
            thesis model: the item leaves at the end of the push). With L_e > 0 the item
            rides the carriage from L_s to L_e after the push (`cell.model.throw.ride`): it
            is carried L_e − L_s along the throw axis, the pads hold it across the axis, and
            gravity's component along the axis takes 2 g sin(e) (L_e − L_s) from its speed
            squared. The PyBullet scene's carriage runs on to its end stop before the item
            flies free, so its calibration sets L_e; an older file without it keeps 0.
    """

    r_r: float = 0.010
    l1: float = 0.030
    phi: float = math.pi / 2
    d: float = 0.020
    L_t: float = 0.160
    L0: float = 0.095
    Ke3: float = 400.0
    Ke2: float = 150.0
    Ke1: float = 114.6
    C: float = 0.0
    dt: float = 0.012
    stroke_min: float = 0.03
    stroke_max: float = 0.11
    L_e: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not isinstance(v, (int, float)) or not math.isfinite(float(v)):
                raise InvalidParameter(
                    f"end-effector parameter {f.name}={v!r} must be a finite number"
                )
        positive = ("r_r", "l1", "d", "L_t", "L0", "dt")
        for name in positive:
            if getattr(self, name) <= 0:
                raise InvalidParameter(
                    f"end-effector parameter {name}={getattr(self, name)} must be > 0"
                )
        # A band is a stiffening spring: its force grows with stretch and its stored energy is
        # positive (identification keeps the same bounds).
        if self.Ke1 <= 0 or min(self.Ke3, self.Ke2) < 0:
            raise InvalidParameter(
                f"band stiffnesses Ke3={self.Ke3}, Ke2={self.Ke2}, Ke1={self.Ke1} N/m^k: valid "
                "are Ke1 > 0 and Ke3, Ke2 >= 0 (a band's force grows with its stretch; a "
                "negative stiffness would store negative energy)"
            )
        if not 0 <= self.phi <= math.pi:
            raise InvalidParameter(f"end-effector parameter phi={self.phi} must be in [0, pi] rad")
        if not 0 < self.stroke_min < self.stroke_max < self.L_t:
            raise InvalidParameter(
                f"stroke range [{self.stroke_min}, {self.stroke_max}] m must satisfy "
                f"0 < stroke_min < stroke_max < L_t={self.L_t}"
            )
        if self.L_e != 0 and not self.stroke_min < self.L_e < self.L_t:
            raise InvalidParameter(
                f"end-effector parameter L_e={self.L_e} m (where the item leaves the carriage) "
                f"must be 0 (off) or in (stroke_min={self.stroke_min}, L_t={self.L_t})"
            )

    def as_dict(self) -> dict[str, float]:
        """The parameters as a plain dict of floats (L_e only when it is on, so files and
        reports of the thesis model stay as they were)."""
        return {k: float(v) for k, v in asdict(self).items() if k != "L_e" or v != 0}

    @classmethod
    def from_dict(cls, values: dict[str, Any], *, where: str = "parameters") -> EndEffectorParams:
        """Build from a dict, naming any unknown key and the valid ones.

        Raises:
            InvalidParameter: on an unknown key or a bad value.
        """
        valid = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - valid)
        if unknown:
            raise InvalidParameter(
                f"{where}: {plural(len(unknown), 'unknown end-effector parameter')} {unknown}; "
                f"valid: {sorted(valid)}"
            )
        numbers: dict[str, float] = {}
        for k, v in values.items():
            try:
                numbers[k] = float(v)
            except (TypeError, ValueError):
                raise InvalidParameter(f"{where}.{k}: {v!r} is not a number") from None
            bound, unit = _FILE_BOUNDS.get(k, (1e9, ""))
            if math.isfinite(numbers[k]) and abs(numbers[k]) > bound:
                raise InvalidParameter(
                    f"{where}.{k}: {numbers[k]:g}{unit} is an absurd magnitude; a value "
                    f"within ±{bound:g}{unit} is valid"
                )
        try:
            return replace(cls(), **numbers)
        except (TypeError, ValueError) as exc:
            if isinstance(exc, InvalidParameter):
                raise InvalidParameter(f"{where}: {exc}") from None
            raise InvalidParameter(f"{where}: {exc}") from None

    # Parameters stage 1 of identification may change (thesis Algorithm 1).
    IDENTIFIABLE = ("Ke3", "Ke2", "Ke1", "C", "r_r", "l1", "phi", "dt")


# The largest magnitude a parameter file may give (typos like 1e300, not physics: the
# constructor's own checks say what is physical); stiffnesses and others up to 1e9.
_FILE_BOUNDS = {
    **{k: (10.0, " m") for k in ("r_r", "l1", "d", "L_t", "L0", "stroke_min", "stroke_max", "L_e")},
    "dt": (10.0, " s"),
    "C": (1e6, " N"),
}

DEFAULT_EE = EndEffectorParams()
