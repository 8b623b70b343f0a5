"""Synthetic throw campaigns: what tests and benchmarks throw when no robot is at hand.

A `World` is the truth the campaign is drawn from: the true end-effector
parameters, each object's true η_o (which the log does not show: the log
carries the catalogue's, i.e. CAD, mass and extents, as a real log would), a
landing-noise model, and an optional `predict` hook `(batch, ee) -> Landing`
through which other parts of the cell inject effects the nominal model lacks.

Noise model (`NoiseModel`). The thesis (§5.4) reports the repeatability of a
5 cm cube thrown 20 times at one stroke from the arm: reach 1.345 ± 0.1086 m,
i.e. a spread of 8.07 % of the reach. Much of such a spread comes from the
release (stroke read-out, band and grip variation), which scales with the launch
speed and so with the reach; a fixed σ of 0.11 m would bury short throws and
flatter long ones. So the landing noise is Gaussian, in the horizontal frame of
the throw, with

    σ_along  = sqrt(floor² + (0.0807 · reach)²)   along the throw direction,
    σ_across = sqrt(floor² + (0.0400 · reach)²)   across it,

with reach the horizontal distance from release to landing and floor = 5 mm
(what a calibrated camera measures a landing point to). At the thesis' 1.345 m
this gives σ_along = 0.1087 m. The thesis reports no lateral spread; half the
along-reach spread is an assumption (a throw's direction is set by the arm,
which repeats far better than the band's push).

Default world (`default_world`). The reference parameters of MODEL.md,
perturbed in a fixed way (`EE_PERTURBATION`, `MASS_FACTORS`, `SIZE_FACTORS`):
band law Ke3 × 1.25, Ke2 × 0.8, Ke1 × 1.12, C = +0.4 N; geometry r_r × 1.1,
l1 × 0.93, phi × 1.05; push duration dt × 0.92. Object k of the sorted catalogue
ids gets mass × MASS_FACTORS[k mod 7] and grip width size_x × SIZE_FACTORS[k mod 5]
(other extents unchanged).

Default campaign (`Campaign`): 865 throws of the 14 `thesis14` objects (61 or 62
each), fixed base (platform arm), strokes uniform over the whole range
[0.03, 0.11] m, release 0.45–0.85 m high within ±0.1 m of the origin,
elevation 15–50°, azimuth ±30°, roll ±0.3 rad, in 5 sessions. A throw whose
true landing lies beyond 4 m of the release (outside the lab floor a camera
watches) is drawn again.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.errors import InvalidInput, InvalidParameter
from cell.log.records import object_columns
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.model.throw import Landing, ThrowBatch, predict_landing
from cell.params import ModelParams

__all__ = [
    "EE_PERTURBATION",
    "MASS_FACTORS",
    "SIZE_FACTORS",
    "Campaign",
    "NoiseModel",
    "PredictHook",
    "World",
    "default_world",
    "draw_campaign",
    "thesis14_ids",
    "world_from_params",
]

PredictHook = Callable[[ThrowBatch, EndEffectorParams], Landing]

EE_PERTURBATION: dict[str, float] = {
    "Ke3": 1.25,
    "Ke2": 0.8,
    "Ke1": 1.12,
    "r_r": 1.1,
    "l1": 0.93,
    "phi": 1.05,
    "dt": 0.92,
}
EE_C_TRUE = 0.4  # [N] band force offset of the default world (reference: 0)
MASS_FACTORS = (1.08, 0.93, 1.12, 0.95, 1.05, 0.90, 1.10)
SIZE_FACTORS = (1.00, 1.03, 0.97, 1.02, 0.98)

# Thesis §5.4: 5 cm cube, 20 throws at one stroke, reach 1.345 ± 0.1086 m.
THESIS_REACH_M = 1.345
THESIS_SPREAD_M = 0.1086


@dataclass(frozen=True)
class NoiseModel:
    """Gaussian landing noise in the throw's horizontal frame (see the module docstring).

    Attributes:
        along_rel: σ along the throw direction per metre of reach [-].
        across_rel: σ across the throw direction per metre of reach [-].
        floor_m: reach-independent σ of the landing measurement [m].
    """

    along_rel: float = THESIS_SPREAD_M / THESIS_REACH_M
    across_rel: float = 0.04
    floor_m: float = 0.005

    def __post_init__(self) -> None:
        for name in ("along_rel", "across_rel", "floor_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InvalidParameter(f"noise {name}={v} must be a finite number ≥ 0")

    def sigma(self, reach_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(σ_along, σ_across) [m] at these reaches [m]."""
        r = np.asarray(reach_m, float)
        f2 = self.floor_m**2
        return np.sqrt(f2 + (self.along_rel * r) ** 2), np.sqrt(f2 + (self.across_rel * r) ** 2)


@dataclass(frozen=True)
class World:
    """The truth a synthetic campaign is drawn from.

    Attributes:
        ee: true end-effector parameters.
        objects: true η_o by object id (an id not here throws with its catalogue values).
        noise: landing-noise model.
        predict: optional `(batch, ee) -> Landing` replacing the nominal model (the
            batch carries the true η_o); None = `predict_landing`.
    """

    ee: EndEffectorParams = DEFAULT_EE
    objects: dict[str, ObjectParams] = field(default_factory=dict)
    noise: NoiseModel = field(default_factory=NoiseModel)
    predict: PredictHook | None = None

    def landing(self, batch: ThrowBatch) -> Landing:
        """Noise-free landings of a batch that carries the true η_o (not strict)."""
        if self.predict is not None:
            return self.predict(batch, self.ee)
        return predict_landing(batch, self.ee, strict=False, check_stroke=False)

    def true_landing(self, table: ThrowTable) -> np.ndarray:
        """Noise-free landing points [m, W] of a log's throws in this world, shape (n, 2)."""
        return self.landing(table.to_batch(objects=self.objects)).xy

    def as_params(self, note: str = "") -> ModelParams:
        """The world's parameters in the parameter-file form (the noise is not part of it)."""
        return ModelParams(ee=self.ee, objects=dict(self.objects), note=note)


def thesis14_ids() -> list[str]:
    """The ids of the 14 identification objects, sorted."""
    return [k for k, e in catalogue().items() if e.set == "thesis14"]


def default_world(noise: NoiseModel | None = None) -> World:
    """The reference parameters perturbed in the fixed, documented way (module docstring)."""
    ee = replace(
        DEFAULT_EE,
        **{k: getattr(DEFAULT_EE, k) * f for k, f in EE_PERTURBATION.items()},
        C=EE_C_TRUE,
    )
    objects = {}
    for k, (oid, entry) in enumerate(catalogue().items()):
        o = entry.params
        sx = o.size[0] * SIZE_FACTORS[k % len(SIZE_FACTORS)]
        size = (sx, sx, sx) if o.shape in ("cube", "sphere") else (sx, *o.size[1:])
        if o.shape == "cylinder":
            size = (sx, sx, o.size[2])
        objects[oid] = replace(o, mass=o.mass * MASS_FACTORS[k % len(MASS_FACTORS)], size=size)
    return World(ee=ee, objects=objects, noise=noise or NoiseModel())


def world_from_params(params: ModelParams, noise: NoiseModel | None = None) -> World:
    """A world whose truth is a parameter file's (objects it lacks keep catalogue values).

    Raises:
        InvalidInput: the file switches model effects on (inject those through `World.predict`).
    """
    if params.effects:
        raise InvalidInput(
            f"a synthetic world draws from the nominal model; effects {sorted(params.effects)} "
            "need a predict hook (World.predict) instead of a parameter file"
        )
    return World(ee=params.ee, objects=dict(params.objects), noise=noise or NoiseModel())


@dataclass(frozen=True)
class Campaign:
    """What a synthetic campaign draws (SI units, angles in rad).

    Attributes:
        n: number of throws.
        objects: catalogue ids thrown, in equal shares.
        stroke_m: stroke range (None = the true end-effector's whole range).
        height_m: release height range.
        xy_m: release x and y within ± this of the origin.
        elevation_rad, azimuth_rad, roll_rad: ranges of the release orientation.
        max_reach_m: throws landing farther than this from the release are redrawn.
        sessions: number of sessions (consecutive blocks of throws).
        platform: platform column of the log.
        seconds_per_throw: spacing of the logged wall time [s].
    """

    n: int = 865
    objects: tuple[str, ...] = field(default_factory=lambda: tuple(thesis14_ids()))
    stroke_m: tuple[float, float] | None = None
    height_m: tuple[float, float] = (0.45, 0.85)
    xy_m: float = 0.1
    elevation_rad: tuple[float, float] = (math.radians(15), math.radians(50))
    azimuth_rad: tuple[float, float] = (math.radians(-30), math.radians(30))
    roll_rad: tuple[float, float] = (-0.3, 0.3)
    max_reach_m: float = 4.0
    sessions: int = 5
    platform: str = "arm"
    seconds_per_throw: float = 30.0

    def __post_init__(self) -> None:
        if self.n < 1:
            raise InvalidParameter(f"campaign n={self.n} must be ≥ 1")
        if not self.objects:
            raise InvalidParameter("campaign objects: at least one object id is needed")
        if self.sessions < 1:
            raise InvalidParameter(f"campaign sessions={self.sessions} must be ≥ 1")


def _draw_poses(rng: np.random.Generator, c: Campaign, ee: EndEffectorParams, n: int) -> dict:
    lo, hi = c.stroke_m or (ee.stroke_min, ee.stroke_max)
    return {
        "stroke": rng.uniform(lo, hi, n),
        "position": np.c_[
            rng.uniform(-c.xy_m, c.xy_m, n),
            rng.uniform(-c.xy_m, c.xy_m, n),
            rng.uniform(*c.height_m, n),
        ],
        "elevation": rng.uniform(*c.elevation_rad, n),
        "azimuth": rng.uniform(*c.azimuth_rad, n),
        "roll": rng.uniform(*c.roll_rad, n),
    }


def _noise(rng: np.random.Generator, world: World, batch: ThrowBatch, xy: np.ndarray) -> np.ndarray:
    """The observation noise [m] (n, 2) of landings xy [m, W]: along and across each
    throw's reach from its release (along its azimuth where it has none), drawn from
    `rng` with the world's noise at that reach."""
    n = len(batch)
    d = xy - batch.position[:, :2]
    reach = np.linalg.norm(d, axis=1)
    az = np.c_[np.cos(batch.azimuth), np.sin(batch.azimuth)]
    along = np.where(reach[:, None] > 1e-6, d / np.maximum(reach, 1e-12)[:, None], az)
    across = np.c_[-along[:, 1], along[:, 0]]
    s_along, s_across = world.noise.sigma(reach)
    return (rng.standard_normal(n) * s_along)[:, None] * along + (
        rng.standard_normal(n) * s_across
    )[:, None] * across


def _record(
    name: str,
    i: int,
    o: ObjectParams,
    batch: ThrowBatch,
    observed: np.ndarray,
    c: Campaign,
    session: int,
) -> dict[str, Any]:
    """Throw i's docs/throw_log.md row of campaign `name`: object `o` as logged, its release
    from `batch`, its observed landing (x, y) [m, W], in session `session` (from 0)."""
    return {
        "throw_id": f"{name}-{i:05d}",
        **object_columns(o),
        "stroke_m": float(batch.stroke[i]),
        "x_m": float(batch.position[i, 0]),
        "y_m": float(batch.position[i, 1]),
        "z_m": float(batch.position[i, 2]),
        "elevation_rad": float(batch.elevation[i]),
        "azimuth_rad": float(batch.azimuth[i]),
        "roll_rad": float(batch.roll[i]),
        "vx_mps": 0.0,
        "vy_mps": 0.0,
        "vz_mps": 0.0,
        "platform": c.platform,
        "rotor_rpm": 0.0,
        "land_z_m": 0.0,
        "landed_x_m": float(observed[0]),
        "landed_y_m": float(observed[1]),
        "session": f"{name}-s{session + 1}",
        "time_s": i * c.seconds_per_throw,
    }


def draw_campaign(world: World, campaign: Campaign | None = None, *, seed: int = 0) -> ThrowTable:
    """Draw a campaign of throws in a world, as a throw log.

    The log carries the catalogue (CAD) mass and extents of each object; the
    landings come from the world's true parameters plus noise. The same world,
    campaign and seed give the same log.

    Args:
        world: the truth.
        campaign: what to throw (None = the default campaign).
        seed: random seed.

    Returns:
        The log (docs/throw_log.md columns plus session, time_s, t_flight_s, and mesh
        when a mesh object is thrown).

    Raises:
        InvalidInput: an unknown object id.
        InvalidParameter: throws that keep landing beyond the campaign's reach limit.
    """
    c = campaign or Campaign()
    cat = catalogue()
    unknown = [o for o in c.objects if o not in cat]
    if unknown:
        from cell.yamltree import nearest

        near = [(o, nearest(o, cat).removeprefix("; did you mean ")[:-1]) for o in unknown]
        named = [f"{n} for {o!r}" for o, n in near if n]
        hint = f"; did you mean {', '.join(named)}?" if named else ""
        raise InvalidInput(
            f"unknown object id(s) {unknown}{hint}; the catalogue has: {', '.join(cat)}"
        )
    rng = np.random.default_rng(seed)
    k = len(c.objects)
    which = rng.permutation(np.arange(c.n) % k)
    logged = [cat[c.objects[j]].params for j in which]
    true = [world.objects.get(o.name, o) for o in logged]
    pose = _draw_poses(rng, c, world.ee, c.n)
    todo = np.arange(c.n)
    for _ in range(100):
        batch = ThrowBatch.build(
            **{key: v for key, v in pose.items()},
            shape=[o.code for o in true],
            mass=[o.mass for o in true],
            size=[o.size for o in true],
        )
        land = world.landing(batch.take(todo))
        reach = np.hypot(land.x - batch.position[todo, 0], land.y - batch.position[todo, 1])
        bad = ~land.landed | ~(reach <= c.max_reach_m)
        if not bad.any():
            break
        todo = todo[bad]
        fresh = _draw_poses(rng, c, world.ee, todo.size)
        for key, v in fresh.items():
            pose[key][todo] = v
    else:
        raise InvalidParameter(
            f"{todo.size} throw(s) keep landing beyond {c.max_reach_m} m (or never land); "
            "raise max_reach_m or narrow the stroke and elevation ranges"
        )
    land = world.landing(batch)
    observed = land.xy + _noise(rng, world, batch, land.xy)
    session = np.minimum((np.arange(c.n) * c.sessions) // c.n, c.sessions - 1)
    records: list[dict[str, Any]] = []
    for i, o in enumerate(logged):
        rec = _record(f"synth{seed}", i, o, batch, observed[i], c, int(session[i]))
        rec["t_flight_s"] = float(land.t_flight[i])
        if any(x.shape == "mesh" for x in logged):
            rec["mesh"] = o.mesh
        records.append(rec)
    return ThrowTable.from_records(records, path="(synthetic campaign)")
