"""A world to check the diagnosis against: campaigns with a withheld effect.

Each campaign is a thesis-sized set of throws (objects of the catalogue's
identification and grasping sets, strokes over the whole range, arm, mobile
and drone platforms, varied poses and landing planes, every configuration
thrown twice) whose landings come from the nominal model plus one injected
effect at a random size, plus Gaussian scatter. The effect's size is drawn
as the ratio of the configured model's RMSE to the scatter, so that every
campaign has a gap the diagnosis can see. Besides the vocabulary's effects
the world knows `none` (scatter only) and `unknown`: a landing floor tilted
about the world origin, which none of the named effects reproduces.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.gap.world_other import draw_release_start
from cell.kinds import PLATFORMS
from cell.log.records import object_columns
from cell.log.table import ThrowTable
from cell.model.effects import (
    BandDamping,
    BandMass,
    Bounce,
    Downwash,
    DragScale,
    Effect,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    TrackingScale,
    Wind,
)
from cell.model.effects_apply import predict_with_effects
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.model.throw import ThrowBatch, throw_axis

__all__ = ["Campaign", "draw_campaign", "TRUTHS", "throw_records"]

WORLD_STEP = 0.004  # [s] the world's integrator step (finer than the diagnosis')
TILT = "floor_tilt"  # the out-of-vocabulary effect


@dataclass(frozen=True)
class Campaign:
    """A drawn campaign.

    Attributes:
        table: the throw log the diagnosis sees.
        truth: the injected effect's name (`none`, or `unknown` for the tilt).
        params: the injected effect's parameters.
        noise_m: the 2-D RMS of the injected scatter [m].
        baseline_m: the configured model's RMSE on the campaign [m].
    """

    table: ThrowTable
    truth: str
    params: dict[str, float]
    noise_m: float
    baseline_m: float


def _make(name: str, rng: np.random.Generator) -> tuple[Callable[[float], list[Effect]], float]:
    """A family of the effect parametrised by its size in [0, hi], and hi."""
    sign = float(rng.choice([-1.0, 1.0]))
    if name == "band_mass":
        return (lambda m: [BandMass(m)]), 0.15
    if name == "band_damping":
        return (lambda m: [BandDamping(m)]), 7.0
    if name == "shape_stretch":
        return (lambda m: [ShapeStretch(m)]), 0.95
    if name == "stroke_offset":
        return (lambda m: [StrokeOffset(sign * m)]), 0.025
    if name == "release_pitch":
        return (lambda m: [ReleasePitch(sign * m)]), 0.3
    if name == "downwash":
        r, p = rng.uniform(0.3, 0.8), rng.uniform(0.8, 2.0)
        return (lambda m: [Downwash(m, r, p)]), 35.0
    if name == "wind":
        th = rng.uniform(-np.pi, np.pi)
        vz = rng.uniform(-0.2, 0.2)
        return (lambda m: [Wind(m * np.cos(th), m * np.sin(th), m * vz)]), 2.5
    if name == "spin":
        lm = rng.uniform(0.2, 0.5)
        return (lambda m: [Spin(sign * m, lm)]), 600.0
    if name == "drag_scale":
        return (lambda m: [DragScale(1.0 + sign * m)]), 0.7
    if name == "tracking_scale":
        return (lambda m: [TrackingScale(1.0 + sign * m)]), 0.3
    if name == "bounce":
        return (lambda m: [Bounce(m)]), 1.5
    raise KeyError(name)


TRUTHS = (
    "band_mass",
    "band_damping",
    "shape_stretch",
    "stroke_offset",
    "release_pitch",
    "downwash",
    "wind",
    "spin",
    "drag_scale",
    "tracking_scale",
    "bounce",
    "none",
    "unknown",
)


def throw_records(
    n: int, rng: np.random.Generator, *, repeats: int = 2, objects: tuple[str, ...] = ()
) -> list[dict]:
    """n throws (configurations thrown `repeats` times each), as log records without
    landings; of the catalogue's `objects` by name (empty: the thesis' and figure 3.3's)."""
    cat = [
        e
        for name, e in catalogue().items()
        if (name in objects if objects else e.set in ("thesis14", "fig33"))
    ]
    strokes = np.linspace(DEFAULT_EE.stroke_min, DEFAULT_EE.stroke_max, 9)
    elevations = np.radians([5.0, 20.0, 35.0, 50.0])
    recs: list[dict] = []
    for _ in range(-(-n // repeats)):
        obj = cat[int(rng.integers(len(cat)))].params
        plat = str(rng.choice(list(PLATFORMS), p=[0.5, 0.2, 0.3]))
        pos, vb, rpm = draw_release_start(plat, rng)
        rec = {
            **object_columns(obj),
            "stroke_m": float(rng.choice(strokes)),
            "x_m": float(pos[0]),
            "y_m": float(pos[1]),
            "z_m": float(pos[2]),
            "elevation_rad": float(rng.choice(elevations)),
            "azimuth_rad": float(rng.uniform(-np.pi, np.pi)),
            "roll_rad": 0.0,
            "vx_mps": float(vb[0]),
            "vy_mps": float(vb[1]),
            "vz_mps": float(vb[2]),
            "platform": plat,
            "rotor_rpm": rpm,
            "land_z_m": float(rng.choice([0.0, 0.25], p=[0.75, 0.25])),
        }
        recs += [dict(rec) for _ in range(repeats)]
    recs = recs[:n]
    order = rng.permutation(len(recs))
    out = []
    for i, j in enumerate(order):
        r = dict(recs[j])
        r["throw_id"] = f"t{i:04d}"
        r["session"] = "check"
        out.append(r)
    return out


def _tilted(
    batch: ThrowBatch, ee: EndEffectorParams, slope: float, th: float, rpm: np.ndarray
) -> np.ndarray:
    """Landings on a floor tilted by `slope` [-] towards azimuth th, about the origin."""
    d = np.array([np.cos(th), np.sin(th)])
    lz0 = batch.land_z.copy()
    xy = predict_with_effects(batch, ee, [], rotor_rpm=rpm).xy
    for _ in range(6):
        lz = lz0 + slope * (xy @ d)
        b = ThrowBatch(**{**batch.__dict__, "land_z": lz})
        xy = predict_with_effects(b, ee, [], rotor_rpm=rpm, step=WORLD_STEP).xy
    return xy


def other_launch(
    batch: Any, recs: list[dict[str, Any]], rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Another launcher's launch of the throws (`throw_records` `recs`, as `batch`):
    (positions [m, W], velocities [m/s, W], times [s]): from the release point along the
    throw axis at a speed drawn in 3-7 m/s (one draw from `rng` seeds them), the same for
    each repeat of a configuration, 0.02 s after the command."""
    n = len(recs)
    u = throw_axis(batch.elevation, batch.azimuth)
    speed = 3.0 + 4.0 * np.random.default_rng(int(rng.integers(2**31))).random(n)
    key: dict[tuple, float] = {}
    for i, r in enumerate(recs):
        speed[i] = key.setdefault((r["object_id"], r["x_m"], r["azimuth_rad"]), speed[i])
    return batch.position.copy(), u * speed[:, None] + batch.base_velocity, np.full(n, 0.02)


def _effect_size(deviation_of: Callable[[float], float], hi: float, target: float) -> float:
    """The effect's size in [0, hi] whose landings deviate `target` [m] from the nominal
    model's (`deviation_of(size)` [m], growing with the size), by 18 bisections; hi where
    even hi deviates no more."""
    lo_m, hi_m = 0.0, hi
    if deviation_of(hi) > target:
        for _ in range(18):
            mid = 0.5 * (lo_m + hi_m)
            if deviation_of(mid) > target:
                hi_m = mid
            else:
                lo_m = mid
    return hi_m


def draw_campaign(
    truth: str,
    rng: np.random.Generator,
    *,
    n: int = 865,
    ratio: tuple[float, float] = (2.5, 5.0),
    noise_m: tuple[float, float] = (0.01, 0.025),
    ee: EndEffectorParams = DEFAULT_EE,
    repeats: int = 2,
) -> Campaign:
    """Draw one campaign with `truth` injected.

    Args:
        truth: an effect name of the vocabulary, `none` or `unknown`.
        rng: the random generator.
        n: number of throws.
        ratio: range of the baseline-to-scatter RMSE ratio the effect's size is drawn for.
        noise_m: range of the per-axis scatter [m].
        ee: the end-effector of the world (and of the configured model).
        repeats: how many times each configuration is thrown.

    Returns:
        The campaign.
    """
    recs = throw_records(n, rng, repeats=repeats)
    stub = [{**r, "landed_x_m": 0.0, "landed_y_m": 0.0} for r in recs]
    table = ThrowTable.from_records(stub)
    batch = table.to_batch()
    rpm = table.num("rotor_rpm")
    nominal = predict_with_effects(batch, ee, [], rotor_rpm=rpm).xy
    sigma = rng.uniform(*noise_m)
    noise = rng.normal(0.0, sigma, (len(recs), 2))
    target = sigma * np.sqrt(2) * np.sqrt(max(rng.uniform(*ratio) ** 2 - 1.0, 0.0))

    def deviation(xy: np.ndarray) -> float:
        d = np.where(np.isfinite(xy), xy - nominal, 3.0)
        return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))

    params: dict[str, float] = {}
    if truth == "none":
        xy = nominal
    else:
        if truth == "unknown":
            th = rng.uniform(-np.pi, np.pi)

            def world(m: float) -> np.ndarray:
                return _tilted(batch, ee, m, th, rpm)

            hi = 0.3
        else:
            family, hi = _make(truth, rng)

            def world(m: float) -> np.ndarray:
                return predict_with_effects(batch, ee, family(m), rotor_rpm=rpm, step=WORLD_STEP).xy

        size = _effect_size(lambda m: deviation(world(m)), hi, target)
        xy = world(size)
        if truth == "unknown":
            params = {"slope": size, "azimuth_rad": float(th)}
        else:
            params = family(size)[0].params()
    ok = np.all(np.isfinite(xy), axis=1)
    obs = xy + noise
    rows = []
    for i, r in enumerate(recs):
        if ok[i]:
            rows.append({**r, "landed_x_m": float(obs[i, 0]), "landed_y_m": float(obs[i, 1])})
    tab = ThrowTable.from_records(rows)
    base = deviation_to(tab, ee)
    return Campaign(
        table=tab,
        truth=truth,
        params=params,
        noise_m=float(np.sqrt(np.mean(np.sum(noise[ok] ** 2, axis=1)))),
        baseline_m=base,
    )


def deviation_to(table: ThrowTable, ee: EndEffectorParams) -> float:
    """RMSE [m] of the configured (nominal) model on a log."""
    xy = predict_with_effects(table.to_batch(), ee, [], rotor_rpm=table.num("rotor_rpm")).xy
    d = np.where(np.isfinite(xy), table.landed - xy, 3.0)
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))
