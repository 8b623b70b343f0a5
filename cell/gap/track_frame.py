"""The tracks and the log in two frames: the logged landings a turn of the tracks' touchdowns.

A motion-capture system writes positions in its own frame. Where its frame is turned about
the vertical against the log's (a tracker set up facing another wall), every track is a
fine free flight, its apparent gravity g, and its touchdown lies metres from the logged
landing: the diagnosis places the gap in the landing and the proposal reaches for terms
that bend every throw alike. The figure that tells a frame from an effect is a rigid
motion of the plane: the logged landings L_i against the tracks' touchdowns T_i,

    L_i ≈ R(θ) T_i + t    (or, with one axis reversed, R(θ) M T_i + t, M = diag(1, −1)),

by least squares (Kabsch/Procrustes in two dimensions, no scale: a tracker's scale is an
effect of the vocabulary). `frame_turn` gives θ, whether the map reverses an axis, and the
RMS distance before and after; `turned` is set where the map takes the distance to within
`TURN_SHARE` of what it was and θ is at least `MIN_TURN_DEG` (or an axis reversed). It is
a figure and a sentence of the evidence (`cell.gap.track_evidence`), not a rule: the
verdict is what the diagnosis finds.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["MIN_TURN_DEG", "TURN_SHARE", "frame_turn", "frame_sentence"]

MIN_TURN_DEG = 2.0  # [deg] a turn of the frames smaller than this is not said
TURN_SHARE = 0.2  # the map leaves at most this share of the distance before it
MIN_POINTS = 5  # landings compared at least


def _fit(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The rotation R (2, 2) and shift t (2,) taking points a (m, 2) nearest b, and the RMS
    distance after."""
    ca, cb = a.mean(axis=0), b.mean(axis=0)
    h = (a - ca).T @ (b - cb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    rot = vt.T @ np.diag([1.0, d]) @ u.T
    t = cb - rot @ ca
    rms = float(np.sqrt(np.mean(np.sum((a @ rot.T + t - b) ** 2, axis=1))))
    return rot, t, rms


def frame_turn(logged: np.ndarray, touchdown: np.ndarray) -> dict[str, Any]:
    """The rigid map of the plane from the tracks' touchdowns (m, 2) [m] to the logged
    landings (m, 2) [m] (rows with a non-finite value left out): `turn_deg` (about z,
    counter-clockwise from the tracks' frame to the log's), `mirrored` (an axis reversed),
    `shift_m` (x, y), `before_m` and `after_m` (RMS distance), `turned`; {} with fewer
    than `MIN_POINTS` landings."""
    ok = np.all(np.isfinite(logged), axis=1) & np.all(np.isfinite(touchdown), axis=1)
    a, b = np.asarray(touchdown, float)[ok], np.asarray(logged, float)[ok]
    if len(a) < MIN_POINTS:
        return {}
    before = float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))
    flip = np.array([1.0, -1.0])
    plain, mirror = _fit(a, b), _fit(a * flip, b)
    mirrored = mirror[2] < 0.5 * plain[2]
    rot, t, after = mirror if mirrored else plain
    turn = float(np.degrees(np.arctan2(rot[1, 0], rot[0, 0])))
    turned = bool(after <= TURN_SHARE * before and (abs(turn) >= MIN_TURN_DEG or mirrored))
    return {"turn_deg": turn, "mirrored": bool(mirrored), "shift_m": [float(t[0]), float(t[1])],
            "before_m": before, "after_m": after, "turned": turned}  # fmt: skip


def frame_sentence(f: dict[str, Any]) -> str:
    """The evidence's sentence where the frames differ ("" otherwise)."""
    if not f.get("turned"):
        return ""
    how = f"turned by {f['turn_deg']:.1f}° about z"
    if f["mirrored"]:
        how = "with their y axis reversed" + (
            f" and {how}" if abs(f["turn_deg"]) >= MIN_TURN_DEG else ""
        )
    return (
        f"the logged landings are the tracks' touchdowns {how} and shifted by "
        f"({f['shift_m'][0]:.3f}, {f['shift_m'][1]:.3f}) m ({f['before_m']:.3f} m apart, "
        f"{f['after_m']:.3f} m after that map): are the tracks and the log in one frame "
        "(world W, z up)?"
    )
