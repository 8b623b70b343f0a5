"""The tracks' evidence in figures and words: the time of flight against the nominal
flight's, and the sentence `cell gap` prints under `where`."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from cell.gap.track_frame import frame_sentence, frame_turn
from cell.model.flight3d import fly

if TYPE_CHECKING:
    from cell.gap.problem import GapProblem
    from cell.gap.tracks import TrackFit

__all__ = ["evidence", "flight_time", "frame_turn"]


def flight_time(
    prob: GapProblem,
    fit: TrackFit,
    idx: np.ndarray,
    kk: np.ndarray,
    lz: np.ndarray,
    t_end: np.ndarray,
) -> tuple[float, float]:
    """The time of flight the tracks show against the nominal flight's from their launch
    states: where the landing points carry no signal (a vertical flight), a flight effect
    or a gravity off still shows in when the object comes down.

    Args:
        t_end: the tracks' touchdown times [s] (the nominal flight from their last
            samples), shape (m,).

    Returns:
        (median of touchdown minus nominal touchdown [ms], its z-score).
    """
    nom = fly(fit.p0[idx], fit.v0[idx], kk, lz, t0=fit.t0[idx], step=prob.step).t
    d = (t_end - nom) * 1000.0
    d = d[np.isfinite(d)]
    if d.size < 3:
        return float("nan"), float("nan")
    med = float(np.median(d))
    se = 1.2533 * float(np.std(d)) / np.sqrt(d.size)
    return med, med / max(se, 1e-9)


def evidence(r: dict[str, Any]) -> str:
    """The tracks' evidence in words, from `track_phase`'s figures."""
    speed_pct, launch_m = r["launch_speed_pct"], r["launch_m"]
    parts = []
    if np.isfinite(speed_pct):
        parts.append(
            f"launch speed from tracks is {abs(speed_pct):.1f}% "
            f"{'below' if speed_pct < 0 else 'above'} the model"
        )
    off = r.get("time_offset")
    if off and off["named"]:  # the speed read at the wrong time: a latency
        at = off["speed_pct_at_offset"]
        parts.append(
            f"the tracks' time stamps lie {abs(off['offset_ms']):.1f} ms "
            f"(±{off['offset_se_ms']:.2g}) {'late' if off['offset_ms'] > 0 else 'early'} "
            f"against the model's release (a tracker's latency); read at that offset the "
            f"launch speed from tracks is {abs(at):.1f}% {'below' if at < 0 else 'above'} "
            "the model"
        )
    parts.append(
        f"launch accounts for {launch_m:.3f} m of landing miss"
        if np.isfinite(launch_m)
        else "no launch comparison (no stroke logged)"
    )
    if (r.get("unseen") or {}).get("sentence"):  # tracks begun mid-flight (`tracks_unseen`)
        parts.append(r["unseen"]["sentence"])
    parts.append(
        f"the flight after launch bends {r['bend_m']:.3f} m off the nominal path over the tracks "
        f"(z {r['bend_z']:.1f}; {r['flight_m']:.3f} m at the landing from the release)"
    )
    if np.isfinite(r.get("flight_time_ms", float("nan"))):
        parts.append(
            f"the tracks reach the landing plane {abs(r['flight_time_ms']):.1f} ms "
            f"{'later' if r['flight_time_ms'] > 0 else 'earlier'} than the nominal flight from "
            f"their launch states (z {r['flight_time_z']:.1f})"
        )
    parts.append(f"logged landings lie {r['landing_m']:.3f} m from the tracks' touchdowns")
    if frame := frame_sentence(r.get("frame") or {}):
        parts.append(frame)
    if r.get("g_ratio_objects", 2) >= 2:
        spread = f"spread over objects {r['g_ratio_object_spread']:.3f}"
    elif r.get("g_ratio_off"):  # nothing to compare it with: it may be the object's own
        spread = "one object: a tracker's scale and the object's own lift look alike"
    else:
        spread = "one object"
    parts.append(f"apparent gravity is {r['g_ratio']:.3f} g (±{r['g_ratio_se']:.3f}, {spread})")
    if np.isfinite(r.get("drag_ratio", float("nan"))):
        parts.append(
            f"the whole tracks, integrated with drag, fit within {r['track_fit_rms_m'] * 1000:.1f}"
            f" mm with a drag {r['drag_ratio']:.2f} × the configured C_d's"
        )
    side = r.get("sideways")
    if side:
        parts.append(
            f"over the whole tracks a tracker scale gains χ² {side['scale_chi2_gain']:.0f} and "
            f"a wind {side['wind_chi2_gain']:.0f} (noise alone {side['noise_chi2']:.0f}): "
            + {
                "scale": "the tracks bend nothing sideways, a scale",
                "wind": "the tracks bend sideways, a wind",
                "either": "either",
                "neither": "neither",
            }[side["prefers"]]  # fmt: skip
        )
    return "; ".join(parts)
