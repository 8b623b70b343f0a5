"""Worlds drawn with laws other than the diagnosis' own formulas (GAP.md: an effect is a
family of laws; the real world is free to follow another law than the tool's first guess).

A world is a list of laws, each a plain dict {"law": name, ...parameters} (picklable, so a
check case can be shipped to a worker). The laws are written here from their physics, not
from `cell.model.effects`:

| law | what the world does | the effect it belongs to |
|---|---|---|
| rolling | the object rolls on after touchdown, its speed decaying exponentially with time constant `tau_s` [s]: it comes to rest `tau_s` · v_h further along v_h (∝ impact speed) | bounce |
| friction | the object slides on under Coulomb friction `mu`: v_h² / (2 μ g) further (∝ impact speed squared), stepped in time here | bounce |
| jet | a rotor jet: downward air speed `w_mps` · (rpm / 5000)^`p`, a Gaussian profile of radius `radius_m` about the release point, decaying as exp(−depth / `depth_m`) below the release height | downwash |
| breeze | a steady air flow `x_mps`, `y_mps` (horizontal) | wind |
| drag | every object's C_d times `factor` (rough, soft or tumbling objects) | drag_scale |
| scale | the tracker logs positions × `s` about the world origin | tracking_scale |
| yaw | the object leaves with its throw axis turned by `delta_rad` about the vertical (not in the vocabulary: a launch gap) | unknown |
| tilt | the landing floor is tilted by `slope` towards `azimuth_rad` about the origin (not in the vocabulary) | unknown |

Throws are this end-effector's (stroke logged, nominal launch) or another launcher's
(no stroke; launch speed drawn in 3–7 m/s along the throw axis). Tracks are sampled at
100 Hz with Gaussian scatter; with `disturbed` the first samples after the release are
still disturbed (the object lags its free flight by a few centimetres, decaying within
~40 ms, as a band or carriage still in contact would make it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.gap.world import other_launch, throw_records
from cell.log.csvio import ThrowTable
from cell.model.flight3d import Rows, fly, sample_path
from cell.model.params import DEFAULT_EE, EndEffectorParams, G
from cell.model.throw import ThrowBatch, drag_constant, launch_state

__all__ = ["LawCampaign", "draw_law_campaign", "LAW_EFFECT"]

TRACK_RATE_HZ = 100.0
WORLD_STEP = 0.004  # [s]
REF_RPM = 5000.0

# the vocabulary effect each law belongs to (its truth)
LAW_EFFECT = {
    "rolling": "bounce",
    "friction": "bounce",
    "jet": "downwash",
    "breeze": "wind",
    "drag": "drag_scale",
    "scale": "tracking_scale",
    "yaw": "unknown",
    "tilt": "unknown",
}


@dataclass(frozen=True)
class LawCampaign:
    """A drawn campaign: the log, the tracks (or None), the truth and the world's floor.

    Attributes:
        table: the throw log.
        tracks: {throw_id: (k, 4) t [s], x, y, z [m]} or None.
        truth: the expected verdict ("+"-joined effect names, `none` or `unknown`).
        laws: the world's laws.
        noise_m: 2-D RMS of the landing scatter [m].
        true_xy: the landings without scatter (observed scale) [m], shape (n, 2).
    """

    table: ThrowTable
    tracks: dict[str, np.ndarray] | None
    truth: str
    laws: tuple[dict[str, Any], ...]
    noise_m: float
    true_xy: np.ndarray
    true_launch: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    accel: Any = None


def _law(laws: list[dict[str, Any]], name: str) -> dict[str, Any] | None:
    return next((w for w in laws if w["law"] == name), None)


def _accel(batch: ThrowBatch, laws: list[dict[str, Any]], rpm: np.ndarray) -> Any:
    jet = _law(laws, "jet")
    breeze = _law(laws, "breeze")
    if jet is None and breeze is None:
        return None
    centre = batch.position.copy()
    w0 = np.zeros(len(batch))
    if jet is not None:
        w0 = jet["w_mps"] * (np.clip(rpm, 0, None) / REF_RPM) ** jet["p"]
    flow = np.zeros(3)
    if breeze is not None:
        flow[:2] = breeze["x_mps"], breeze["y_mps"]

    rows = Rows({"cx": centre[:, 0], "cy": centre[:, 1], "cz": centre[:, 2], "w0": w0})

    def accel(p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[Any, Any]:
        w = np.broadcast_to(flow, p.shape).copy()
        if jet is not None:
            r = rows(idx)
            rho2 = (p[:, 0] - r["cx"]) ** 2 + (p[:, 1] - r["cy"]) ** 2
            depth = np.maximum(r["cz"] - p[:, 2], 0.0)
            prof = np.exp(-rho2 / jet["radius_m"] ** 2) * np.exp(-depth / jet["depth_m"])
            w[:, 2] -= r["w0"] * prof
        return w, None

    return accel


def _rest(xy: np.ndarray, v_imp: np.ndarray, laws: list[dict[str, Any]]) -> np.ndarray:
    """Where the objects come to rest after touchdown (rolling or sliding on)."""
    vh = v_imp[:, :2]
    out = xy.copy()
    roll = _law(laws, "rolling")
    if roll is not None:
        # v(t) = v_h exp(-t / tau): the distance rolled is v_h tau
        t = np.linspace(0.0, 12.0 * roll["tau_s"], 2001)
        dist = np.trapezoid(np.exp(-t / roll["tau_s"]), t)
        out = out + vh * dist
    fr = _law(laws, "friction")
    if fr is not None:
        # Coulomb deceleration μ g against the motion until rest, stepped in time
        speed = np.linalg.norm(vh, axis=1)
        d = vh / np.maximum(speed, 1e-12)[:, None]
        s = np.zeros_like(speed)
        u = speed.copy()
        h = 1e-3
        dec = fr["mu"] * G
        while np.any(u > 0):
            u_new = np.maximum(u - dec * h, 0.0)
            s += 0.5 * (u + u_new) * h
            u = u_new
        out = out + d * s[:, None]
    return out


def _tilted_landing(
    p1: np.ndarray, v1: np.ndarray, t1: np.ndarray, k: np.ndarray, lz0: np.ndarray,
    accel: Any, tilt: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    d = np.array([np.cos(tilt["azimuth_rad"]), np.sin(tilt["azimuth_rad"])])
    res = fly(p1, v1, k, lz0, accel=accel, t0=t1, step=WORLD_STEP)
    for _ in range(6):
        lz = lz0 + tilt["slope"] * np.nan_to_num(res.position[:, :2] @ d)
        res = fly(p1, v1, k, lz, accel=accel, t0=t1, step=WORLD_STEP)
    return res.position, res.velocity, res.t


def _drag(batch: Any, laws: list[dict[str, Any]]) -> np.ndarray:
    """The throws' drag constants [1/m], scaled by the `drag` law where there is one."""
    k = drag_constant(batch.shape, batch.mass, batch.size)
    dr = _law(laws, "drag")
    if dr is not None:
        k = k * dr["factor"]
    return k


def _law_launch(
    batch: Any,
    recs: list[dict[str, Any]],
    yaw: dict[str, Any] | None,
    rng: np.random.Generator,
    other_launcher: bool,
    ee: EndEffectorParams,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(positions [m], velocities [m/s], times [s]) at the launch of `draw_law_campaign`'s
    throws: another launcher's (a speed drawn per configuration along the throw axis), or
    the model's push; turned about the vertical by the `yaw` law."""
    n = len(recs)
    if other_launcher:
        p1, v1, t1 = other_launch(batch, recs, rng)
    else:
        p1, v1 = launch_state(batch, ee)
        t1 = np.full(n, ee.dt)
    if yaw is not None:
        c, s_ = np.cos(yaw["delta_rad"]), np.sin(yaw["delta_rad"])
        rel = v1 - batch.base_velocity
        rel = np.c_[c * rel[:, 0] - s_ * rel[:, 1], s_ * rel[:, 0] + c * rel[:, 1], rel[:, 2]]
        v1 = rel + batch.base_velocity
    return p1, v1, t1


def _law_path(
    p1: np.ndarray,
    v1: np.ndarray,
    t1: np.ndarray,
    k: np.ndarray,
    accel: Any,
    landed: tuple[np.ndarray, np.ndarray],
    s: float,
    rng: np.random.Generator,
    disturbed: bool,
    track_noise_m: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(times since the launch [s] (n, m), the tracked positions [m, W] (n, m, 3)) of each
    throw's track at TRACK_RATE_HZ up to its landing (`landed`: (landed?, landing time)),
    on the observed scale `s`, with `track_noise_m` of noise and, `disturbed`, its first
    samples pulled back."""
    ok, t_land = landed
    n = len(p1)
    t_end = np.where(ok, t_land - t1 - 0.02, 0.0)
    m = int(np.ceil(np.nanmax(t_end) * TRACK_RATE_HZ)) + 1
    t_rel = np.arange(m)[None, :] / TRACK_RATE_HZ + np.zeros((n, 1))
    t_rel = np.where(t_rel <= t_end[:, None], t_rel, np.nan)
    path = sample_path(p1, v1, k, t_rel, accel=accel, step=WORLD_STEP)
    if disturbed:
        # the object still lags its free flight: pulled back along its launch direction
        lag = rng.uniform(0.02, 0.04, n)[:, None, None]
        u = v1 / np.linalg.norm(v1, axis=1)[:, None]
        decay = np.exp(-np.nan_to_num(t_rel, nan=1.0) / 0.012)[:, :, None]
        path = path - lag * decay * u[:, None, :]
    path = path * s + rng.normal(0.0, track_noise_m, path.shape)
    return t_rel, path


def draw_law_campaign(
    laws: list[dict[str, Any]] | tuple[dict[str, Any], ...],
    rng: np.random.Generator,
    *,
    n: int = 240,
    other_launcher: bool = False,
    tracked: bool = False,
    disturbed: bool = False,
    landing_noise_m: float = 0.012,
    track_noise_m: float = 0.003,
    ee: EndEffectorParams = DEFAULT_EE,
    repeats: int = 2,
) -> LawCampaign:
    """Draw a campaign whose world follows `laws`.

    Args:
        laws: the world's laws (see the module table); empty: nominal.
        rng: the random generator.
        n: throws.
        other_launcher: throws from another launcher (no stroke logged; needs tracks).
        tracked: log tracks of every throw.
        disturbed: the first samples of each track are disturbed.
        landing_noise_m: per-axis scatter of the logged landings [m].
        track_noise_m: per-axis scatter of each track sample [m].
        ee: the end-effector (of the world and of the configured model).
        repeats: times each configuration is thrown.
    """
    laws = list(laws)
    recs = throw_records(n, rng, repeats=repeats)
    stub = ThrowTable.from_records([{**r, "landed_x_m": 0.0, "landed_y_m": 0.0} for r in recs])
    batch = stub.to_batch()
    rpm = stub.num("rotor_rpm")
    p1, v1, t1 = _law_launch(batch, recs, _law(laws, "yaw"), rng, other_launcher, ee)
    k = _drag(batch, laws)
    accel = _accel(batch, laws, rpm)
    tilt = _law(laws, "tilt")
    if tilt is not None:
        pos, vel, t_land = _tilted_landing(p1, v1, t1, k, batch.land_z, accel, tilt)
    else:
        res = fly(p1, v1, k, batch.land_z, accel=accel, t0=t1, step=WORLD_STEP)
        pos, vel, t_land = res.position, res.velocity, res.t
    ok = np.isfinite(t_land)
    sc = _law(laws, "scale")
    s = sc["s"] if sc is not None else 1.0
    xy = _rest(pos[:, :2], vel, laws) * s
    noise = rng.normal(0.0, landing_noise_m, (n, 2))
    tracks: dict[str, np.ndarray] | None = None
    path = t_rel = None
    if tracked or other_launcher:
        t_rel, path = _law_path(
            p1, v1, t1, k, accel, (ok, t_land), s, rng, disturbed, track_noise_m
        )
        tracks = {}
    rows = []
    for i, r in enumerate(recs):
        if not ok[i]:
            continue
        row = {**r, "landed_x_m": float(xy[i, 0] + noise[i, 0]),
               "landed_y_m": float(xy[i, 1] + noise[i, 1])}  # fmt: skip
        if other_launcher:
            row["stroke_m"] = ""
        rows.append(row)
        if tracks is not None and path is not None and t_rel is not None:
            sel = np.isfinite(t_rel[i])
            tracks[r["throw_id"]] = np.c_[t_rel[i, sel] + t1[i], path[i, sel]]
    truth = "+".join(dict.fromkeys(LAW_EFFECT[w["law"]] for w in laws)) or "none"
    if "unknown" in truth:
        truth = "unknown"
    return LawCampaign(
        table=ThrowTable.from_records(rows),
        tracks=tracks,
        truth=truth,
        laws=tuple(laws),
        noise_m=float(landing_noise_m * np.sqrt(2)),
        true_xy=xy[ok],
        true_launch=(p1[ok], v1[ok], t1[ok]),
        accel=(accel, k[ok], ok),
    )
