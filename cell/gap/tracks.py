"""Where the gap lies, from observed tracks: launch, flight, landing or measurement.

For each tracked throw:

* launch state: fitted to the whole track (not its first samples alone) with a free
  start state and a free constant acceleration besides gravity and drag; the first
  samples after a release may still be disturbed (contact with the launcher, the
  tracker's lock), so a leading run of samples off the fit to the rest is dropped. This
  is the launch of a throw from another launcher;
* launch and flight shares: the free flight (acceleration linear in time) fitted to the
  even and to the odd samples separately, carried back to the release. Launch share:
  the landing difference between that release state and the model's under the nominal
  flight; flight share: the landing difference between the nominal flight from it and
  the observed flight. Each is the mean product of the two halves' differences, so the
  tracks' scatter drops out, and comes with a z-score;
* landing: the touchdown the track leads to (the nominal flight from the state fitted to
  the last samples) against the logged landing point;
* measurement: the whole track's apparent gravity against g; a tracking system off in
  scale shows a gravity off by the same factor for every object.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects_apply import launch_overrides
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
        a0: the whole track's constant acceleration besides gravity and drag [m/s²],
            shape (n, 3).
        halves: the free flight fitted to the even and to the odd samples (acceleration
            linear in time): position [m] and velocity [m/s] at the first and at the last
            kept sample, the extra acceleration [m/s²] at the first and its rate [m/s³],
            shape (2 halves, 6, n, 3).
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
    a0: np.ndarray
    halves: np.ndarray
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


def _drag_path(
    tau: np.ndarray, v0: np.ndarray, acc: np.ndarray, k: float, jerk: np.ndarray | None = None
) -> np.ndarray:
    """Displacement [m] drag adds at times tau (from 0) along the path with start velocity
    v0, acceleration acc and jerk (drag evaluated on that path, integrated twice by the
    trapezoid rule from tau = 0)."""
    t = np.r_[0.0, tau] if tau[0] > 0 else tau
    v = v0[None, :] + t[:, None] * acc[None, :]
    if jerk is not None:
        v = v + 0.5 * t[:, None] ** 2 * jerk[None, :]
    d = -k * np.linalg.norm(v, axis=1)[:, None] * v
    dt = np.diff(t)[:, None]
    vel = np.vstack([np.zeros(3), np.cumsum(0.5 * (d[1:] + d[:-1]) * dt, axis=0)])
    pos = np.vstack([np.zeros(3), np.cumsum(0.5 * (vel[1:] + vel[:-1]) * dt, axis=0)])
    return pos[1:] if tau[0] > 0 else pos


def _free_fit(
    tau: np.ndarray, pos: np.ndarray, k: float, jerk: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity at tau = 0 and a constant extra acceleration (besides gravity and
    drag) fitted to samples (tau (m,) [s], pos (m, 3) [m]); also the residuals (m, 3).
    With `jerk` the extra acceleration is linear in time (returned as (a, j) stacked, (2, 3))."""
    gvec = np.array([0.0, 0.0, -G])
    cols = [np.ones_like(tau), tau, 0.5 * tau**2] + ([tau**3 / 6] if jerk else [])
    a_mat = np.stack(cols, axis=1)
    sol = np.linalg.lstsq(a_mat, pos, rcond=None)[0]
    for _ in range(3):
        drag = _drag_path(tau, sol[1], sol[2], k, sol[3] if jerk else None)
        sol = np.linalg.lstsq(a_mat, pos - drag, rcond=None)[0]
    drag = _drag_path(tau, sol[1], sol[2], k, sol[3] if jerk else None)
    res = pos - drag - a_mat @ sol
    extra = np.stack([sol[2] - gvec, sol[3]]) if jerk else sol[2] - gvec
    return sol[0], sol[1], extra, res


def _whole_track(
    tr: np.ndarray, k: float
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, float, int]:
    """The launch state from the whole track, its disturbed first samples dropped.

    The track is fitted with a free start state and a free constant acceleration (gravity,
    any steady flight effect and a tracking scale all show as such) plus drag. The first
    samples after a release may still be disturbed (contact with the launcher, the
    tracker's lock): a fit to the samples after DISTURBED_S gives the scatter σ of the
    rest; the leading samples off that fit by more than DROP_SIGMA σ are dropped, and
    the state is fitted again from the first sample kept.

    Returns:
        (t0 [s], p0 [m], v0 [m/s] at the first kept sample, the extra acceleration
        [m/s²], apparent gravity / g, samples dropped).
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
    # the leading run of samples off the fit (a disturbance decays: the two samples after
    # the last one detected are dropped as well)
    out = off[: max(len(t) // 2, 1)] > DROP_SIGMA
    drop = int(np.argmin(out)) if not out.all() else int(out.size)
    drop = drop + 2 if drop else 0
    if len(t) - drop < 8:
        drop = max(len(t) - 8, 0)
    t0 = float(t[drop])
    p0, v0, a, _ = _free_fit(t[drop:] - t0, pos[drop:], k)
    g_ratio = float(-(a[2] - G) / G) if np.ptp(t[drop:]) >= 0.1 else float("nan")
    return t0, p0, v0, a, g_ratio, drop


def _halves(tr: np.ndarray, k: float, drop: int) -> np.ndarray | None:
    """The free flight (acceleration linear in time) fitted to the even and to the odd
    samples kept: per half, position and velocity at the first and at the last kept sample,
    the extra acceleration at the first and its rate, (2, 6, 3) [m, m/s, m/s², m/s³] (None:
    too few samples). Two independent estimates
    of the same path: the product of their deviations from a reference is free of the
    track's scatter on average."""
    t = tr[drop:, 0]
    pos = tr[drop:, 1:4]
    if len(t) < 16:
        return None
    out = np.zeros((2, 6, 3))
    gvec = np.array([0.0, 0.0, -G])
    for h in range(2):
        sel = slice(h, None, 2)
        p0, v0, aj, _ = _free_fit(t[sel] - t[0], pos[sel], k, jerk=True)
        a, j = aj
        grid = np.linspace(0.0, float(t[-1] - t[0]), 60)
        vg = v0 + np.outer(grid, gvec + a) + 0.5 * np.outer(grid**2, j)
        d = -k * np.linalg.norm(vg, axis=1)[:, None] * vg
        dvel = np.vstack(
            [np.zeros(3), np.cumsum(0.5 * (d[1:] + d[:-1]) * np.diff(grid)[:, None], 0)]
        )
        dpos = np.vstack(
            [np.zeros(3), np.cumsum(0.5 * (dvel[1:] + dvel[:-1]) * np.diff(grid)[:, None], 0)]
        )
        tau = grid[-1]
        out[h, 0], out[h, 1] = p0, v0
        out[h, 2] = p0 + v0 * tau + 0.5 * (gvec + a) * tau**2 + j * tau**3 / 6 + dpos[-1]
        out[h, 3] = vg[-1] + dvel[-1]
        out[h, 4], out[h, 5] = a, j
    return out


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
        "a0": np.full((n, 3), np.nan),
        "halves": np.full((2, 6, n, 3), np.nan),
    }
    samples: list[np.ndarray | None] = []
    for i, tid in enumerate(throw_ids):
        tr = tracks.get(tid)
        if tr is None or len(tr) < MIN_SAMPLES or not np.all(np.isfinite(tr)):
            samples.append(None)
            continue
        samples.append(tr)
        t0, p0, v0, a, g_ratio, drop = _whole_track(tr, float(k[i]))
        out["t0"][i], out["p0"][i], out["v0"][i], out["g_ratio"][i] = t0, p0, v0, g_ratio
        out["a0"][i] = a
        out["dropped"][i] = drop
        hv = _halves(tr, float(k[i]), drop)
        if hv is not None:
            out["halves"][:, :, i] = hv
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


def fit_span(fit: TrackFit, idx: np.ndarray) -> np.ndarray:
    """Time from the first kept sample to the last [s] of throws idx."""
    return np.array(
        [
            (tr[-1, 0] - fit.t0[i]) if tr is not None else np.nan
            for i, tr in ((i, fit.samples[i]) for i in idx)
        ]
    )


def _cross_rms(d0: np.ndarray, d1: np.ndarray) -> tuple[float, float]:
    """√ of the mean product of two independent estimates of the same differences (n, 2):
    the RMS of the differences, free of the estimates' scatter on average (0 when the
    product is negative: nothing beyond scatter); and the mean product's z-score (mean over
    its standard error: how clearly there is something beyond scatter)."""
    ok = np.all(np.isfinite(d0), axis=1) & np.all(np.isfinite(d1), axis=1)
    if ok.sum() < 2:
        return float("nan"), float("nan")
    prod = np.sum(d0[ok] * d1[ok], axis=1)
    m = float(np.mean(prod))
    se = float(np.std(prod) / np.sqrt(prod.size))
    return float(np.sqrt(max(m, 0.0))), m / max(se, 1e-300)


Z_SIG = 3.0  # a launch or flight share whose split-half z-score is this high is significant
LANDING_SIG = 1.5  # a landing share above this × the noise floor is significant


def phase_evidence(tracks: dict[str, Any], floor_m: float) -> dict[str, Any]:
    """Which phases the tracks show a gap in.

    Args:
        tracks: `track_phase`'s result.
        floor_m: the noise floor of the landings [m].

    Returns:
        {"shares": {phase: share [m]}, "significant": {phase: bool}, "phase": the phase the
        tracks place the gap in, or None when no share is significant (the tracks cannot
        tell; the first samples after a release are not seen, so a flight effect acting
        right after it can look like a launch gap)}.
    """
    shares = {p: float(tracks.get(f"{p}_m", float("nan"))) for p in ("launch", "flight", "landing")}
    # a flight effect shows as the flight share or as the bend the tracks see directly
    bend = float(tracks.get("bend_m", float("nan")))
    if np.isfinite(bend):
        shares["flight"] = max(shares["flight"], bend) if np.isfinite(shares["flight"]) else bend
    sig = {
        "launch": bool(tracks.get("launch_z", float("nan")) >= Z_SIG),
        "flight": bool(
            tracks.get("flight_z", float("nan")) >= Z_SIG
            or tracks.get("bend_z", float("nan")) >= Z_SIG
        ),
        "landing": bool(shares["landing"] > LANDING_SIG * floor_m),
    }
    if tracks.get("measurement"):
        return {"shares": shares, "significant": sig, "phase": "measurement"}
    cands = [p for p in shares if sig[p] and np.isfinite(shares[p])]
    phase = max(cands, key=lambda p: shares[p]) if cands else None
    return {"shares": shares, "significant": sig, "phase": phase}


def _half_landings(
    prob: GapProblem,
    hv: np.ndarray,
    kk: np.ndarray,
    lz: np.ndarray,
    back: np.ndarray,
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Each half's free flight carried back to the release, and its track's own landing.

    Args:
        prob: the problem.
        hv: the halves' fits of the tracked throws (`TrackFit.halves[:, :, idx]`).
        kk: their drag constants [1/m].
        lz: their landing planes [m].
        back: time from the release to the first kept sample [s], shape (m, 1).

    Returns:
        (per half, the landing [m] of the nominal flight from the release state the half's
        acceleration, linear in time, extrapolates back to; per half, the landing [m] of the
        nominal flight from the half's last state), each shape (m, 2).
    """
    gvec = np.array([0.0, 0.0, -G])
    rel_land, bent_land = [], []
    for h in range(2):
        p0h, v0h, pe, ve, ah, jh = (np.nan_to_num(x) for x in hv[h])
        acc0 = gvec + ah - kk[:, None] * np.linalg.norm(v0h, axis=1)[:, None] * v0h
        v_rel = v0h - acc0 * back + 0.5 * jh * back**2
        p_rel = p0h - v0h * back + 0.5 * acc0 * back**2 - jh * back**3 / 6
        rel_land.append(fly(p_rel, v_rel, kk, lz, step=prob.step).position[:, :2])
        bent_land.append(fly(pe, ve, kk, lz, step=prob.step).position[:, :2])
    return rel_land, bent_land


def _bend(
    prob: GapProblem,
    fit: TrackFit,
    idx: np.ndarray,
    hv: np.ndarray,
    kk: np.ndarray,
    has_h: np.ndarray,
) -> tuple[float, float]:
    """The bend: each half's nominal flight from its first kept state against its own last
    state (no extrapolation: what the tracks see of a flight effect directly).

    Returns:
        (the bend's split-half RMS [m], its z-score) (`_cross_rms`).
    """
    t_span = np.nan_to_num(fit_span(fit, idx))
    bends = []
    for h in range(2):
        p0h, v0h, pe = (np.nan_to_num(x) for x in (hv[h, 0], hv[h, 1], hv[h, 2]))
        nom = sample_path(p0h, v0h, kk, t_span[:, None], step=prob.step)[:, 0, :]
        bends.append(pe - nom)
    return _cross_rms(bends[0][has_h], bends[1][has_h])


def _launch_share(
    prob: GapProblem,
    idx: np.ndarray,
    hv: np.ndarray,
    own: np.ndarray,
    kk: np.ndarray,
    lz: np.ndarray,
    back: np.ndarray,
    rel_land: list[np.ndarray],
) -> tuple[float, float, float]:
    """The launch share on the tracked throws from this launcher with both halves fitted
    (own): the landing difference between the halves' release states and the model's
    launch state under the nominal flight.

    Returns:
        (the share's split-half RMS [m], its z-score, the median launch speed of the first
        half carried back to the release against the model's [%]); NaN when no throw has
        a logged stroke.
    """
    if not own.any():
        return float("nan"), float("nan"), float("nan")
    sub = prob.batch.take(idx[own])
    push, pm, ax = launch_overrides(sub, prob.ee, list(prob.base_effects))
    p_m, v_m = launch_state(sub, prob.ee, push=push, push_mass=pm, axis=ax)
    mod_land = fly(p_m, v_m, kk[own], lz[own], step=prob.step).position[:, :2]
    launch_m, launch_z = _cross_rms(rel_land[0][own] - mod_land, rel_land[1][own] - mod_land)
    v0h = hv[0, 1, own]
    v_back = v0h - (np.array([0.0, 0.0, -G]) * back[own])
    sp_mod = np.linalg.norm(v_m, axis=1)
    speed_pct = float(np.nanmedian(100 * (np.linalg.norm(v_back, axis=1) / sp_mod - 1)))
    return launch_m, launch_z, speed_pct


def _apparent_gravity(
    prob: GapProblem, fit: TrackFit, idx: np.ndarray
) -> tuple[float, float, float, bool]:
    """The tracks' apparent gravity, and whether it shows a measurement gap (off g by more
    than 1.5 % and 4 standard errors, alike for every object).

    Returns:
        (median ratio to g, its standard error, the spread of the objects' medians,
        whether it is a measurement gap).
    """
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
    return g_med, g_se, spread, bool(measurement)


def _evidence(r: dict[str, Any]) -> str:
    """The tracks' evidence in words, from `track_phase`'s figures."""
    speed_pct, launch_m = r["launch_speed_pct"], r["launch_m"]
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
        f"the flight after launch bends {r['bend_m']:.3f} m off the nominal path over the tracks "
        f"(z {r['bend_z']:.1f}; {r['flight_m']:.3f} m at the landing from the release)"
    )
    parts.append(f"logged landings lie {r['landing_m']:.3f} m from the tracks' touchdowns")
    parts.append(
        f"apparent gravity is {r['g_ratio']:.3f} g (±{r['g_ratio_se']:.3f}, spread over "
        f"objects {r['g_ratio_object_spread']:.3f})"
    )
    return "; ".join(parts)


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
    # each half's free flight carried back to the release (its acceleration, linear in time,
    # extrapolated) against the model's launch state there. launch share: the landing
    # difference the two release states make under the nominal flight; flight share: the
    # landing difference between the nominal flight from the release state and the
    # observed flight (the nominal flight from the track's last state). Each is the mean
    # product of the two halves' differences: the tracks' scatter drops out on average.
    hv = fit.halves[:, :, idx]
    t_rel0 = np.where(prob.has_stroke[idx], prob.ee.dt, fit.t0[idx])
    back = np.clip(fit.t0[idx] - t_rel0, 0.0, None)[:, None]
    rel_land, bent_land = _half_landings(prob, hv, kk, lz, back)
    has_h = np.all(np.isfinite(hv[:, 0, :, 0]), axis=0)
    bend_m, bend_z = _bend(prob, fit, idx, hv, kk, has_h)
    # the track's touchdown: nominal flight from the state fitted to its last samples
    end_land = fly(fit.p1[idx], fit.v1[idx], kk, lz, step=prob.step).position[:, :2]
    own = prob.has_stroke[idx] & has_h
    launch_m, launch_z, speed_pct = _launch_share(prob, idx, hv, own, kk, lz, back, rel_land)
    flight_land_m, flight_z = _cross_rms(
        (bent_land[0] - rel_land[0])[has_h], (bent_land[1] - rel_land[1])[has_h]
    )
    # the bend of the path: the nominal flight from the whole-track launch state against
    # the track's last state
    t_rel = (fit.t1[idx] - fit.t0[idx])[:, None]
    p_last = sample_path(fit.p0[idx], fit.v0[idx], kk, t_rel, step=prob.step)[:, 0, :]
    flight_m = _rms(np.linalg.norm(p_last - fit.p1[idx], axis=1))
    landing_m = _rms(np.linalg.norm(prob.observed[idx] - end_land, axis=1))
    g_med, g_se, spread, measurement = _apparent_gravity(prob, fit, idx)
    shares = {"launch": launch_m, "flight": flight_land_m, "landing": landing_m}
    finite = {kk_: v for kk_, v in shares.items() if np.isfinite(v)}
    phase = "measurement" if measurement else max(finite, key=lambda p: finite[p])
    figures = {
        "launch_m": launch_m,
        "flight_m": flight_land_m,
        "flight_path_m": flight_m,
        "landing_m": landing_m,
        "launch_speed_pct": speed_pct,
        "g_ratio": g_med,
        "g_ratio_se": g_se,
        "g_ratio_object_spread": spread,
        "measurement": measurement,
        "launch_z": launch_z,
        "flight_z": flight_z,
        "bend_m": bend_m,
        "bend_z": bend_z,
        "dropped_samples_mean": float(np.mean(fit.dropped[idx])),
    }
    return {"tracked": n_tr, "phase": phase, "evidence": _evidence(figures), **figures}
