"""Where the gap lies, from observed tracks: launch, flight, landing or measurement.

For each tracked throw:

* launch: the launch state (position, velocity at the first sample) is fitted
  to the first samples (gravity and drag at the fitted velocity as the known
  acceleration) and compared with the model's; its share of the landing miss
  is the landing difference it makes under the nominal flight;
* flight: the nominal flight from the observed launch state is compared with
  the rest of the track (the deviation at the last sample);
* landing: the touchdown the track leads to (the nominal flight from the state
  fitted to the last samples) against the logged landing point;
* measurement: the track's apparent gravity (a free quadratic fit, corrected
  for drag) against g; a tracking system off in scale shows a gravity off by
  the same factor for every object.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import launch_overrides
from cell.model.flight3d import fly, sample_path
from cell.model.params import G
from cell.model.throw import drag_constant, launch_state

__all__ = ["TrackFit", "fit_tracks", "track_phase", "launch_arrays"]

WINDOW_S = 0.15  # [s] samples used for an end state
MIN_SAMPLES = 4
DISTURBED_S = 0.08  # [s] the first samples a release may still disturb (fit to the rest)
DROP_SIGMA = 3.0  # a leading sample this many σ (per axis) off the rest's fit is dropped


@dataclass(frozen=True)
class TrackFit:
    """States fitted to each throw's track (NaN rows: no usable track).

    Attributes:
        t0: time of the first sample [s], shape (n,).
        p0, v0: position [m] and velocity [m/s] at t0, shape (n, 3).
        c0: how an acceleration error Δa [m/s²] biases (p0, v0), shape (n, 2): zero, since
            the whole-track fit frees a constant acceleration (kept for the problem's
            launch correction).
        t1: time of the last sample [s], shape (n,).
        p1, v1: position and velocity at t1, shape (n, 3).
        g_ratio: apparent gravity over g (the whole track's free acceleration), shape (n,).
        dropped: leading samples dropped as disturbed, shape (n,).
        samples: the track per throw (k, 4) arrays t, x, y, z (None: no track).
    """

    t0: np.ndarray
    p0: np.ndarray
    v0: np.ndarray
    c0: np.ndarray
    t1: np.ndarray
    p1: np.ndarray
    v1: np.ndarray
    g_ratio: np.ndarray
    dropped: np.ndarray
    samples: list[np.ndarray | None]


def _state(
    tr: np.ndarray, k: float, at_start: bool
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """Position and velocity at the first (or last) sample, fitted to the samples within
    WINDOW_S of it with gravity and drag (at the fitted velocity) as known acceleration."""
    if at_start:
        sel = tr[:, 0] <= tr[0, 0] + WINDOW_S
        if sel.sum() < MIN_SAMPLES:
            sel = np.arange(len(tr)) < MIN_SAMPLES
        t_ref = tr[0, 0]
    else:
        sel = tr[:, 0] >= tr[-1, 0] - WINDOW_S
        if sel.sum() < MIN_SAMPLES:
            sel = np.arange(len(tr)) >= len(tr) - MIN_SAMPLES
        t_ref = tr[-1, 0]
    tau = tr[sel, 0] - t_ref
    pos = tr[sel, 1:4]
    a_mat = np.stack([np.ones_like(tau), tau], axis=1)
    acc = np.array([0.0, 0.0, -G])
    sol = np.zeros((2, 3))
    for _ in range(3):
        rhs = pos - 0.5 * tau[:, None] ** 2 * acc
        sol = np.linalg.lstsq(a_mat, rhs, rcond=None)[0]
        v = sol[1]
        acc = np.array([0.0, 0.0, -G]) - k * np.linalg.norm(v) * v
    bias = np.linalg.lstsq(a_mat, 0.5 * tau**2, rcond=None)[0]
    return float(t_ref), sol[0], sol[1], bias


def _drag_path(tau: np.ndarray, v0: np.ndarray, acc: np.ndarray, k: float) -> np.ndarray:
    """Displacement [m] drag adds at times tau (from 0) along the path with start velocity
    v0 and constant acceleration acc (drag evaluated on that path, integrated twice by the
    trapezoid rule from tau = 0)."""
    t = np.r_[0.0, tau] if tau[0] > 0 else tau
    v = v0[None, :] + t[:, None] * acc[None, :]
    d = -k * np.linalg.norm(v, axis=1)[:, None] * v
    dt = np.diff(t)[:, None]
    vel = np.vstack([np.zeros(3), np.cumsum(0.5 * (d[1:] + d[:-1]) * dt, axis=0)])
    pos = np.vstack([np.zeros(3), np.cumsum(0.5 * (vel[1:] + vel[:-1]) * dt, axis=0)])
    return pos[1:] if tau[0] > 0 else pos


def _free_fit(
    tau: np.ndarray, pos: np.ndarray, k: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity at tau = 0 and a constant extra acceleration (besides gravity and
    drag) fitted to samples (tau (m,) [s], pos (m, 3) [m]); also the residuals (m, 3)."""
    gvec = np.array([0.0, 0.0, -G])
    a_mat = np.stack([np.ones_like(tau), tau, 0.5 * tau**2], axis=1)
    sol = np.linalg.lstsq(a_mat, pos, rcond=None)[0]
    for _ in range(3):
        drag = _drag_path(tau, sol[1], sol[2], k)
        sol = np.linalg.lstsq(a_mat, pos - drag, rcond=None)[0]
    drag = _drag_path(tau, sol[1], sol[2], k)
    res = pos - drag - a_mat @ sol
    return sol[0], sol[1], sol[2] - gvec, res


def _whole_track(tr: np.ndarray, k: float) -> tuple[float, np.ndarray, np.ndarray, float, int]:
    """The launch state from the whole track, its disturbed first samples dropped.

    The track is fitted with a free start state and a free constant acceleration (gravity,
    any steady flight effect and a tracking scale all show as such) plus drag. The first
    samples after a release may still be disturbed (contact with the launcher, the
    tracker's lock): a fit to the samples after DISTURBED_S gives the scatter σ of the
    rest; the leading samples off that fit by more than DROP_SIGMA σ are dropped, and
    the state is fitted again from the first sample kept.

    Returns:
        (t0 [s], p0 [m], v0 [m/s] at the first kept sample, apparent gravity / g, dropped).
    """
    t = tr[:, 0]
    pos = tr[:, 1:4]
    core = t >= t[0] + DISTURBED_S
    if core.sum() < 8:
        core = np.ones(len(t), bool)
    _, _, _, res_core = _free_fit(t[core] - t[0], pos[core], k)
    sigma = float(np.sqrt(np.mean(np.sum(res_core**2, axis=1))))
    p_c, v_c, a_c, _ = _free_fit(t[core] - t[0], pos[core], k)
    tau_all = t - t[0]
    gvec = np.array([0.0, 0.0, -G])
    pred = p_c + np.outer(tau_all, v_c) + 0.5 * np.outer(tau_all**2, gvec + a_c)
    pred = pred + _drag_path(np.maximum(tau_all, 1e-9), v_c, gvec + a_c, k)
    off = np.linalg.norm(pos - pred, axis=1) / max(sigma / np.sqrt(3.0), 1e-4)
    # the leading run of samples off the fit (a disturbance decays: the sample after the
    # last one detected is dropped as well)
    out = off[: max(len(t) // 2, 1)] > DROP_SIGMA
    drop = int(np.argmin(out)) if not out.all() else int(out.size)
    drop = drop + 1 if drop else 0
    if len(t) - drop < 8:
        drop = max(len(t) - 8, 0)
    t0 = float(t[drop])
    p0, v0, a, _ = _free_fit(t[drop:] - t0, pos[drop:], k)
    g_ratio = float(-(a[2] - G) / G) if np.ptp(t[drop:]) >= 0.1 else float("nan")
    return t0, p0, v0, g_ratio, drop


def fit_tracks(throw_ids: list[str], tracks: dict[str, np.ndarray], k: np.ndarray) -> TrackFit:
    """Fit launch and end states and the apparent gravity to each throw's track.

    Args:
        throw_ids: the throws, in problem order.
        tracks: {throw_id: (m, 4) array of t_s, x_m, y_m, z_m} (read_tracks_csv).
        k: drag constant per throw [1/m], shape (n,).
    """
    n = len(throw_ids)
    out = {
        "t0": np.full(n, np.nan),
        "p0": np.full((n, 3), np.nan),
        "v0": np.full((n, 3), np.nan),
        "c0": np.zeros((n, 2)),
        "t1": np.full(n, np.nan),
        "p1": np.full((n, 3), np.nan),
        "v1": np.full((n, 3), np.nan),
        "g_ratio": np.full(n, np.nan),
        "dropped": np.zeros(n),
    }
    samples: list[np.ndarray | None] = []
    for i, tid in enumerate(throw_ids):
        tr = tracks.get(tid)
        if tr is None or len(tr) < MIN_SAMPLES or not np.all(np.isfinite(tr)):
            samples.append(None)
            continue
        samples.append(tr)
        t0, p0, v0, g_ratio, drop = _whole_track(tr, float(k[i]))
        out["t0"][i], out["p0"][i], out["v0"][i], out["g_ratio"][i] = t0, p0, v0, g_ratio
        out["dropped"][i] = drop
        out["t1"][i], out["p1"][i], out["v1"][i], _ = _state(tr, float(k[i]), False)
    return TrackFit(samples=samples, **out)


def launch_arrays(
    fit: TrackFit,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The observed launch states (p0, v0, t0) and their bias coefficients c0."""
    return fit.p0, fit.v0, fit.t0, fit.c0


def _rms(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


def track_phase(prob: GapProblem, fit: TrackFit) -> dict[str, Any]:
    """Each phase's share of the landing miss on the tracked throws, and the phase it points to.

    Returns:
        {"phase", "evidence", "launch_m", "flight_m", "landing_m", "g_ratio", "tracked"}.
    """
    ok = np.isfinite(fit.t0) & np.isfinite(fit.t1)
    n_tr = int(ok.sum())
    if n_tr < 5:
        return {"phase": None, "evidence": "fewer than 5 usable tracks", "tracked": n_tr}
    b = prob.batch
    k = drag_constant(b.shape, b.mass, b.size)
    idx = np.flatnonzero(ok)
    kk = k[idx]
    lz = b.land_z[idx]
    # observed launch state, nominal flight
    obs_land = fly(fit.p0[idx], fit.v0[idx], kk, lz, step=prob.step).position[:, :2]
    # the track's touchdown: nominal flight from the state fitted to its last samples
    end_land = fly(fit.p1[idx], fit.v1[idx], kk, lz, step=prob.step).position[:, :2]
    logged = prob.observed[idx]
    out: dict[str, Any] = {"tracked": n_tr}
    launch_m = float("nan")
    speed_pct = float("nan")
    own = prob.has_stroke[idx]
    if own.any():
        sub = b.take(idx[own])
        push, pm, ax = launch_overrides(sub, prob.ee, list(prob.base_effects))
        p_m, v_m = launch_state(sub, prob.ee, push=push, push_mass=pm, axis=ax)
        # the model's state carried to the first sample's time
        dt = fit.t0[idx[own]] - prob.ee.dt
        t_rel = np.maximum(dt, 0.0)[:, None]
        p_at = sample_path(p_m, v_m, kk[own], t_rel, step=prob.step)[:, 0, :]
        v_at = v_m + np.array([0.0, 0.0, -G]) * t_rel
        mod_land = fly(p_at, v_at, kk[own], lz[own], step=prob.step).position[:, :2]
        launch_m = _rms(np.linalg.norm(obs_land[own] - mod_land, axis=1))
        sp_obs = np.linalg.norm(fit.v0[idx[own]], axis=1)
        sp_mod = np.linalg.norm(v_at, axis=1)
        speed_pct = float(np.nanmedian(100 * (sp_obs / sp_mod - 1)))
    # flight: where the nominal flight from the observed launch is at the last sample
    t_rel = (fit.t1[idx] - fit.t0[idx])[:, None]
    p_last = sample_path(fit.p0[idx], fit.v0[idx], kk, t_rel, step=prob.step)[:, 0, :]
    flight_m = _rms(np.linalg.norm(p_last - fit.p1[idx], axis=1))
    flight_land_m = _rms(np.linalg.norm(end_land - obs_land, axis=1))
    landing_m = _rms(np.linalg.norm(logged - end_land, axis=1))
    g = fit.g_ratio[idx]
    g = g[np.isfinite(g)]
    g_med = float(np.median(g)) if g.size else float("nan")
    g_se = float(1.2533 * np.std(g) / np.sqrt(max(g.size, 1))) if g.size else float("nan")
    per_obj = []
    for o in np.unique(prob.groups[idx]):
        go = fit.g_ratio[idx][prob.groups[idx] == o]
        go = go[np.isfinite(go)]
        if go.size >= 3:
            per_obj.append(np.median(go))
    spread = float(np.std(per_obj)) if len(per_obj) >= 2 else 0.0
    measurement = (
        np.isfinite(g_med)
        and abs(g_med - 1) > max(0.015, 4 * g_se)
        and spread < 0.3 * abs(g_med - 1)
    )
    shares = {"launch": launch_m, "flight": flight_land_m, "landing": landing_m}
    finite = {kk_: v for kk_, v in shares.items() if np.isfinite(v)}
    if measurement:
        phase = "measurement"
    else:
        phase = max(finite, key=lambda p: finite[p])
    parts = []
    if np.isfinite(speed_pct):
        parts.append(
            f"launch speed from tracks is {abs(speed_pct):.1f}% "
            f"{'below' if speed_pct < 0 else 'above'} the model"
        )
    parts.append(
        f"launch accounts for {launch_m:.3f} m of landing miss"
        if np.isfinite(launch_m)
        else "no launch comparison (no stroke logged)"
    )
    parts.append(
        f"the flight after launch bends {flight_m:.3f} m off the nominal path "
        f"({flight_land_m:.3f} m at the landing)"
    )
    parts.append(f"logged landings lie {landing_m:.3f} m from the tracks' touchdowns")
    parts.append(
        f"apparent gravity is {g_med:.3f} g (±{g_se:.3f}, spread over objects {spread:.3f})"
    )
    out.update(
        {
            "phase": phase,
            "evidence": "; ".join(parts),
            "launch_m": launch_m,
            "flight_m": flight_land_m,
            "flight_path_m": flight_m,
            "landing_m": landing_m,
            "launch_speed_pct": speed_pct,
            "g_ratio": g_med,
            "g_ratio_se": g_se,
            "g_ratio_object_spread": spread,
            "measurement": bool(measurement),
            "dropped_samples_mean": float(np.mean(fit.dropped[idx])),
        }
    )
    return out
