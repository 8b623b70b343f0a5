"""Where the gap lies, from observed tracks: launch, flight, landing or measurement.

For each tracked throw:

* launch state: fitted to the whole track (not its first samples alone), the flight
  integrated with drag, with a free start state and a free constant acceleration
  besides gravity and drag (`cell.gap.track_launch`); the first
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
  scale shows a gravity off by the same factor for every object (on one object a
  spinning ball's lift looks the same: the evidence says so).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.gap.track_check import check_tracks
from cell.gap.track_drag import drag_figures
from cell.gap.track_evidence import evidence, flight_time, frame_turn
from cell.gap.track_gravity import no_flight_under_gravity
from cell.gap.track_gust import pull_along
from cell.gap.track_halves import _state, end_state, halves
from cell.gap.track_launch import whole_track_launch
from cell.gap.track_sideways import scale_or_wind
from cell.gap.tracks_unseen import release_unseen
from cell.model.effects_apply import launch_overrides
from cell.model.flight3d import fly, sample_path
from cell.model.params import G
from cell.model.throw import drag_constant, launch_state

__all__ = ["TrackFit", "fit_tracks", "track_phase", "launch_arrays", "phase_evidence", "_state"]


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
        samples: the track per throw (k, 4) arrays t, x, y, z (None: no usable track).
        theta: the whole track's flight fitted with drag (`cell.gap.track_ode`, model
            "accel"), shape (n, 12).
        rms_m: the RMS residual of that fit [m], shape (n,).
        drag_ratio: the drag that fit finds over the configured one, shape (n,) (1 where
            the track does not identify it).
        unusable: the tracks the fit could not use, [{"throw_id", "why"}].
        mended: what was mended in the tracks used, [{"throw_id", "note"}].
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
    theta: np.ndarray
    rms_m: np.ndarray
    drag_ratio: np.ndarray
    unusable: tuple[dict[str, str], ...] = ()
    mended: tuple[dict[str, str], ...] = ()


MAX_FIT_RMS_M = 0.03  # [m] a track the whole-track fit misses by more is not one free flight
_CACHE: dict[tuple[str, float, bytes], tuple] = {}
_CACHE_MAX = 5000


def _key(tid: str, tr: np.ndarray, k: float) -> tuple[str, float, bytes]:
    return (tid, k, hashlib.sha1(np.ascontiguousarray(tr).tobytes()).digest())


def fit_tracks(throw_ids: list[str], tracks: dict[str, np.ndarray], k: np.ndarray) -> TrackFit:
    """Fit launch and end states and the apparent gravity to each throw's track.

    A track the fit cannot use is named in `unusable` with why (`cell.gap.track_check`);
    none stops the fit. Fits are cached by throw, track and drag constant.

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
        "theta": np.full((n, 12), np.nan),
        "rms_m": np.full(n, np.nan),
        "drag_ratio": np.full(n, np.nan),
    }
    usable, bad, mended = check_tracks(list(throw_ids), tracks)
    samples: list[np.ndarray | None] = [usable.get(t) for t in throw_ids]
    keys = {
        i: _key(throw_ids[i], tr, float(k[i])) for i, tr in enumerate(samples) if tr is not None
    }
    # this call's fits held here: a cache cleared as they are fitted (more tracks) loses none
    fits = {i: _CACHE[key] for i, key in keys.items() if key in _CACHE}
    todo = [i for i in keys if i not in fits]
    if todo:
        wl = whole_track_launch([samples[i] for i in todo], np.asarray(k, float)[todo])  # type: ignore[misc]
        for j, i in enumerate(todo):
            tr = samples[i]
            assert tr is not None
            drop = int(wl["dropped"][j])
            hv = halves(tr, float(k[i]), drop)
            end = end_state(tr, float(k[i]))
            row = {key: wl[key][j] for key in ("t0", "p0", "v0", "a0", "g_ratio", "dropped",
                                               "theta", "rms_m", "drag_ratio")}  # fmt: skip
            fits[i] = (row, hv, end)
        if len(_CACHE) + len(todo) > _CACHE_MAX:
            _CACHE.clear()
        _CACHE.update((keys[i], fits[i]) for i in todo[:_CACHE_MAX])
    for i, tr in enumerate(samples):
        if tr is None:
            continue
        row, hv, end = fits[i]
        if not row["rms_m"] <= MAX_FIT_RMS_M:
            why = (
                f"not one free flight: the whole-track fit with drag misses it by "
                f"{row['rms_m'] * 1000:.0f} mm RMS (a bounce, a catch, two objects?)"
            )
            bad.append({"throw_id": str(throw_ids[i]), "why": why})
            samples[i] = None
            continue
        not_down = no_flight_under_gravity(row)
        if not_down:
            bad.append({"throw_id": str(throw_ids[i]), "why": not_down})
            samples[i] = None
            continue
        for key, val in row.items():
            out[key][i] = val
        if hv is not None:
            out["halves"][:, :, i] = hv
        out["t1"][i], out["p1"][i], out["v1"][i], _ = end
    return TrackFit(samples=samples, unusable=tuple(bad), mended=tuple(mended), **out)


def launch_arrays(fit: TrackFit) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
) -> tuple[float, float, float, int, bool, bool]:
    """The tracks' apparent gravity, and whether it shows a measurement gap: off g by more
    than 1.5 % and 4 standard errors, alike for every object. On one object a gravity off
    g may as well be that object's own flight (a spinning ball's lift), which only another
    object flying under the same tracker would tell from the tracker's scale: it is still
    called a measurement gap (a tracks-only launcher of one object off in scale is common,
    and refused it was named a drag), and the evidence says the two look alike.

    Returns:
        (median ratio to g, its standard error, the spread of the objects' medians, the
        number of objects compared, whether it is off g, whether it is a measurement gap).
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
    off = bool(np.isfinite(g_med) and abs(g_med - 1) > max(0.015, 4 * g_se))
    measurement = off and spread < 0.3 * abs(g_med - 1)
    return g_med, g_se, spread, len(per_obj), off, bool(measurement)


def _sideways(
    prob: GapProblem, fit: TrackFit, idx: np.ndarray, k: np.ndarray
) -> dict[str, Any] | None:
    """A tracker scale or a wind, on the tracked throws of another launcher."""
    other = idx[~prob.has_stroke[idx]]
    return scale_or_wind(
        [fit.samples[i] for i in other], fit.dropped[other], fit.theta[other],
        fit.rms_m[other], k[other],
    )  # fmt: skip


def track_phase(prob: GapProblem, fit: TrackFit) -> dict[str, Any]:
    """Each phase's share of the landing miss on the tracked throws, and the phase it points to.

    Returns:
        {"phase", "evidence", "launch_m", "flight_m", "landing_m", "g_ratio", "tracked",
        "unusable": [{"throw_id", "why"}], "mended": [{"throw_id", "note"}], "sideways":
        `cell.gap.track_sideways.scale_or_wind` on the throws of another launcher or None,
        "pull_along": `cell.gap.track_gust.pull_along` on every tracked throw or None}.
        "phase" is None when the tracks cannot place the gap (too few usable tracks, no
        share computable).
    """
    ok = np.isfinite(fit.t0) & np.isfinite(fit.t1)
    n_tr = int(ok.sum())
    named = {"unusable": list(fit.unusable), "mended": list(fit.mended)}
    if n_tr < 5:
        why = f"{n_tr} usable track{'s' if n_tr != 1 else ''} (5 needed)"
        if fit.unusable:
            why += f"; {len(fit.unusable)} unusable, e.g. {fit.unusable[0]['throw_id']}: "
            why += fit.unusable[0]["why"]
        return {"phase": None, "evidence": why, "tracked": n_tr, **named}
    b = prob.batch
    k = drag_constant(b.shape, b.mass, b.size)
    idx = np.flatnonzero(ok)
    kk, lz = k[idx], b.land_z[idx]
    # launch and flight shares from the halves (module docstring)
    hv = fit.halves[:, :, idx]
    t_rel0 = np.where(prob.has_stroke[idx], prob.ee.dt, fit.t0[idx])
    back = np.clip(fit.t0[idx] - t_rel0, 0.0, None)[:, None]
    rel_land, bent_land = _half_landings(prob, hv, kk, lz, back)
    has_h = np.all(np.isfinite(hv[:, 0, :, 0]), axis=0)
    bend_m, bend_z = _bend(prob, fit, idx, hv, kk, has_h)
    # the track's touchdown: nominal flight from the state fitted to its last samples
    end_fl = fly(fit.p1[idx], fit.v1[idx], kk, lz, t0=fit.t1[idx], step=prob.step)
    end_land = end_fl.position[:, :2]
    tof_ms, tof_z = flight_time(prob, fit, idx, kk, lz, end_fl.t)
    own = prob.has_stroke[idx] & has_h
    launch_m, launch_z, speed_pct = _launch_share(prob, idx, hv, own, kk, lz, back, rel_land)
    flight_land_m, flight_z = _cross_rms(
        (bent_land[0] - rel_land[0])[has_h], (bent_land[1] - rel_land[1])[has_h]
    )
    # the path's bend: nominal flight from the whole-track launch state vs the track's last one
    t_rel = (fit.t1[idx] - fit.t0[idx])[:, None]
    p_last = sample_path(fit.p0[idx], fit.v0[idx], kk, t_rel, step=prob.step)[:, 0, :]
    flight_m = _rms(np.linalg.norm(p_last - fit.p1[idx], axis=1))
    landing_m = _rms(np.linalg.norm(prob.observed[idx] - end_land, axis=1))
    g_med, g_se, spread, n_obj, g_off, measurement = _apparent_gravity(prob, fit, idx)
    shares = {"launch": launch_m, "flight": flight_land_m, "landing": landing_m}
    finite = {kk_: v for kk_, v in shares.items() if np.isfinite(v)}
    top = max(finite, key=lambda p: finite[p]) if finite else None
    phase = "measurement" if measurement else top
    side = _sideways(prob, fit, idx, k)
    figures = {
        "launch_m": launch_m,
        "flight_m": flight_land_m,
        "flight_path_m": flight_m,
        "landing_m": landing_m,
        "launch_speed_pct": speed_pct,
        "g_ratio": g_med,
        "g_ratio_se": g_se,
        "g_ratio_object_spread": spread,
        "g_ratio_objects": n_obj,
        "g_ratio_off": g_off,
        "measurement": measurement,
        "launch_z": launch_z,
        "flight_z": flight_z,
        "bend_m": bend_m,
        "bend_z": bend_z,
        "flight_time_ms": tof_ms,
        "flight_time_z": tof_z,
        "dropped_samples_mean": float(np.mean(fit.dropped[idx])),
        "track_fit_rms_m": float(np.median(fit.rms_m[idx])),
        **drag_figures(np.asarray(prob.table.text("object_id"))[idx], fit.drag_ratio[idx]),
        "sideways": side,
        "pull_along": pull_along([fit.samples[i] for i in idx], fit.dropped[idx], kk),
        "frame": frame_turn(prob.observed[idx], end_land),  # the log's frame and the tracks'
        "unseen": release_unseen(back, fit_span(fit, idx)),  # tracks begun mid-flight
        "_bend_parts": (idx, hv, kk, has_h, fit_span(fit, idx)),  # `cell.gap.track_member`
    }
    ev = evidence(figures) if finite else "no phase share could be computed from the tracks"
    return {"tracked": n_tr, "phase": phase, "evidence": ev, **figures, **named}
