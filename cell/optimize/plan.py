"""Throw planning: a target in, the release state σ* out (thesis §4.2).

`plan_throw` tries the fast inverse (`fast.ReachTable`) for a fixed base and
falls back to the full NLP (`nlp.solve_nlp`). Whatever produced σ*, the plan
is judged by the NumPy model: `cell.model.predict_landing` flies σ*, a short
Newton polish on the model itself removes what is left of the miss, and a
plan whose predicted miss stays above MISS_TOL is not returned; the target is
then unreachable and the error names the reachable range.

Secondary objective (which σ among the many that hit):
    least stored band energy (equivalently the longest stroke, the largest
    margin from the most-stretched stroke limit), then the release point
    nearest the reference point (the current grip centre when given, else the
    nominal release point of the bounds). The fast path applies it within its
    pose family (release point fixed, candidate elevations of the bounds); the
    NLP over the whole bounds box (see `nlp`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import asdict, dataclass, replace
from typing import Literal

import numpy as np

from cell.errors import InvalidParameter
from cell.model.band import band_state
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.model.throw import ThrowBatch
from cell.optimize.bounds import DEFAULT_BOUNDS, SIGMA_COLUMNS, ThrowBounds
from cell.optimize.fast import reach_table
from cell.optimize.nlp import solve_nlp
from cell.optimize.reach import unreachable_error
from cell.optimize.verify import POLISH_TOL, fly, polish, sigma_batch

__all__ = ["ThrowPlan", "plan_throw", "plan_facing", "rotate_plan", "MISS_TOL"]

log = logging.getLogger(__name__)

MISS_TOL = 1e-3  # [m] largest predicted miss of a returned plan
_FAST_ITERS = 4  # secant steps of the fast path's polish

Method = Literal["auto", "fast", "nlp"]


@dataclass(frozen=True)
class ThrowPlan:
    """A planned throw: σ* in docs/throw_log.md column names, and its predicted landing.

    Attributes:
        x_m, y_m, z_m: release grip centre [m, W].
        vx_mps, vy_mps, vz_mps: base velocity at release [m/s, W].
        roll_rad, elevation_rad, azimuth_rad: throw axis and roll [rad].
        stroke_m: stroke L_s [m].
        target_x_m, target_y_m: the goal on the landing plane [m, W].
        land_z_m: landing-plane height (the goal's z) [m].
        pred_x_m, pred_y_m: landing predicted by `predict_landing` [m, W].
        miss_m: distance from the predicted landing to the goal [m].
        energy_j: stored band energy at release, both halves [J].
        t_flight_s: flight time from the start of the push [s].
        method: "fast" or "nlp", what produced σ*.
        object_id: catalogue id of the object, or its shape for an ad-hoc one.
    """

    x_m: float
    y_m: float
    z_m: float
    vx_mps: float
    vy_mps: float
    vz_mps: float
    roll_rad: float
    elevation_rad: float
    azimuth_rad: float
    stroke_m: float
    target_x_m: float
    target_y_m: float
    land_z_m: float
    pred_x_m: float
    pred_y_m: float
    miss_m: float
    energy_j: float
    t_flight_s: float
    method: str
    object_id: str

    @property
    def sigma(self) -> np.ndarray:
        """σ*, shape (10,), SIGMA_COLUMNS order."""
        return np.array([getattr(self, c) for c in SIGMA_COLUMNS])

    def as_dict(self) -> dict[str, float | str]:
        """Every field, named as above (σ with the docs/throw_log.md column names)."""
        return asdict(self)

    def to_batch(self, obj: ObjectParams) -> ThrowBatch:
        """The planned throw as a one-throw batch for `predict_landing`."""
        return sigma_batch(obj, self.sigma, self.land_z_m)


class _NoPlan(Exception):
    """Internal: a method found no plan within MISS_TOL (best miss in .miss [m])."""

    def __init__(self, reason: str, miss: float = math.inf) -> None:
        super().__init__(reason)
        self.miss = miss


def _wrap_azimuth(a: float, bounds: ThrowBounds) -> float | None:
    for cand in (a, a + 2 * math.pi, a - 2 * math.pi):
        if bounds.azimuth_min <= cand <= bounds.azimuth_max:
            return cand
    return None


def _release_point(target: np.ndarray, bounds: ThrowBounds, current: np.ndarray | None):
    return bounds.clip_position(current) if current is not None else bounds.nominal_release(target)


def _fast_sigma(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    p0: np.ndarray,
) -> tuple[np.ndarray, float]:
    """σ from the reach table (not yet verified) and dR/dL_s [m/m]."""
    dx, dy = float(target[0] - p0[0]), float(target[1] - p0[1])
    dist = math.hypot(dx, dy)
    az = _wrap_azimuth(math.atan2(dy, dx), bounds)
    if az is None:
        raise _NoPlan("the target's azimuth from the release point is outside the bounds")
    table = reach_table(obj, ee, tuple(bounds.elevations()), bounds.stroke_range(ee))
    sol = table.invert(dist, float(p0[2] - target[2]))
    if sol is None:
        raise _NoPlan("no candidate elevation of the fast path reaches the target")
    sigma = np.array([*p0, 0.0, 0.0, 0.0, bounds.roll, sol.elevation, az, sol.stroke])
    return sigma, sol.slope


def _make_plan(
    obj: ObjectParams,
    sigma: np.ndarray,
    target: np.ndarray,
    xy: np.ndarray,
    miss: float,
    t_flight: float,
    ee: EndEffectorParams,
    method: str,
) -> ThrowPlan:
    energy = float(band_state(sigma[9], obj.width, ee).energy)
    values = {c: float(v) for c, v in zip(SIGMA_COLUMNS, sigma, strict=True)}
    return ThrowPlan(
        **values,
        target_x_m=float(target[0]),
        target_y_m=float(target[1]),
        land_z_m=float(target[2]),
        pred_x_m=float(xy[0]),
        pred_y_m=float(xy[1]),
        miss_m=miss,
        energy_j=energy,
        t_flight_s=t_flight,
        method=method,
        object_id=obj.name or obj.shape,
    )


def _plan_fast(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    current: np.ndarray | None,
) -> ThrowPlan:
    p0 = _release_point(target, bounds, current)
    sigma, slope = _fast_sigma(obj, target, ee, bounds, p0)
    lower, upper = bounds.vectors(ee)
    xy, miss, tf = fly(obj, sigma, target, ee)
    for _ in range(_FAST_ITERS):
        if miss[0] <= POLISH_TOL or not np.isfinite(miss[0]):
            break
        # the flight stays in the azimuth's vertical plane: only the reach is off
        along = (xy[0, 0] - p0[0]) * math.cos(sigma[8]) + (xy[0, 1] - p0[1]) * math.sin(sigma[8])
        dist = math.hypot(target[0] - p0[0], target[1] - p0[1])
        sigma[9] = float(np.clip(sigma[9] - (along - dist) / slope, lower[9], upper[9]))
        xy, miss, tf = fly(obj, sigma, target, ee)
    if not miss[0] <= MISS_TOL:
        raise _NoPlan("the fast path's polish did not converge", float(miss[0]))
    return _make_plan(obj, sigma, target, xy[0], float(miss[0]), float(tf[0]), ee, "fast")


def _guesses(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    reference: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> list[np.ndarray]:
    out = []
    if not lower[3:6].any() and not upper[3:6].any():  # fixed base: the table applies
        try:
            out.append(_fast_sigma(obj, target, ee, bounds, reference)[0])
        except _NoPlan:
            pass
    wrapped = _wrap_azimuth(math.atan2(target[1] - reference[1], target[0] - reference[0]), bounds)
    az = float(np.clip(0.0 if wrapped is None else wrapped, lower[8], upper[8]))
    v_mid = 0.5 * (lower[3:6] + upper[3:6])
    for frac_e, frac_s in ((0.6, 0.5), (0.3, 0.2), (0.9, 0.8)):
        e = lower[7] + frac_e * (upper[7] - lower[7])
        s = lower[9] + frac_s * (upper[9] - lower[9])
        out.append(np.array([*reference, *v_mid, bounds.roll, e, az, s]))
    return out


def _plan_nlp(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    bounds: ThrowBounds,
    current: np.ndarray | None,
    base_velocity: np.ndarray | None,
) -> ThrowPlan:
    lower, upper = bounds.vectors(ee)
    if base_velocity is not None:
        lower[3:6] = upper[3:6] = base_velocity
    reference = _release_point(target, bounds, current)
    best = math.inf
    for guess in _guesses(obj, target, ee, bounds, reference, lower, upper):
        _, _, tf = fly(obj, guess, target, ee)
        t_guess = float(tf[0]) - ee.dt if np.isfinite(tf[0]) else 0.8
        res = solve_nlp(obj, target, ee, lower, upper, guess, t_guess, reference)
        sigma, xy, miss, t_flight = polish(obj, res.sigma, target, ee, lower, upper)
        log.debug("NLP %s: predicted miss %.2e m", res.status, miss)
        if miss <= MISS_TOL:
            return _make_plan(obj, sigma, target, xy, miss, t_flight, ee, "nlp")
        best = min(best, miss)
    raise _NoPlan("the NLP found no plan", best)


def plan_throw(
    obj: ObjectParams,
    target: tuple[float, float, float] | np.ndarray,
    ee: EndEffectorParams = DEFAULT_EE,
    bounds: ThrowBounds = DEFAULT_BOUNDS,
    *,
    current: tuple[float, float, float] | np.ndarray | None = None,
    base_velocity: tuple[float, float, float] | np.ndarray | None = None,
    method: Method = "auto",
) -> ThrowPlan:
    """Plan the release state σ* that lands an object on a target.

    Args:
        obj: the object.
        target: goal (x, y, z) [m, W]; z is the landing plane's height (a bin's rim).
        ee: end-effector parameters (identified ones for real throws).
        bounds: the bounds of σ; the default is an arm at the world origin.
        current: the current grip centre [m, W]: the fast path releases there
            (moved into the bounds' box) and the NLP's pose term pulls toward it.
        base_velocity: a known base velocity at release [m/s, W]; None leaves it
            free within the bounds (zero for a fixed base).
        method: "fast" (the reach table only), "nlp" (the NLP only), or "auto"
            (fast, then the NLP as the fallback).

    Returns:
        The plan; its predicted miss (by `predict_landing`) is at most MISS_TOL.

    Raises:
        UnreachableTarget: no σ within the bounds lands within MISS_TOL of the
            target; the message gives the reachable range.
        InvalidParameter: a malformed target, current pose, velocity or method.
    """
    tgt = np.asarray(target, float).reshape(-1)
    if tgt.shape != (3,) or not np.all(np.isfinite(tgt)):
        raise InvalidParameter(f"target {target!r} must be three finite numbers (x, y, z) [m]")
    cur = None
    if current is not None:
        cur = np.asarray(current, float).reshape(-1)
        if cur.shape != (3,) or not np.all(np.isfinite(cur)):
            raise InvalidParameter(f"current {current!r} must be three finite numbers [m]")
    vb = None
    if base_velocity is not None:
        vb = np.asarray(base_velocity, float).reshape(-1)
        if vb.shape != (3,) or not np.all(np.isfinite(vb)):
            raise InvalidParameter(f"base_velocity {base_velocity!r} must be three numbers [m/s]")
    if method not in ("auto", "fast", "nlp"):
        raise InvalidParameter(f"method {method!r} must be one of auto, fast, nlp")
    fast_ok = bounds.fixed_base if vb is None else not vb.any()
    notes = []
    best = math.inf
    if method in ("auto", "fast"):
        if not fast_ok:
            if method == "fast":
                raise InvalidParameter("the fast path needs a fixed base (zero base velocity)")
        else:
            try:
                return _plan_fast(obj, tgt, ee, bounds, cur)
            except _NoPlan as exc:
                notes.append(f"fast path: {exc}")
                best = min(best, exc.miss)
    if method in ("auto", "nlp"):
        try:
            return _plan_nlp(obj, tgt, ee, bounds, cur, vb)
        except _NoPlan as exc:
            notes.append(f"NLP over the release box: {exc}")
            best = min(best, exc.miss)
    detail = "; ".join(notes)
    if math.isfinite(best):
        detail += f" (best predicted miss {best:.3f} m)"
    raise unreachable_error(obj, tgt, ee, bounds, _release_point(tgt, bounds, cur), detail + ".")


FACING_SECTOR_RAD = math.radians(45.0)  # targets within ±45° of +x use the bounds as given


def rotate_plan(plan: ThrowPlan, angle_rad: float) -> ThrowPlan:
    """The plan turned by `angle_rad` about the vertical axis through the world origin
    (the model is invariant under it: gravity is vertical, the air still)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)

    def rot(x: float, y: float) -> tuple[float, float]:
        return c * x - s * y, s * x + c * y

    x, y = rot(plan.x_m, plan.y_m)
    vx, vy = rot(plan.vx_mps, plan.vy_mps)
    tx, ty = rot(plan.target_x_m, plan.target_y_m)
    px, py = rot(plan.pred_x_m, plan.pred_y_m)
    az = math.atan2(math.sin(plan.azimuth_rad + angle_rad), math.cos(plan.azimuth_rad + angle_rad))
    return replace(
        plan,
        x_m=x,
        y_m=y,
        vx_mps=vx,
        vy_mps=vy,
        azimuth_rad=az,
        target_x_m=tx,
        target_y_m=ty,
        pred_x_m=px,
        pred_y_m=py,
    )


def plan_facing(
    obj: ObjectParams,
    target: tuple[float, float, float] | np.ndarray,
    ee: EndEffectorParams = DEFAULT_EE,
    bounds: ThrowBounds = DEFAULT_BOUNDS,
) -> ThrowPlan:
    """`plan_throw` for an arm that turns to face its target.

    The bounds' release box lies in front of the base (+x). A target outside
    ±FACING_SECTOR_RAD of +x (beside or behind the arm) is planned in the frame
    turned toward it, and the plan is turned back: the arm releases on the side of
    the bin, as it would after turning its first joint, instead of throwing over
    its shoulder from the front box.

    With `bounds.facing_rad` set, the frame is turned to that azimuth whatever the
    target's, and the release point is `release_radius` from the base along it at
    `release_height` (the box's point nearest it); the throw axis turns from there
    to the target. An arm that turns back to a pick station after each throw faces
    part-way toward it (`Orchestrator._facing_toward_station`).
    """
    g = np.asarray(target, float)
    phi = math.atan2(g[1], g[0])
    current = None
    if bounds.facing_rad is not None:
        phi = bounds.facing_rad
        current = (bounds.release_radius, 0.0, bounds.release_height)
        bounds = replace(bounds, facing_rad=None)
    elif abs(phi) <= FACING_SECTOR_RAD:
        return plan_throw(obj, g, ee, bounds)
    c, s = math.cos(-phi), math.sin(-phi)
    local = (c * g[0] - s * g[1], s * g[0] + c * g[1], g[2])
    return rotate_plan(plan_throw(obj, local, ee, bounds, current=current), phi)
