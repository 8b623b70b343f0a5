"""Whether the sideways pull the tracks show grows along the flight: a steady wind or not.

A steady wind pushes a flight across its plane from the release on; a gust that rises late
in the flight (an effect outside the vocabulary) pushes only its end. Landings alone can
take the late push for a smaller steady wind. The tracks tell them apart: each track's
first and last third is fitted on its own with a steady horizontal wind besides gravity and
the configured drag (`cell.gap.track_ode`'s "wind" model, without its prior), and the part
of that wind across the track's vertical plane is the air's speed across the flight that
this part shows (a wind w across the flight pulls k·|v|·w sideways: read as air speed, a
steady wind's pull is the same on a slow rise as on a fast descent). Along the flight and vertically a drag or gravity off the configured one pulls
too, and more where the flight is faster, so only the sideways part is compared.

Pooled over the tracks, each track's sideways air speeds are read as one horizontal air
velocity across all their directions (least squares: track i's value is n_i · W, n_i its
sideways unit vector): W at the start, W at the end, and their difference D with its
z-score ‖N D‖ / s (s the scatter of the tracks' differences about N D; under a steady wind
D is zero and z² about χ² with two degrees of freedom). Where z exceeds GROW_Z and the end's
pull is the larger, a verdict naming a steady `wind` is not given: it is `unknown`, the wind
its partial effect, with the sentence of `unsteady_wind`.

A push early in the flight the whole-track launch state takes in, and the landings may then
agree with the model (`none`) while the tracks bend off its flight: where the bend's z-score
(`cell.gap.tracks._bend`) is over BEND_Z, `flight_bends` makes that `unknown` in the flight.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.track_launch import pad_tracks, start_guess
from cell.gap.track_ode import fit_ode

__all__ = ["BEND_Z", "GROW_Z", "flight_bends", "pull_along", "unsteady_wind"]

# [z] the tracks' bend off the model's flight (`cell.gap.tracks._bend`) that a `none` verdict
# may not pass over: still air with the model's drag (an own RK4, 40 and 160 tracks at 60-300
# Hz, 1 mm scatter, 3.5-8 m/s, 6 seeds each) gave z up to 2.0, a gust over the first 30 % of
# each flight medians of 6.7-12.3 (docs/HISTORY.md, branch `bend63`)
BEND_Z = 5.0
GROW_Z = 4.0  # the end's sideways pull differs from the start's by this many standard errors
PART = 1.0 / 3.0  # the share of a track's kept span fitted at its start and at its end
MIN_PART_SAMPLES = 8  # samples a part needs
MIN_PART_S = 0.08  # [s] span a part needs
MIN_SIDE_SPEED = 0.5  # [m/s] a track's horizontal speed that defines its sideways direction
MIN_TRACKS = 8  # tracks compared at least
MAX_TRACKS = 120  # tracks compared at most (evenly chosen)


def _part(kept: np.ndarray, start: bool) -> np.ndarray | None:
    """A track's first (or last) PART of its kept span (None: too short)."""
    t = kept[:, 0]
    span = t[-1] - t[0]
    sel = t <= t[0] + PART * span if start else t >= t[-1] - PART * span
    if sel.sum() < MIN_PART_SAMPLES or PART * span < MIN_PART_S:
        return None
    return kept[sel]


def _winds(parts: list[np.ndarray], k: np.ndarray) -> np.ndarray:
    """The steady horizontal wind [m/s] fitted to each part with gravity and the configured
    drag (`cell.gap.track_ode`, model "wind", without its prior), shape (m, 2)."""
    tau, pos = pad_tracks(parts, np.zeros(len(parts), int))
    fit = fit_ode(tau, pos, k, "wind", start_guess(tau, pos), priors=False)
    return fit.theta[:, 10:12]


def _field(n: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    """The horizontal air velocity W [m/s] whose sideways parts n_i · W best fit w, and the
    RMS [m/s] of the parts N W it explains."""
    sol = np.linalg.lstsq(n, w, rcond=None)[0]
    return sol, float(np.sqrt(np.mean((n @ sol) ** 2)))


def pull_along(
    samples: list[np.ndarray | None], dropped: np.ndarray, k: np.ndarray
) -> dict[str, Any] | None:
    """The tracks' sideways pull at the start and at the end of their flights.

    Args:
        samples: the tracks, (m, 4) arrays t [s], x, y, z [m] (None: none).
        dropped: leading samples dropped per track (disturbed by the release).
        k: drag constants [1/m], shape (n,).

    Returns:
        {"tracks": tracks compared, "start_mps", "end_mps": the horizontal air velocity
        [m/s] the sideways pulls of the tracks' first and last thirds show, "start_rms_mps",
        "end_rms_mps": the RMS over the tracks of its part across each flight [m/s],
        "change_mps": the end's minus the start's, "change_z": its z-score, "grows": the
        change's z over GROW_Z ("grow_z") and the end's pull the larger}, or None with fewer than
        MIN_TRACKS tracks long enough and thrown with a horizontal speed.
    """
    idx = [i for i, tr in enumerate(samples) if tr is not None]
    if len(idx) > MAX_TRACKS:
        idx = [idx[j] for j in np.linspace(0, len(idx) - 1, MAX_TRACKS).astype(int)]
    sides, firsts, lasts, kk = [], [], [], []
    for i in idx:
        tr = samples[i]
        assert tr is not None
        kept = tr[int(dropped[i]) :]
        first, last = _part(kept, True), _part(kept, False)
        chord = kept[-1, 1:3] - kept[0, 1:3]
        h_speed = float(np.linalg.norm(chord)) / max(float(kept[-1, 0] - kept[0, 0]), 1e-9)
        if first is None or last is None or h_speed < MIN_SIDE_SPEED:
            continue
        sides.append(np.array([-chord[1], chord[0]]) / np.linalg.norm(chord))  # ẑ × along
        firsts.append(first)
        lasts.append(last)
        kk.append(float(k[i]))
    if len(sides) < MIN_TRACKS:
        return None
    n = np.array(sides)
    w_s = np.sum(n * _winds(firsts, np.array(kk)), axis=1)
    w_e = np.sum(n * _winds(lasts, np.array(kk)), axis=1)
    ok = np.isfinite(w_s) & np.isfinite(w_e)
    n, w_s, w_e = n[ok], w_s[ok], w_e[ok]
    if len(n) < MIN_TRACKS:
        return None
    start, start_rms = _field(n, w_s)
    end, end_rms = _field(n, w_e)
    change, change_rms = _field(n, w_e - w_s)
    resid = (w_e - w_s) - n @ change
    dof = max(len(n) - int(np.linalg.matrix_rank(n)), 1)
    s = float(np.sqrt(np.sum(resid**2) / dof))
    z = change_rms * np.sqrt(len(n)) / max(s, 1e-12)
    return {
        "tracks": len(n),
        "start_mps": [float(x) for x in start],
        "end_mps": [float(x) for x in end],
        "start_rms_mps": start_rms,
        "end_rms_mps": end_rms,
        "change_mps": [float(x) for x in change],
        "change_z": float(z),
        "grows": bool(z > GROW_Z and end_rms > start_rms),
        "grow_z": GROW_Z,
    }


def unsteady_wind(verdict: list[str], tracks: dict[str, Any] | None) -> dict[str, Any] | None:
    """Why a verdict naming `wind` is no steady wind, where the tracks show its pull growing
    along the flight (`pull_along`'s "grows"), with the figures; None otherwise (no wind
    named, no tracks, or a pull the same at both ends)."""
    pull = (tracks or {}).get("pull_along")
    if "wind" not in verdict or not pull or not pull["grows"]:
        return None
    why = (
        f"the tracks' sideways pull grows along the flight: the first third of "
        f"{pull['tracks']} tracks shows an air speed across the flight of "
        f"{pull['start_rms_mps']:.2f} m/s, the last third {pull['end_rms_mps']:.2f} m/s "
        f"(change z {pull['change_z']:.1f}); a steady wind pulls alike from the release on, "
        f"so this is no steady wind"
    )
    return {"why": why, **pull}


def flight_bends(verdict: list[str], tracks: dict[str, Any] | None) -> dict[str, Any] | None:
    """Why a `none` verdict is `unknown`: the tracks bend off the model's flight with a
    z-score over BEND_Z (a push the whole-track launch state absorbs, as a gust early in the
    flight), with the figures; None otherwise (another verdict, no tracks, a bend within)."""
    bend_z = float((tracks or {}).get("bend_z", float("nan")))
    if verdict != ["none"] or not bend_z > BEND_Z:
        return None
    bend_m = float(tracks["bend_m"])  # type: ignore[index]
    why = (
        f"the tracks bend {bend_m:.3f} m off the model's flight (z {bend_z:.1f}, over "
        f"{BEND_Z:g}): the landings agree with the model from the tracks' launch states, "
        f"but the flight after launch is not the model's, and no effect explains it"
    )
    return {
        "why": why,
        "phase": "flight",
        "bend_m": bend_m,
        "bend_z": bend_z,
        "bend_bound_z": BEND_Z,
    }
