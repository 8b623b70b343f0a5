"""Synthetic worlds with an effect the model lacks, and targeted throws of
objects at set targets in such a world (thesis §5.3), with and without the
residual.

The shape-stretch world: a band wrapped round a curved or irregular object
stretches more than the flat-contact geometry of eqs. 3.1-3.2 says (GAP.md
`shape_stretch`). Here the extra stretch is

    ΔL_extra = κ · a        for cylinders, spheres and meshes,
    ΔL_extra = 0            for cubes and cuboids (flat faces),

with a = size_x the grip width [m], and the push is f_o = 2 f_e(ΔL + ΔL_extra) cos α.
The world knows only the shape class and the width: it is independent of the
point-cloud descriptors the residual learns from.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.errors import InvalidInput
from cell.model.band import band_angle, band_force, band_stretch
from cell.model.objects import SHAPES, ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import Landing, ThrowBatch, predict_landing
from cell.residual.target import OK, reach_along_azimuth, stroke_for_reach

__all__ = [
    "CURVED_SHAPES",
    "shape_stretch_hook",
    "TargetedThrows",
    "targeted_throws",
    "unseen_ids",
    "world_thrower",
]

CURVED_SHAPES = ("cylinder", "sphere", "mesh")
_CURVED_CODES = np.array([SHAPES.index(s) for s in CURVED_SHAPES])

PredictHook = Callable[[ThrowBatch, EndEffectorParams], Landing]


def shape_stretch_hook(kappa: float) -> PredictHook:
    """A world `predict` hook with the shape-dependent extra band stretch κ · a.

    Args:
        kappa: extra stretch per metre of grip width [m/m] for curved shapes.
    """

    def predict(batch: ThrowBatch, ee: EndEffectorParams) -> Landing:
        width = batch.size[:, 0]
        extra = np.where(np.isin(batch.shape, _CURVED_CODES), kappa * width, 0.0)
        stretch = band_stretch(batch.stroke, width, ee) + extra
        push = 2 * band_force(stretch, ee) * np.cos(band_angle(batch.stroke, width, ee))
        return predict_landing(batch, ee, strict=False, check_stroke=False, push=push)

    return predict


def unseen_ids() -> list[str]:
    """The catalogue's unseen objects (thesis §5.3: 2 primitives and 5 meshes), sorted."""
    return [k for k, e in catalogue().items() if e.set == "unseen"]


@dataclass(frozen=True)
class TargetedThrows:
    """Throws at set targets, each made twice: with the model's stroke and with the residual's.

    Attributes:
        object_id: object of each throw, length n.
        target_xy: targets [m, W], shape (n, 2).
        stroke_model: the model's stroke for the target [m], shape (n,).
        delta_stroke: the residual's ΔL_s [m], shape (n,).
        stroke_residual: L_s + ΔL_s, clipped to the stroke range [m], shape (n,).
        clipped: True where L_s + ΔL_s left the stroke range, shape (n,).
        landed_model: landings with the model's stroke [m, W], shape (n, 2).
        landed_residual: landings with the corrected stroke [m, W], shape (n, 2).
    """

    object_id: list[str]
    target_xy: np.ndarray
    stroke_model: np.ndarray
    delta_stroke: np.ndarray
    stroke_residual: np.ndarray
    clipped: np.ndarray
    landed_model: np.ndarray
    landed_residual: np.ndarray

    def rmse(self, residual: bool) -> float:
        """Landing RMSE to the targets [m], with or without the residual, over the
        throws that landed in both runs (a throw a scene lost is left out of both)."""
        return _rmse(self._err(residual)[self.landed_both])

    @property
    def landed_both(self) -> np.ndarray:
        """True where both throws of a target have a landing point, shape (n,)."""
        return np.isfinite(self.landed_model).all(axis=1) & np.isfinite(self.landed_residual).all(
            axis=1
        )

    def _err(self, residual: bool) -> np.ndarray:
        land = self.landed_residual if residual else self.landed_model
        return np.sum((land - self.target_xy) ** 2, axis=1)

    def per_object(self) -> dict[str, dict[str, float]]:
        """Landing RMSE to the targets per object [m], without and with the residual."""
        out: dict[str, dict[str, float]] = {}
        ids = np.asarray(self.object_id)
        for oid in sorted(set(self.object_id)):
            m = (ids == oid) & self.landed_both
            out[oid] = {
                "rmse_before_m": _rmse(self._err(False)[m]),
                "rmse_after_m": _rmse(self._err(True)[m]),
                "throws": int(m.sum()),
            }
        return out


def _rmse(sq: np.ndarray) -> float:
    return float(np.sqrt(np.mean(sq))) if sq.size else float("nan")


Thrower = Callable[[list[str], np.ndarray, dict[str, np.ndarray]], np.ndarray]


def world_thrower(world: Any, seed: int = 0) -> Thrower:
    """A thrower that throws in a synthetic world (`cell.synth.World`): true η_o, the
    world's landing and its landing noise. Every call draws the same noise sequence
    (common random numbers), so two calls with different strokes differ only by
    what the strokes do.

    The thrower is called as `thrower(object_ids, stroke_m, pose)` with pose the
    ThrowBatch keywords position, elevation, azimuth, land_z, and returns landings
    (n, 2) [m, W].
    """
    cat = catalogue()

    def throw(ids: list[str], stroke: np.ndarray, pose: dict[str, np.ndarray]) -> np.ndarray:
        true = [world.objects.get(o, cat[o].params) for o in ids]
        b = ThrowBatch.build(
            stroke=stroke,
            shape=[o.code for o in true],
            mass=[o.mass for o in true],
            size=[o.size for o in true],
            **pose,
        )
        land = world.landing(b)
        d = land.xy - b.position[:, :2]
        reach = np.linalg.norm(d, axis=1)
        along = d / np.maximum(reach, 1e-12)[:, None]
        across = np.c_[-along[:, 1], along[:, 0]]
        s_al, s_ac = world.noise.sigma(reach)
        z = np.random.default_rng(seed).standard_normal((len(ids), 2))
        return land.xy + (z[:, 0] * s_al)[:, None] * along + (z[:, 1] * s_ac)[:, None] * across

    return throw


def _random_poses(
    rng: np.random.Generator, n: int, height_m: tuple[float, float], land_z_m: float
) -> dict[str, np.ndarray]:
    """n release poses drawn from `rng` (`targeted_throws`): grip centres within ±0.1 m of
    the origin in x and y at heights in `height_m` [m, W], the throw axis 15-50° up and
    ±30° round, landing on the plane z = land_z_m [m]."""
    return {
        "position": np.c_[
            rng.uniform(-0.1, 0.1, n), rng.uniform(-0.1, 0.1, n), rng.uniform(*height_m, n)
        ],
        "elevation": rng.uniform(np.radians(15), np.radians(50), n),
        "azimuth": rng.uniform(np.radians(-30), np.radians(30), n),
        "land_z": np.full(n, float(land_z_m)),
    }


def targeted_throws(
    world: Any,
    residual: Any,
    object_ids: list[str],
    *,
    model_ee: EndEffectorParams,
    throws_per_object: int = 5,
    seed: int = 0,
    stroke_range_m: tuple[float, float] = (0.045, 0.095),
    height_m: tuple[float, float] = (0.45, 0.85),
    land_z_m: float = 0.0,
) -> TargetedThrows:
    """Throw each object at set targets, with and without the residual.

    A target is where the model lands the object from a random release pose with
    a random stroke in `stroke_range_m`, so that every target is within the
    model's reach. The model's stroke for it is found by the model's inverse; the
    residual adds ΔL_s (clipped to the stroke range, flagged); both strokes are
    thrown.

    Args:
        world: a `cell.synth.World` (thrown with `world_thrower`, same noise for
            both strokes), or a thrower `(object_ids, stroke_m, pose) -> (n, 2)`
            landings, e.g. one that throws in the PyBullet scene.
        residual: a fitted `ResidualModel`.
        object_ids: catalogue ids to throw.
        model_ee: the model's (identified) end-effector parameters.
        throws_per_object: throws per object (thesis §5.3: 5).
        seed: random seed.
        stroke_range_m: range of the strokes the targets are made with [m].
        height_m: range of release heights [m].
        land_z_m: landing plane of the targets [m].

    Raises:
        InvalidInput: an unknown object id.
    """
    from cell.residual.features import GripPose

    cat = catalogue()
    bad = [o for o in object_ids if o not in cat]
    if bad:
        raise InvalidInput(f"unknown object id(s) {bad}; the catalogue has: {', '.join(cat)}")
    thrower: Thrower = world_thrower(world, seed + 1) if hasattr(world, "landing") else world
    rng = np.random.default_rng(seed)
    ids = [o for o in object_ids for _ in range(throws_per_object)]
    objs: list[ObjectParams] = [cat[o].params for o in ids]
    n = len(ids)
    pose = _random_poses(rng, n, height_m, land_z_m)
    model_batch = ThrowBatch.build(
        stroke=rng.uniform(*stroke_range_m, n),
        shape=[o.code for o in objs],
        mass=[o.mass for o in objs],
        size=[o.size for o in objs],
        **pose,
    )
    target = predict_landing(model_batch, model_ee, check_stroke=False).xy
    sol = stroke_for_reach(model_batch, reach_along_azimuth(model_batch, target), model_ee)
    if not np.all(sol.status == OK):
        raise InvalidInput("a target fell outside the model's reach; narrow stroke_range_m")
    poses = [
        GripPose(float(s), float(e)) for s, e in zip(sol.stroke, model_batch.elevation, strict=True)
    ]
    delta = residual.delta_strokes(objs, poses)
    raw = sol.stroke + delta
    stroke_res = np.clip(raw, model_ee.stroke_min, model_ee.stroke_max)
    return TargetedThrows(
        object_id=ids,
        target_xy=target,
        stroke_model=sol.stroke,
        delta_stroke=delta,
        stroke_residual=stroke_res,
        clipped=raw != stroke_res,
        landed_model=thrower(ids, sol.stroke, pose),
        landed_residual=thrower(ids, stroke_res, pose),
    )
