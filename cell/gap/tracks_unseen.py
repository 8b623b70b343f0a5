"""Tracks first seen well after the release: said, since the launch is then not seen.

A tracker that picks a throw up mid-flight (a camera whose view begins past the launcher)
gives tracks whose first kept sample comes a good part of the flight after the release.
The launch figures (`cell.gap.tracks`: the launch speed from tracks, the launch share) are
then the halves' fits carried back over that time by a Taylor series of their acceleration,
not measured: on a log with no effect, tracks begun 40 % into the flight read the launch
speed 1.1 % slow and a launch share of 0.034 m (the evidence said both, as if seen). A
figure, not a rule: where the median time from the release to the first kept sample is
`UNSEEN_SHARE` or more of the median time the tracks cover, the evidence says so.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["UNSEEN_SHARE", "release_unseen"]

# the release counts as unseen where the tracks begin this share of their own span after it
# (a tracker's lock and the leading samples off the fit cost a few ms: a few %)
UNSEEN_SHARE = 0.25


def release_unseen(back_s: np.ndarray, span_s: np.ndarray) -> dict[str, Any]:
    """The tracks' unseen start: {"release_to_first_s": the median time [s] from the release
    to the first kept sample, "unseen_share": that over the median tracked span,
    "sentence": what the evidence says ("" where the release is seen)}."""
    back = np.asarray(back_s, float).ravel()
    span = np.asarray(span_s, float).ravel()
    ok = np.isfinite(back) & np.isfinite(span)
    if not ok.any():
        return {"release_to_first_s": float("nan"), "unseen_share": float("nan"), "sentence": ""}
    b, s = float(np.median(back[ok])), float(np.median(span[ok]))
    share = b / s if s > 0 else float("inf")
    sentence = ""
    if share >= UNSEEN_SHARE:
        sentence = (
            f"the tracks begin {b:.3f} s (median) after the release, {share:.2f} of the time "
            "they cover: the release is not seen, and the launch speed and launch share above "
            "are carried back over that time, not measured"
        )
    return {"release_to_first_s": b, "unseen_share": share, "sentence": sentence}
