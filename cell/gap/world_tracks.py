"""Tracked campaigns for the check world: camera tracks of every throw, and throws from
another launcher (no stroke logged) whose launch the world draws directly."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cell.gap.world import other_launch, throw_records
from cell.log.table import ThrowTable
from cell.model.effects import Effect, TrackingScale
from cell.model.effects_apply import flight_accel, launch_overrides, predict_with_effects
from cell.model.flight3d import sample_path
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.model.throw import drag_constant, launch_state

__all__ = ["TrackedCampaign", "draw_tracked_campaign"]

TRACK_RATE_HZ = 100.0


@dataclass(frozen=True)
class TrackedCampaign:
    """A campaign with tracks {throw_id: (k, 4) t, x, y, z} and its truth."""

    table: ThrowTable
    tracks: dict[str, np.ndarray]
    truth: str
    effects: tuple[Effect, ...]
    noise_m: float


def draw_tracked_campaign(
    effects: tuple[Effect, ...],
    rng: np.random.Generator,
    *,
    n: int = 200,
    other_launcher: bool = True,
    landing_noise_m: float = 0.01,
    track_noise_m: float = 0.003,
    ee: EndEffectorParams = DEFAULT_EE,
    objects: tuple[str, ...] = (),
) -> TrackedCampaign:
    """Draw throws with tracks.

    Args:
        effects: the world's effects (empty: nominal).
        rng: random generator.
        n: throws.
        other_launcher: throws from another launcher: no stroke logged, launch speed
            drawn in 3–7 m/s along the throw axis; else this end-effector's throws.
        landing_noise_m: per-axis scatter of the logged landing [m].
        track_noise_m: per-axis scatter of each track sample [m].
        ee: the end-effector.
        objects: the catalogue's objects thrown, by name (empty: `throw_records`' own).
    """
    recs = throw_records(n, rng, objects=objects)
    stub = ThrowTable.from_records([{**r, "landed_x_m": 0.0, "landed_y_m": 0.0} for r in recs])
    batch = stub.to_batch()
    rpm = stub.num("rotor_rpm")
    eff = list(effects)
    s = next((e.scale_factor for e in eff if isinstance(e, TrackingScale)), 1.0)
    if other_launcher:  # the same config is thrown twice with the same launch (repeats)
        p1, v1, t1 = other_launch(batch, recs, rng)
    else:
        push, pm, ax = launch_overrides(batch, ee, eff)
        p1, v1 = launch_state(batch, ee, push=push, push_mass=pm, axis=ax)
        t1 = np.full(n, ee.dt)
    land = predict_with_effects(
        batch, ee, eff, rotor_rpm=rpm, launch=(p1 * s, v1 * s, t1), step=0.004
    )
    ok = land.landed
    t_end = land.t_flight - t1 - 0.02
    m = int(np.ceil(np.nanmax(t_end) * TRACK_RATE_HZ)) + 1
    t_rel = np.arange(m)[None, :] / TRACK_RATE_HZ + np.zeros((n, 1))
    t_rel = np.where(t_rel <= t_end[:, None], t_rel, np.nan)
    kd = drag_constant(batch.shape, batch.mass, batch.size)
    accel = flight_accel(batch, eff, rpm)
    path = sample_path(p1, v1, kd, t_rel, accel=accel, step=0.004) * s
    path = path + rng.normal(0.0, track_noise_m, path.shape)
    noise = rng.normal(0.0, landing_noise_m, (n, 2))
    rows, tracks = [], {}
    for i, r in enumerate(recs):
        if not ok[i]:
            continue
        row = {**r, "landed_x_m": float(land.x[i] + noise[i, 0]),
               "landed_y_m": float(land.y[i] + noise[i, 1])}  # fmt: skip
        if other_launcher:
            row["stroke_m"] = ""
        rows.append(row)
        sel = np.isfinite(t_rel[i])
        tracks[r["throw_id"]] = np.c_[t_rel[i, sel] + t1[i], path[i, sel]]
    truth = "+".join(e.name for e in eff) or "none"
    return TrackedCampaign(
        table=ThrowTable.from_records(rows),
        tracks=tracks,
        truth=truth,
        effects=tuple(effects),
        noise_m=float(landing_noise_m * np.sqrt(2)),
    )
