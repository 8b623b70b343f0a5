"""Whether a track's whole-track fit is a flight under gravity in a z-up frame
(`cell.gap.tracks.fit_tracks` sets aside a track that is not, with why)."""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.model.params import G

__all__ = ["DOWN_COS", "DOWN_MIN_G", "GRAVITY_MAX_G", "GRAVITY_MIN_G", "no_flight_under_gravity"]

DOWN_COS = 0.5  # the gravity a track's fit finds points within 60° of -z, if z is up
DOWN_MIN_G = 0.5  # ... judged where it is this many g or more (a frame's up is then clear)
# [g] the apparent gravity a free flight's whole-track fit finds (the size of (0, 0, -G) plus
# its free constant acceleration) lies within these: the shipped real tracks 0.98-1.29 g,
# the check world's tracked campaigns 0.67 g (a tracker's scale 0.7) to 9.5 g (a drone's
# downwash of 35 m/s on light objects); outside, the track is no flight under gravity as
# given (a straight line, positions or times in other units, a frame's drift)
GRAVITY_MIN_G = 0.5
GRAVITY_MAX_G = 20.0


def no_flight_under_gravity(row: dict[str, Any]) -> str | None:
    """Why a track's whole-track fit is no flight under gravity in a z-up frame (None: it
    may be one). The gravity it finds is (0, 0, -G) plus its free constant acceleration,
    drag apart; not judged where the span is too short to tell gravity (`g_ratio` NaN).
    Its size is under GRAVITY_MIN_G or over GRAVITY_MAX_G g (a straight line, other units),
    or, being DOWN_MIN_G g or more, it points over 60° away from -z (a frame with y up)."""
    if not np.isfinite(row["g_ratio"]):
        return None  # too short a span to tell gravity
    gvec = np.asarray(row["a0"], float) + np.array([0.0, 0.0, -G])
    size = float(np.linalg.norm(gvec))
    if not GRAVITY_MIN_G <= size / G <= GRAVITY_MAX_G:
        g = size / G
        what = "a straight line, no fall" if g < GRAVITY_MIN_G else "a fall far faster than g"
        return (
            f"no flight under gravity: the fit with drag finds an apparent gravity of {g:.2g} g "
            f"({g * G:.3g} m/s², a free flight's is within {GRAVITY_MIN_G:g}-{GRAVITY_MAX_G:g} "
            f"g): {what}; are x_m, y_m, z_m in metres, t_s in seconds, and is z up?"
        )
    if size < DOWN_MIN_G * G or -gvec[2] >= DOWN_COS * size:
        return None
    axis = int(np.argmax(np.abs(gvec)))
    towards = f"{'-' if gvec[axis] < 0 else '+'}{'xyz'[axis]}"
    # pulled up along z: a frame with z down, or a track that runs on past a landing
    lands = ", and does the track stop before the object lands" if towards == "+z" else ""
    return (
        f"no descent under gravity along z: the fit with drag finds gravity towards {towards} "
        f"({size:.1f} m/s²); is z up{lands}?"
    )
