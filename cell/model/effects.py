"""Effects: augmentations of the nominal throw model (GAP.md's vocabulary).

Each effect is a frozen dataclass with a few parameters (SI units in their
names), bounds, a typical scale, the phase it acts in and, where its size
hangs on a logged quantity, that quantity's name (for the permutation
control of the sim-to-real diagnosis). Every form is physically shaped:

| effect | form |
|---|---|
| band_mass | the push drives m + m_b (m_b = `mass_kg`) |
| band_damping | f_o scaled by (1 - c ΔL), c = `per_m` [1/m]: a loss growing with stretch |
| shape_stretch | curved or irregular objects (cylinder, sphere, mesh) stretch the band by k·a more |
| stroke_offset | the true stroke is the logged one + δ (`delta_m`) |
| release_pitch | the object leaves at elevation + δ (`delta_rad`) |
| downwash (column) | air moves down at w = k (rpm / 5000)^p within `radius_m` of the release (horizontally) |
| downwash (decay) | the same column, its speed falling off as exp(−depth / `depth_m`) below the release height |
| downwash (jet) | a free round jet below the release point: a Gaussian profile exp(−(ρ / b)²) whose width b = `radius_m` + `JET_SPREAD` · depth grows with the depth, its centre speed w · `radius_m` / b (the jet's momentum flux kept) |
| wind | a constant air velocity (`x_mps`, `y_mps`, `z_mps`) in the drag law |
| wind (level) | the same without its vertical part (`x_mps`, `y_mps`) |
| drag_scale | the drag constant k = ½ρC_dA/m times `factor` (C_d off for rough, soft or tumbling objects) |
| spin | Magnus lift ½ρA C_L |v|² / m normal to v in its vertical plane, C_L = c tanh(S / c), S = ω r / |v| |
| tracking_scale | the tracker logs s · true positions (about the world origin); release poses and planes are the robot's, true |
| bounce (friction) | the logged point is the rest point: touchdown + v_h |v_h| / (2 μ g) (∝ impact speed²) |
| bounce (rolling) | the rest point is touchdown + `tau_s` · v_h (∝ impact speed: rolling) |
| bounce (impact) | a Coulomb contact that takes its friction impulse at the impact too: v_h loses μ v_z as the object hits (a plastic impact, v_z the vertical impact speed), then slides (v_h − μ v_z)² / (2 μ g) further, nothing where μ v_z ≥ v_h; `inv_mu_imp` = 1/μ |
| bounce (drop) | the object falls on from the landing plane to a floor `depth_m` below it (its centre to its smallest half-extent r above it: v_h t_d further), hits it at v_z' = √(v_z² + 2 g (depth_m − r)) as the impact law's contact, then slides (v_h − μ v_z')² / (2 μ g); `inv_mu_drop` = 1/μ (`cell.model.effects_bounce`) |
| bounce (roll) | a ball falls on to the floor (z = 0) from the log's plane (`land_z_m` above it) as in the drop law, the impact brings it to rolling at 5/7 v_h less the rolling resistance's impulse 5 μ_r v_z' / (7 r), then it rolls v'² · 7 r / (10 μ_r g) to rest (a deceleration 5 μ_r g / (7 r)); `inv_mu_r_per_m` = 1/μ_r [1/m], μ_r the rolling resistance length |

An effect is a family of laws (`FAMILIES`): its members share the name and the phase and
differ in how the effect grows (the diagnosis picks the member that predicts held-out
throws best). Besides its bounds, each effect has a plausible range (`plausible`): a value
no real cell has (a 2 m/s updraught indoors) is outside it.

`predict_with_effects` evaluates a batch with any set of effects; launch
effects reuse `predict_landing`'s push overrides, flight effects use the 3-D
integrator of `cell.model.flight3d`. With no effects it is exactly the
nominal model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from cell.errors import InvalidParameter
from cell.model.effect_base import Effect
from cell.model.effects_bounce import Bounce, BounceDrop, BounceImpact, BounceRoll, BounceRolling
from cell.model.objects import SHAPES

if TYPE_CHECKING:
    pass

__all__ = [
    "Effect",
    "BandMass",
    "BandDamping",
    "ShapeStretch",
    "StrokeOffset",
    "ReleasePitch",
    "Downwash",
    "Wind",
    "WindLevel",
    "Spin",
    "TrackingScale",
    "Bounce",
    "BounceRolling",
    "BounceImpact",
    "BounceDrop",
    "BounceRoll",
    "DownwashDecay",
    "DownwashJet",
    "DragScale",
    "EFFECTS",
    "FAMILIES",
    "PHASES",
    "effects_from_mapping",
    "effects_to_mapping",
]

PHASES = ("launch", "flight", "landing", "measurement")
_CURVED = np.array([s in ("cylinder", "sphere", "mesh") for s in SHAPES])
DOWNWASH_EDGE_M = 0.05  # [m] width of the smooth edge of the downwash column
DOWNWASH_REF_RPM = 5000.0  # [rpm] rotor speed at which the downwash speed is k
# [-] a round turbulent jet's spreading rate: the 1/e width of its Gaussian profile grows
# by this per metre downstream (half-velocity width 0.094 x, Hussein, Capp & George 1994,
# Pope, Turbulent Flows, 2000, Table 5.1, divided by √ln 2); a property of free round
# jets, not fitted to any case (the landings hang little on it: docs/gap_scene.md)
JET_SPREAD = 0.11


@dataclass(frozen=True)
class BandMass(Effect):
    """Part of the band moves with the object during the push."""

    name: ClassVar[str] = "band_mass"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 0.2),)
    scale: ClassVar[tuple[float, ...]] = (0.01,)
    hangs_on: ClassVar[str | None] = "mass"
    mass_kg: float = 0.0  # [kg] band mass driven with the object


@dataclass(frozen=True)
class BandDamping(Effect):
    """The band loses a share c·ΔL of its push on release."""

    name: ClassVar[str] = "band_damping"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 8.0),)
    scale: ClassVar[tuple[float, ...]] = (1.0,)
    hangs_on: ClassVar[str | None] = "stretch"
    per_m: float = 0.0  # [1/m] loss per metre of stretch


@dataclass(frozen=True)
class ShapeStretch(Effect):
    """Curved or irregular objects stretch the band by k·a more (a = grip width)."""

    name: ClassVar[str] = "shape_stretch"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-1.0, 1.0),)
    scale: ClassVar[tuple[float, ...]] = (0.1,)
    hangs_on: ClassVar[str | None] = "shape"
    k: float = 0.0  # [-] extra stretch per metre of width


@dataclass(frozen=True)
class StrokeOffset(Effect):
    """The true stroke is the logged one plus a constant."""

    name: ClassVar[str] = "stroke_offset"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-0.03, 0.03),)
    scale: ClassVar[tuple[float, ...]] = (0.003,)
    delta_m: float = 0.0  # [m]


@dataclass(frozen=True)
class ReleasePitch(Effect):
    """The object leaves at the commanded elevation plus a constant."""

    name: ClassVar[str] = "release_pitch"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-0.4, 0.4),)
    scale: ClassVar[tuple[float, ...]] = (0.03,)
    delta_rad: float = 0.0  # [rad]


@dataclass(frozen=True)
class Downwash(Effect):
    """Rotor downwash: air moving down near the drone, growing with rotor speed."""

    name: ClassVar[str] = "downwash"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 40.0), (0.02, 5.0), (0.5, 2.5))
    scale: ClassVar[tuple[float, ...]] = (2.0, 0.3, 0.5)
    hangs_on: ClassVar[str | None] = "rotor_rpm"
    law: ClassVar[str] = "column"
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = (
        (0.0, 15.0),
        (0.05, 3.0),
        (0.5, 2.5),
    )
    speed_mps: float = 0.0  # [m/s] downward air speed at DOWNWASH_REF_RPM
    radius_m: float = 0.5  # [m] horizontal reach of the column around the release point
    exponent: float = 1.0  # [-] w ∝ rpm^exponent


@dataclass(frozen=True)
class DownwashDecay(Effect):
    """Rotor downwash falling off with depth below the rotor (the release height)."""

    name: ClassVar[str] = "downwash"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = (
        (0.0, 40.0),
        (0.02, 5.0),
        (0.05, 10.0),
        (0.5, 2.5),
    )
    scale: ClassVar[tuple[float, ...]] = (2.0, 0.3, 0.5, 0.5)
    hangs_on: ClassVar[str | None] = "rotor_rpm"
    law: ClassVar[str] = "decay"
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = (
        (0.0, 15.0),
        (0.05, 3.0),
        (0.05, 8.0),
        (0.5, 2.5),
    )
    speed_mps: float = 0.0  # [m/s] downward air speed at the rotor, at DOWNWASH_REF_RPM
    radius_m: float = 0.5  # [m] horizontal reach of the column around the release point
    depth_m: float = 1.0  # [m] e-folding depth of the speed below the release height
    exponent: float = 1.0  # [-] w ∝ rpm^exponent


@dataclass(frozen=True)
class DownwashJet(Effect):
    """Rotor downwash as a round jet: the far-field law of a free round turbulent jet below
    the rotor, a Gaussian profile whose width grows in proportion to the depth at the
    round jet's spreading rate (`JET_SPREAD`) and whose centre speed falls as the width
    grows (a free jet keeps its momentum flux, ∝ centre speed² · width²): the form a
    column of fixed reach or an exponential decay cannot take when the jet widens and
    slows algebraically over the drop."""

    name: ClassVar[str] = "downwash"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 40.0), (0.02, 5.0), (0.5, 2.5))
    scale: ClassVar[tuple[float, ...]] = (2.0, 0.3, 0.5)
    hangs_on: ClassVar[str | None] = "rotor_rpm"
    law: ClassVar[str] = "jet"
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = (
        (0.0, 25.0),
        (0.05, 3.0),
        (0.5, 2.5),
    )
    speed_mps: float = 0.0  # [m/s] centre speed at the rotor, at DOWNWASH_REF_RPM
    radius_m: float = 0.5  # [m] the profile's width (1/e of the speed) at the rotor
    exponent: float = 1.0  # [-] w ∝ rpm^exponent


# [m/s] an indoor cell's air: a fan's jet or a draught through a door reaches a fresh
# breeze across (6 m/s); air rising or sinking, away from a drone's rotors, stays slow
WIND_ACROSS_MPS = 6.0
WIND_UP_MPS = 1.0


@dataclass(frozen=True)
class WindLevel(Effect):
    """A steady horizontal air flow in the cell (world frame): the wind without its
    vertical part (`Wind` adds it as a term, chosen where it predicts held-out throws
    better and stays within its plausible range)."""

    name: ClassVar[str] = "wind"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-10.0, 10.0),) * 2
    scale: ClassVar[tuple[float, ...]] = (1.0, 1.0)
    law: ClassVar[str] = "level"
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = (
        (-WIND_ACROSS_MPS, WIND_ACROSS_MPS),
    ) * 2
    x_mps: float = 0.0
    y_mps: float = 0.0

    @property
    def z_mps(self) -> float:
        """No vertical part."""
        return 0.0


@dataclass(frozen=True)
class Wind(Effect):
    """A steady air flow in the cell (world frame)."""

    name: ClassVar[str] = "wind"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-10.0, 10.0),) * 3
    scale: ClassVar[tuple[float, ...]] = (1.0, 1.0, 1.0)
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = (
        (-WIND_ACROSS_MPS, WIND_ACROSS_MPS),
    ) * 2 + ((-WIND_UP_MPS, WIND_UP_MPS),)
    law: ClassVar[str] = "with vertical"
    x_mps: float = 0.0
    y_mps: float = 0.0
    z_mps: float = 0.0


@dataclass(frozen=True)
class Spin(Effect):
    """Magnus lift from a spin the object leaves with (positive = backspin)."""

    name: ClassVar[str] = "spin"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((-600.0, 600.0), (0.05, 1.0))
    scale: ClassVar[tuple[float, ...]] = (20.0, 0.2)
    spin_rad_s: float = 0.0  # [rad/s]
    lift_max: float = 0.4  # [-] saturated lift coefficient


@dataclass(frozen=True)
class DragScale(Effect):
    """The object's air drag is `factor` times what its shape's C_d says."""

    name: ClassVar[str] = "drag_scale"
    phase: ClassVar[str] = "flight"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.1, 6.0),)
    scale: ClassVar[tuple[float, ...]] = (0.05,)
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = ((0.25, 4.0),)
    factor: float = 1.0  # [-] C_d multiplier


@dataclass(frozen=True)
class TrackingScale(Effect):
    """The tracking system sees positions scaled by s about its (the world) origin."""

    name: ClassVar[str] = "tracking_scale"
    phase: ClassVar[str] = "measurement"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.5, 2.0),)
    scale: ClassVar[tuple[float, ...]] = (0.01,)
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = ((0.8, 1.25),)
    scale_factor: float = 1.0  # [-]


EFFECTS: dict[str, type[Effect]] = {
    c.name: c
    for c in (
        BandMass,
        BandDamping,
        ShapeStretch,
        StrokeOffset,
        ReleasePitch,
        Downwash,
        Wind,
        Spin,
        DragScale,
        TrackingScale,
        Bounce,
    )
}

# every effect's family of laws (the first member is the effect's class in EFFECTS)
FAMILIES: dict[str, tuple[type[Effect], ...]] = {
    name: (cls, *extra)
    for name, cls in EFFECTS.items()
    for extra in [
        {
            "downwash": (DownwashDecay, DownwashJet),
            "bounce": (BounceRolling, BounceImpact, BounceDrop, BounceRoll),
            "wind": (WindLevel,),
        }.get(name, ())
    ]
}


def member_for(name: str, params: Sequence[str]) -> type[Effect] | None:
    """The family member of effect `name` whose parameters are `params` (or a subset)."""
    for cls in FAMILIES.get(name, ()):
        if set(params) <= set(cls.param_names()):
            return cls
    return None


def effects_from_mapping(mapping: Mapping[str, Mapping[str, Any]] | None) -> list[Effect]:
    """Effects from a parameter file's `effects` mapping {name: {param: value}}.

    Raises:
        InvalidParameter: an unknown effect or parameter, or a value out of range.
    """
    out: list[Effect] = []
    for name, values in (mapping or {}).items():
        cls0 = EFFECTS.get(str(name))
        if cls0 is None:
            raise InvalidParameter(f"effects: unknown effect {name!r}; valid: {', '.join(EFFECTS)}")
        values = values or {}
        if not isinstance(values, Mapping):
            raise InvalidParameter(f"effects.{name}: must map parameter names to numbers")
        cls = member_for(str(name), list(values)) or cls0
        names = tuple(dict.fromkeys(n for c in FAMILIES[str(name)] for n in c.param_names()))
        bad = [k for k in values if k not in names]
        if bad:
            raise InvalidParameter(
                f"effects.{name}: unknown parameter(s) {bad}; valid: {', '.join(names)}"
            )
        if member_for(str(name), list(values)) is None:
            laws = "; ".join(f"{c.law}: {', '.join(c.param_names())}" for c in FAMILIES[str(name)])
            raise InvalidParameter(
                f"effects.{name}: parameters {list(values)} mix laws of the family ({laws})"
            )
        try:
            vals = {k: float(v) for k, v in values.items()}
        except (TypeError, ValueError):
            raise InvalidParameter(f"effects.{name}: parameters must be numbers") from None
        out.append(cls(**vals))
    return out


def effects_to_mapping(effects: Sequence[Effect]) -> dict[str, dict[str, float]]:
    """The parameter-file form {name: {param: value}} of a list of effects."""
    return {e.name: e.params() for e in effects}


def _find(effects: Sequence[Effect], cls: type[Effect]) -> Any:
    for e in effects:
        if isinstance(e, cls):
            return e
    return None
