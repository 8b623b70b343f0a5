"""The effects applied: the launch under the launch effects, the flight's extra
accelerations, and the landing points as observed (`predict_with_effects`). The effects
themselves, their parameters and families, are in `cell.model.effects`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from cell.model.band import band_angle, band_force, band_stretch
from cell.model.effects import (
    _CURVED,
    DOWNWASH_REF_RPM,
    BandDamping,
    BandMass,
    Bounce,
    BounceDrop,
    BounceImpact,
    BounceRoll,
    BounceRolling,
    Downwash,
    DownwashDecay,
    DownwashJet,
    DragScale,
    Effect,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    TrackingScale,
    Wind,
    WindLevel,
    _find,
    effects_from_mapping,
)
from cell.model.effects_air import AirKind, make_accel
from cell.model.flight3d import fly
from cell.model.params import EndEffectorParams, G, aero_factor_kg_per_m
from cell.model.throw import (
    Landing,
    ThrowBatch,
    drag_constant,
    launch_state,
    no_landing_error,
    predict_landing,
    throw_axis,
)

__all__ = ["flight_accel", "launch_overrides", "predict_with_effects"]


def _permuted(values: np.ndarray, permutation: np.ndarray | None) -> np.ndarray:
    return values if permutation is None else values[permutation]


def launch_overrides(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    effects: Sequence[Effect],
    *,
    permutation: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The push f_o [N], the pushed mass [kg] and the throw axis (n, 3) under the launch effects.

    Args:
        batch: the throws.
        ee: end-effector parameters.
        effects: the effects (non-launch ones are ignored).
        permutation: when given, each effect's own term reads the quantity it hangs
            on from the throws in this order (the permutation control).
    """
    so = _find(effects, StrokeOffset)
    bm = _find(effects, BandMass)
    bd = _find(effects, BandDamping)
    ss = _find(effects, ShapeStretch)
    rp = _find(effects, ReleasePitch)
    stroke = batch.stroke + (so.delta_m if so else 0.0)
    width = batch.size[:, 0]
    stretch = band_stretch(stroke, width, ee)
    if ss is not None:
        curved = _permuted(_CURVED[batch.shape], permutation)
        stretch = stretch + ss.k * curved * _permuted(width, permutation)
    push = 2 * band_force(stretch, ee) * np.cos(band_angle(stroke, width, ee))
    if bd is not None:
        push = push * np.clip(1.0 - bd.per_m * _permuted(stretch, permutation), 0.0, None)
    m = batch.mass
    if bm is not None:
        mp = _permuted(m, permutation)
        push_mass = m * (mp + bm.mass_kg) / mp  # = m + m_b without permutation
    else:
        push_mass = m
    elevation = batch.elevation + (rp.delta_rad if rp else 0.0)
    return push, push_mass, throw_axis(elevation, batch.azimuth)


def _flight_accel(
    batch: ThrowBatch,
    effects: Sequence[Effect],
    rotor_rpm: np.ndarray,
    permutation: np.ndarray | None,
) -> Any:
    wind = _find(effects, Wind) or _find(effects, WindLevel)
    dw = _find(effects, Downwash) or _find(effects, DownwashDecay) or _find(effects, DownwashJet)
    sp = _find(effects, Spin)
    ds = _find(effects, DragScale)
    if wind is None and dw is None and sp is None and ds is None:
        return None
    decay, jet = isinstance(dw, DownwashDecay), isinstance(dw, DownwashJet)
    par = _params(wind, dw, sp)
    # a parameter given one value per throw (a fit's stacked Jacobian, cell/gap/fit_jac.py)
    # is read at the rows integrated, like the per-throw arrays
    per_throw = {k: v for k, v in par.items() if np.ndim(v) == (2 if k == "w" else 1)}
    if dw is not None:
        rpm = _permuted(rotor_rpm, permutation)
        per_throw["w_dw"] = (
            dw.speed_mps * (np.clip(rpm, 0.0, None) / DOWNWASH_REF_RPM) ** dw.exponent
        )
        per_throw["cx"], per_throw["cy"] = batch.position[:, 0], batch.position[:, 1]
        per_throw["release_z"] = batch.position[:, 2]
    if sp is not None:
        per_throw["kl"] = aero_factor_kg_per_m(1.0, _area(batch)) / batch.mass  # [1/m] per C_L
        per_throw["size_radius"] = batch.size.max(axis=1) / 2
    if ds is not None:
        # the drag the nominal law does not have: (factor - 1) of it
        k_extra = (ds.factor - 1.0) * drag_constant(batch.shape, batch.mass, batch.size)
        per_throw["neg_k_extra"] = -k_extra
    kind = AirKind(wind is not None, dw is not None, decay, jet, sp is not None, ds is not None)
    return make_accel(kind, par, per_throw, len(batch))


def _params(wind: Any, dw: Any, sp: Any) -> dict[str, Any]:
    """The flight effects' parameters the callback reads: each a scalar, or one value per
    throw (n,) (the air velocity (3,) or (n, 3))."""
    w = np.array([wind.x_mps, wind.y_mps, wind.z_mps], float).T if wind else np.zeros(3)
    par: dict[str, Any] = {"w": w}
    if dw is not None:
        par["radius"] = dw.radius_m
        if isinstance(dw, DownwashDecay):
            par["depth"] = dw.depth_m
    if sp is not None:
        par["spin"], par["lift_max"] = sp.spin_rad_s, sp.lift_max
    return par


def flight_accel(
    batch: ThrowBatch,
    effects: Sequence[Effect],
    rotor_rpm: np.ndarray | None = None,
    *,
    permutation: np.ndarray | None = None,
) -> Any:
    """The flight effects' air velocity and extra acceleration as `flight3d.Accel`
    (None when no flight effect is present)."""
    rpm = np.zeros(len(batch)) if rotor_rpm is None else np.asarray(rotor_rpm, float)
    effs = [e.per_throw(batch, permutation) for e in effects]
    return _flight_accel(batch, effs, rpm, permutation)


def _area(batch: ThrowBatch) -> np.ndarray:
    from cell.model.objects import drag_area

    return np.asarray(drag_area(batch.shape, batch.size))


def _after_landing(
    xy: np.ndarray,
    v_imp: np.ndarray,
    effs: Sequence[Effect],
    size: np.ndarray | None = None,
    shape: np.ndarray | None = None,
    land_z: np.ndarray | None = None,
    k_drag: np.ndarray | None = None,
) -> np.ndarray:
    """The landing points xy [m] (n, 2) moved on by the landing effects (a bounce, a roll)
    from the impact velocities v_imp [m/s] (n, 3) at the landing plane; `size` (n, 3) [m]
    the objects' extents (the drop law's fall ends at the smallest half-extent), `shape`
    (n,) their shape codes (`cell.model.objects.SHAPES`: the roll law moves balls alone;
    None: every object a ball), `land_z` (n,) [m] the landing planes' heights above the
    floor (the roll law's fall; None: 0, no fall), `k_drag` (n,) [1/m] the air's drag
    constant on each object as it slides (the drop law's slide; None: no drag)."""
    # a parameter is one value, or one per throw (a law in a covariate, `cell.gap.laws`)
    bo = _find(effs, Bounce)
    if bo is not None and np.any(np.asarray(bo.inv_mu) > 0):
        vh = v_imp[:, :2]
        inv_mu = np.asarray(bo.inv_mu, float)
        xy = xy + vh * (np.linalg.norm(vh, axis=1) * inv_mu / (2 * G))[:, None]
    br = _find(effs, BounceRolling)
    if br is not None and np.any(np.asarray(br.tau_s) > 0):
        xy = xy + v_imp[:, :2] * np.reshape(np.asarray(br.tau_s, float), (-1, 1))
    bi = _find(effs, BounceImpact)
    if bi is not None and np.any(np.asarray(bi.inv_mu_imp) > 0):
        # the impact's friction impulse μ v_z off v_h, then the slide (v_h')² / (2 μ g)
        vh = v_imp[:, :2]
        speed = np.linalg.norm(vh, axis=1)
        inv_mu = np.asarray(bi.inv_mu_imp, float)
        mu = 1.0 / np.maximum(inv_mu, 1e-12)
        left = np.maximum(speed - mu * np.abs(v_imp[:, 2]), 0.0)
        slide = left**2 * inv_mu / (2 * G)
        xy = xy + vh * (slide / np.maximum(speed, 1e-12))[:, None]
    bd = _find(effs, BounceDrop)
    if bd is not None and (
        np.any(np.asarray(bd.inv_mu_drop) > 0) or np.any(np.asarray(bd.depth_m) > 0)
    ):
        xy = xy + drop_slide(v_imp, bd.inv_mu_drop, bd.depth_m, size, k_drag)
    bl = _find(effs, BounceRoll)
    if bl is not None and np.any(np.asarray(bl.inv_mu_r_per_m) > 0):
        move = roll_move(v_imp, bl.inv_mu_r_per_m, 0.0 if land_z is None else land_z, size)
        if shape is not None:  # a block does not roll: the law leaves it where it landed
            from cell.model.objects import SHAPES

            move = move * (np.asarray(shape) == SHAPES.index("sphere"))[:, None]
        xy = xy + move
    return xy


def _fall(
    v_imp: np.ndarray, depth_m: Any, size: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any, np.ndarray]:
    """The fall from the landing plane's crossing at v_imp [m/s] (n, 3) to a floor depth_m
    [m] below it, the centre stopping r (the smallest half-extent of `size` (n, 3) [m]; 0
    without sizes) above the floor: (v_h (n, 2), |v_h|, |v_z| at the plane, r, |v_z| at the
    floor √(v_z² + 2 g (depth_m − r)₊)), shared by the drop and roll laws."""
    vh = v_imp[:, :2]
    speed = np.linalg.norm(vh, axis=1)
    vz = np.abs(v_imp[:, 2])
    r = 0.0 if size is None else np.min(np.asarray(size, float), axis=1) / 2
    fall = np.maximum(np.asarray(depth_m, float) - r, 0.0)
    return vh, speed, vz, r, np.sqrt(vz**2 + 2 * G * fall)


def roll_move(
    v_imp: np.ndarray, inv_mu_r: Any, depth_m: Any, size: np.ndarray | None
) -> np.ndarray:
    """The roll law's move (n, 2) [m] (`cell.model.effects_bounce.BounceRoll`) from the
    landing plane's crossing at v_imp [m/s] (n, 3): the free fall over depth_m − r (r the
    smallest half-extent of `size` (n, 3) [m]; 0 without sizes) at v_h, the impact at
    v_z' = √(v_z² + 2 g (depth_m − r)) bringing the ball to rolling at
    5/7 v_h − 5 μ_r v_z' / (7 r), the roll v'² · 7 r / (10 μ_r g); inv_mu_r = 1/μ_r [1/m]."""
    vh, speed, vz, r, vz_floor = _fall(v_imp, depth_m, size)
    inv = np.asarray(inv_mu_r, float)
    rr = np.maximum(r, 1e-6)  # a ball of no size (no sizes given) brakes at once
    brake = 5.0 * vz_floor / (7.0 * rr * np.maximum(inv, 1e-12))
    rolling = np.maximum(5.0 / 7.0 * speed - brake, 0.0)
    along = speed * (vz_floor - vz) / G + 7.0 * rr * rolling**2 * inv / (10.0 * G)
    return vh * (along / np.maximum(speed, 1e-12))[:, None]


def drop_slide(
    v_imp: np.ndarray,
    inv_mu: Any,
    depth_m: Any,
    size: np.ndarray | None,
    k_drag: Any = None,
) -> np.ndarray:
    """The drop law's move (n, 2) [m] (`cell.model.effects_bounce.BounceDrop`) from the
    landing plane's crossing at v_imp [m/s] (n, 3): the free fall over depth_m − r (r the
    smallest half-extent of `size` (n, 3) [m]; 0 without sizes) at v_h, the impact at
    v_z' = √(v_z² + 2 g (depth_m − r)) taking μ v_z' off v_h, the slide (v_h')² / (2 μ g),
    or, with the air's drag on the sliding object (k_drag [1/m] per throw or one value:
    the deceleration μ g + k v²), ln(1 + k v_h'² / (μ g)) / (2 k)."""
    vh, speed, vz, _, vz_floor = _fall(v_imp, depth_m, size)
    inv_mu = np.asarray(inv_mu, float)
    left = np.maximum(speed - vz_floor / np.maximum(inv_mu, 1e-12), 0.0)
    slide = left**2 * inv_mu / (2 * G)
    if k_drag is not None:
        slide = slide * _log1p_ratio(2.0 * np.asarray(k_drag, float) * slide)
    along = speed * (vz_floor - vz) / G + slide
    return vh * (along / np.maximum(speed, 1e-12))[:, None]


def _log1p_ratio(z: np.ndarray) -> np.ndarray:
    """ln(1 + z) / z (1 at z = 0, its series below 1e-6): a slide s without drag becomes
    s · ln(1 + 2 k s) / (2 k s) with it."""
    z = np.asarray(z, float)
    small = np.abs(z) < 1e-6
    safe = np.where(small, 1.0, z)
    return np.where(small, 1.0 - z / 2.0, np.log1p(safe) / safe)


def _slide_drag(batch: ThrowBatch, effs: Sequence[Effect]) -> np.ndarray | None:
    """The air's drag constant k [1/m] (n,) on each object as it slides after a drop law's
    impact: the flight's (½ ρ C_d A / m, times a drag scale's factor where there is one);
    None where no drop law is among the effects (nothing else reads it)."""
    if _find(effs, BounceDrop) is None:
        return None
    ds = _find(effs, DragScale)
    k = drag_constant(batch.shape, batch.mass, batch.size)
    return k * np.asarray(ds.factor, float) if ds is not None else k


def _given_launch(
    launch: tuple[np.ndarray, np.ndarray, np.ndarray] | None, n: int
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """(which of n throws have an observed launch state, (positions, velocities, times))
    of `predict_with_effects`' `launch` (NaN where none is given)."""
    if launch is None:
        return np.zeros(n, bool), (
            np.full((n, 3), np.nan),
            np.full((n, 3), np.nan),
            np.full(n, np.nan),
        )
    lp, lv, lt = (np.asarray(a, float) for a in launch)
    given = np.isfinite(lt) & np.all(np.isfinite(lp), axis=1) & np.all(np.isfinite(lv), axis=1)
    return given, (lp, lv, lt)


def _launched(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    modelled: tuple[np.ndarray, np.ndarray, np.ndarray],
    given: np.ndarray,
    observed: tuple[np.ndarray, ...],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions [m], velocities [m/s], times [s] since the release command) at the
    launch: the `observed` ones where `given`, else the push under the launch effects
    (`modelled`: push [N], pushed mass [kg], throw axis) from `launch_state`."""
    n, mod = len(batch), ~given
    push, push_mass, axis = modelled
    p1, v1, t1 = np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full(n, ee.dt)
    if mod.any():
        sub = batch.take(mod)
        p1[mod], v1[mod] = launch_state(
            sub, ee, push=push[mod], push_mass=push_mass[mod], axis=axis[mod]
        )
    if given.any():
        p1[given], v1[given], t1[given] = (o[given] for o in observed)
    return p1, v1, t1


def predict_with_effects(
    batch: ThrowBatch,
    ee: EndEffectorParams,
    effects: Sequence[Effect] | Mapping[str, Mapping[str, Any]] | None = None,
    *,
    rotor_rpm: np.ndarray | None = None,
    launch: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    permutation: np.ndarray | None = None,
    strict: bool = False,
    check_stroke: bool = False,
    step: float = 0.01,
) -> Landing:
    """Observed landing points of a batch with the model plus effects.

    Args:
        batch: the throws.
        ee: end-effector parameters.
        effects: a list of effects, or a parameter file's mapping {name: {param: value}}.
        rotor_rpm: rotor speed per throw [rpm] (downwash); zeros when None.
        launch: observed launch states (position (n, 3) [m], velocity (n, 3) [m/s],
            time since the release command (n,) [s]) that replace the modelled push
            where finite (throws from another launcher, diagnosed from tracks).
        permutation: the permutation control: effects read the logged quantity they
            hang on in this order.
        strict: raise NoLanding when a throw never reaches its plane.
        check_stroke: reject strokes outside the end-effector's range.
        step: RK4 step of the 3-D flight integrator [s] (flight effects only).

    Returns:
        The landings as observed (with a measurement effect, on the observed scale).

    Raises:
        InvalidParameter: an unknown effect or bad parameter; a stroke out of range
            with check_stroke.
        NoLanding: with strict, when a throw never reaches its plane.
    """
    if effects is None:
        effs: list[Effect] = []
    elif isinstance(effects, Mapping):
        effs = effects_from_mapping(effects)
    else:
        effs = list(effects)
    effs = [e.per_throw(batch, permutation) for e in effs]
    n = len(batch)
    rpm = np.zeros(n) if rotor_rpm is None else np.asarray(rotor_rpm, float)
    ts = _find(effs, TrackingScale)
    s = ts.scale_factor if ts else 1.0
    if check_stroke:
        batch.check_stroke(ee)
    push, push_mass, axis = launch_overrides(batch, ee, effs, permutation=permutation)
    accel = _flight_accel(batch, effs, rpm, permutation)
    given, (lp, lv, lt) = _given_launch(launch, n)
    if accel is None and not given.any():
        land = predict_landing(
            batch, ee, strict=False, check_stroke=False, push=push, push_mass=push_mass, axis=axis
        )
        xyz_t = np.c_[land.x, land.y, batch.land_z]
        v_imp, t_fl, landed = land.impact_velocity, land.t_flight, land.landed
        p1, v1 = land.launch_position, land.launch_velocity
    else:
        p1, v1, t1 = _launched(batch, ee, (push, push_mass, axis), given, (lp / s, lv / s, lt))
        k = drag_constant(batch.shape, batch.mass, batch.size)
        res = fly(p1, v1, k, batch.land_z, accel=accel, t0=t1, step=step)
        xyz_t, v_imp, t_fl, landed = res.position, res.velocity, res.t, res.landed
    xy = (
        _after_landing(
            xyz_t[:, :2].copy(),
            v_imp,
            effs,
            batch.size,
            batch.shape,
            batch.land_z,
            _slide_drag(batch, effs),
        )
        * s
    )
    if strict and not np.all(landed):
        raise no_landing_error(np.flatnonzero(~landed), batch)
    return Landing(
        x=xy[:, 0],
        y=xy[:, 1],
        t_flight=t_fl,
        launch_position=p1,
        launch_velocity=v1,
        landed=landed,
        impact_velocity=v_imp,
    )
