"""The bounce's family of laws (`cell.model.effects.FAMILIES`): where an object that
crossed the landing plane comes to rest on the floor, each member one law of the slide
(`cell.model.effects_apply._after_landing` moves the landing points by it)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from cell.model.effect_base import Effect

__all__ = ["Bounce", "BounceRolling", "BounceImpact", "BounceDrop", "BounceRoll"]


@dataclass(frozen=True)
class Bounce(Effect):
    """The logged point is where the object came to rest after sliding."""

    name: ClassVar[str] = "bounce"
    phase: ClassVar[str] = "landing"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 2.0),)
    scale: ClassVar[tuple[float, ...]] = (0.05,)
    law: ClassVar[str] = "friction"
    inv_mu: float = 0.0  # [-] 1/μ, the inverse friction coefficient of the slide


@dataclass(frozen=True)
class BounceRolling(Effect):
    """The logged point is where the object came to rest after rolling on: tau_s · v_h
    beyond the touchdown (a speed decaying with time constant tau_s)."""

    name: ClassVar[str] = "bounce"
    phase: ClassVar[str] = "landing"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 1.0),)
    scale: ClassVar[tuple[float, ...]] = (0.01,)
    law: ClassVar[str] = "rolling"
    tau_s: float = 0.0  # [s] rolled distance per m/s of horizontal impact speed


@dataclass(frozen=True)
class BounceImpact(Effect):
    """The logged point is where the object came to rest on a Coulomb contact of friction
    μ that acts through the impact as well: the floor's normal impulse m v_z (a plastic
    impact, v_z the vertical impact speed) brings a friction impulse of at most μ m v_z,
    so the object leaves the impact at v_h − μ v_z (or stops), then slides under μ g
    to rest: (v_h − μ v_z)² / (2 μ g) beyond the touchdown. A rolling ball's resistance
    takes the same form (its torque, too, is bounded by the normal force, at the impact as
    after it). Steep impacts slide less than flat ones of the same v_h, which the friction
    law (v_h² / (2 μ g)) cannot tell apart.

    The slide is nil wherever μ v_z ≥ v_h, so about its neutral size (μ → ∞) the law is
    flat: a fit without a warm start begins at μ 0.5 (`start`), a middling floor's."""

    name: ClassVar[str] = "bounce"
    phase: ClassVar[str] = "landing"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 5.0),)
    scale: ClassVar[tuple[float, ...]] = (0.05,)
    law: ClassVar[str] = "impact"
    start: ClassVar[tuple[float, ...] | None] = (2.0,)
    inv_mu_imp: float = 0.0  # [-] 1/μ of the contact (impact impulse and slide)


@dataclass(frozen=True)
class BounceDrop(Effect):
    """The logged point is where the object came to rest on a floor `depth_m` below the
    landing plane (the world frame's floor, z = 0, under a plane at `land_z`): from the
    crossing the object falls on until it touches the floor, its centre r (its smallest
    half-extent) above it, moving v_h · t_d further (t_d the free fall's time over
    depth_m − r from the crossing's v_z), hits the floor at v_z' = √(v_z² + 2 g (depth_m − r))
    as the impact law's plastic Coulomb contact (v_h loses μ v_z', or stops), then slides
    to rest braked by the friction and by the air as in its flight (dv/dt = −μ g − k v²,
    k = ½ ρ C_d A / m its drag constant, times a drag scale's factor where there is one):
    ln(1 + k v_h'² / (μ g)) / (2 k), (v_h − μ v_z')² / (2 μ g) where k → 0 (on a slide of
    a metre or two the air takes a few per cent off). A ball whose rolling resistance
    holds its spin at nil (Bullet's rolling friction, a torque up to μ_r N, outlasts the
    friction's μ N r where μ_r ≥ μ r) slides so; the impact law taken at the plane misses
    the fall by a length that hangs on v_h / v_z and on the object's size.

    At its neutral size (depth_m 0, 1/μ 0) it does nothing; the fall is nil where
    depth_m ≤ r, so a fit without a warm start begins below the objects' half-sizes'
    range (`start`: a floor 0.25 m down, μ 0.5, a middling floor's).

    A law of the throw (`cell.gap.laws`) may be given to 1/μ alone (`law_params`): the
    contact's friction is the object's and the floor's (an object of another mass or
    shape may meet the floor otherwise), while the depth is the cell's geometry, the same
    under every throw, and stays one value common to all."""

    name: ClassVar[str] = "bounce"
    phase: ClassVar[str] = "landing"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 5.0), (0.0, 1.0))
    scale: ClassVar[tuple[float, ...]] = (0.05, 0.01)
    law: ClassVar[str] = "drop"
    start: ClassVar[tuple[float, ...] | None] = (2.0, 0.25)
    law_params: ClassVar[tuple[str, ...] | None] = ("inv_mu_drop",)
    inv_mu_drop: float = 0.0  # [-] 1/μ of the floor's contact (impact impulse and slide)
    depth_m: float = 0.0  # [m] the floor's depth below the landing plane


@dataclass(frozen=True)
class BounceRoll(Effect):
    """The logged point is where a ball came to rest after rolling on the floor, the
    world frame's z = 0 under a landing plane at the log's `land_z_m` (`docs/throw_log.md`:
    the height of the plane, 0 the floor): the drop law's fall (v_h · t_d further, the
    floor hit at v_z' = √(v_z² + 2 g (land_z − r)), r the object's smallest half-extent),
    then an impact whose friction brings the ball to rolling (ω r = v) at 5/7 v_h (a ball
    of zero spin: its moment of inertia 2/5 m r²; the friction impulse is taken as large
    enough, μ v_z' ≥ 2/7 v_h) less the rolling resistance's impulse 5 μ_r v_z' / (7 r) (a
    torque up to μ_r N over the normal impulse m v_z'), or stopped, then a roll at the
    deceleration 5 μ_r g / (7 r) to rest: 7 r v'² / (10 μ_r g) further. μ_r [m] is the
    rolling resistance length (Bullet's rolling friction: a torque up to μ_r N); a ball
    rolls so where μ_r < μ r, and slides as the drop law has it elsewhere. Only a ball
    rolls: an object of another shape is left where it crossed the plane.

    Its one parameter is 1/μ_r [1/m], so that the neutral size (0) does nothing (an
    infinite resistance: no roll beyond the fall); the depth is the log's, not fitted: a
    fitted depth takes up the configured model's flight misses along v_h on long rolls
    (`s:bounce-roll-hard`: 0.217 m for the plane's 0.1, docs/HISTORY.md). The roll is nil
    wherever 5 μ_r v_z' ≥ 5 v_h r, so about the neutral size the law is flat: a fit
    without a warm start begins at μ_r 0.01 m (a hard floor's few mm)."""

    name: ClassVar[str] = "bounce"
    phase: ClassVar[str] = "landing"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.0, 2000.0),)
    scale: ClassVar[tuple[float, ...]] = (10.0,)
    law: ClassVar[str] = "roll"
    start: ClassVar[tuple[float, ...] | None] = (100.0,)
    inv_mu_r_per_m: float = 0.0  # [1/m] 1/μ_r, the inverse rolling resistance length
