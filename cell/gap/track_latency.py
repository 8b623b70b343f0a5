"""A tracker's time offset against the release, fitted with the launch state from the tracks.

A track's `t_s` is the time since the release command (docs/throw_log.md); on the band's
throws (a stroke logged) the model releases the object at the push's end, t = Δt
(`EndEffectorParams.dt`), at the launch position `launch_state` gives: the carriage's end
stop, which no launch effect of the vocabulary moves. A tracker whose stamps lie τ late
shows the object there at t = Δt + τ. Each tracked throw's whole-track state is carried
from its first sample back to Δt (gravity and the configured drag at that state, a
second-order step over the few ms between), and its offset is the time along its
velocity from there to the model's release point:

    τ_i = (p_model − p_track(Δt)) · v / |v|²  [s]

The log's offset is their median, its standard error 1.2533 σ/√n. It is named (the
evidence says it, and the launch speed from tracks at Δt + τ beside the one at Δt) where
it is OFFSET_Z standard errors from 0 and at least MIN_OFFSET_S: a speed from the tracks
read at the wrong time is off by the flight's deceleration over τ (a tracker 15 ms late:
3.7 % above the model on the band's throws), which is a latency, not a launch gap.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.gap.track_evidence import evidence
from cell.model.effects_apply import launch_overrides
from cell.model.params import G
from cell.model.throw import drag_constant, launch_state

__all__ = ["MIN_OFFSET_S", "OFFSET_Z", "add_offset", "time_offset"]

MIN_OFFSET_S = 0.002  # [s] an offset below this is no latency worth naming
OFFSET_Z = 4.0  # standard errors from 0 for an offset to be named
MIN_RELEASES = 5  # tracked throws of the band, at least


def _carried(p0: np.ndarray, v0: np.ndarray, k: np.ndarray, dt: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The state (p, v) [m, m/s] dt [s] (n,) from (p0, v0) under gravity and drag k [1/m]
    (the acceleration at the start, held: its change over a few ms is below a µm)."""
    a = -(k * np.linalg.norm(v0, axis=1))[:, None] * v0
    a[:, 2] -= G
    d = dt[:, None]
    return p0 + v0 * d + 0.5 * a * d * d, v0 + a * d


def time_offset(prob: GapProblem, t0: np.ndarray, p0: np.ndarray, v0: np.ndarray
                ) -> dict[str, Any] | None:  # fmt: skip
    """The tracker's time offset (module docstring) from the tracks' whole-track states
    (t0 [s] (n,), p0 [m] and v0 [m/s] (n, 3), NaN where untracked).

    Returns:
        {"offset_ms", "offset_se_ms", "offset_z", "named", "releases", "speed_pct_at_offset"
        (the launch speed from tracks at Δt + τ against the model's [%])}, or None where
        fewer than MIN_RELEASES tracked throws have a stroke.
    """
    ok = np.isfinite(t0) & np.all(np.isfinite(p0), axis=1) & np.all(np.isfinite(v0), axis=1)
    idx = np.flatnonzero(ok & prob.has_stroke)
    if idx.size < MIN_RELEASES:
        return None
    sub = prob.batch.take(idx)
    push, pm, ax = launch_overrides(sub, prob.ee, list(prob.base_effects))
    p_m, v_m = launch_state(sub, prob.ee, push=push, push_mass=pm, axis=ax)
    k = drag_constant(sub.shape, sub.mass, sub.size)
    p_t, v_t = _carried(p0[idx], v0[idx], k, prob.ee.dt - t0[idx])
    tau = np.sum((p_m - p_t) * v_t, axis=1) / np.maximum(np.sum(v_t * v_t, axis=1), 1e-9)
    med = float(np.median(tau))
    se = 1.2533 * float(np.std(tau)) / np.sqrt(tau.size)
    z = med / max(se, 1e-12)
    _, v_at = _carried(p0[idx], v0[idx], k, prob.ee.dt + med - t0[idx])
    pct = 100.0 * (np.linalg.norm(v_at, axis=1) / np.linalg.norm(v_m, axis=1) - 1.0)
    return {
        "offset_ms": 1000.0 * med,
        "offset_se_ms": 1000.0 * se,
        "offset_z": z,
        "named": bool(abs(z) >= OFFSET_Z and abs(med) >= MIN_OFFSET_S),
        "releases": int(idx.size),
        "speed_pct_at_offset": float(np.median(pct)),
    }


def add_offset(tp: dict[str, Any], prob: GapProblem, t0: np.ndarray, p0: np.ndarray,
               v0: np.ndarray) -> None:  # fmt: skip
    """`track_phase`'s result `tp` with the tracker's time offset (`time_offset`) as
    "time_offset" (where the tracks gave figures), its evidence said again where named."""
    if "launch_m" not in tp:
        return
    tp["time_offset"] = off = time_offset(prob, t0, p0, v0)
    if off is not None and off["named"]:
        tp["evidence"] = evidence(tp)
