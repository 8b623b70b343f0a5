"""The drag the tracks measure per object, and a drag factor they contradict.

The whole-track fit (`cell.gap.track_launch`) frees the drag of each track beside a
constant acceleration, with a weak prior on it (`cell.gap.track_ode`): over an object's
tracks the median ratio to the configured drag moves toward the object's true C_d factor
but only part of the way (the constant acceleration takes the rest: a C_d × 1.6 on a
43 mm ball launched at 3.5-6 m/s shows as 1.13 ± 0.03). The direction is what the ratio
tells: a `drag_scale` whose factor for an object is off 1 by more than DRAG_AGREE while
the tracks' ratio is within DRAG_Z standard errors of 1, or off 1 the other way, is one
the tracks contradict: it stands in for something else the landings show (a lift that
lengthens the fast throws, say), not for the object's drag.

The ratio's standard error is its scatter over the tracks, not how much of a factor the
fit can see: on flights where the constant acceleration takes most of the drag's change
(near-vertical throws, a heavy ball) the ratio stays near 1 under a real factor (the
thirteenth lab round's W8: C_d × 1.8 on every object of throws at 72-84°, a golf ball's
tracks 1.02 ± 0.03, a brick's 1.03 ± 0.05; docs/HISTORY.md, branch `lab67`). So the
tracks' halves are read too (`halves_share`, where the tracks' evidence carries
`_bend_parts`): each half of an object's tracks flown from its first state with the factor
and without it (`cell.gap.track_member.halves_deviation`), the tracks' own deviation from
the nominal flight projected on the factor's (one half's on the other's, so that the
tracker's scatter cancels): β = Σ seen·dev / Σ dev·dev, 1 where the tracks bend as the
factor does, 0 where they fly as configured. An object whose halves show β above DRAG_Z
standard errors and above BETA_MIN does show the factor's direction, whatever its ratio.
BETA_MIN: under a real factor W8's objects showed β 0.39-0.91, `test_gap_track_lift`'s drag
world's ball 0.93; where the drag is as configured a ball's halves showed 0.036 ± 0.008 (a
bias of the halves' fit or of the lab's integrator), and the lift world's balls 0.01-0.03.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effect_base import Effect

__all__ = [
    "drag_figures",
    "object_drag_ratios",
    "drag_refusal",
    "DRAG_Z",
    "DRAG_AGREE",
    "MIN_TRACKS",
    "BETA_MIN",
    "halves_share",
]

DRAG_Z = 3.0  # standard errors of the tracks' per-object drag ratio (SCALE_AGREE's level)
DRAG_AGREE = 0.10  # [-] a factor within this of 1 is never refused
MIN_TRACKS = 5  # an object's tracks needed to judge its drag
BETA_MIN = 0.2  # [-] the least share of a factor's bend the tracks' halves must show


def object_drag_ratios(object_ids: np.ndarray, ratio: np.ndarray) -> dict[str, list[float]]:
    """Per object (id), [the median drag ratio of its tracks, its standard error (1.2533 ×
    the standard deviation over √n), the tracks used] (objects with MIN_TRACKS finite
    ratios or more)."""
    out: dict[str, list[float]] = {}
    ids = np.asarray(object_ids).astype(str)
    r = np.asarray(ratio, float)
    for o in np.unique(ids):
        v = r[(ids == o) & np.isfinite(r)]
        if v.size >= MIN_TRACKS:
            se = 1.2533 * float(np.std(v, ddof=1)) / np.sqrt(v.size)
            out[str(o)] = [float(np.median(v)), se, float(v.size)]
    return out


def drag_figures(object_ids: np.ndarray, ratio: np.ndarray) -> dict[str, Any]:
    """The tracks' figures of the drag: "drag_ratio", the median over the tracks, and
    "drag_ratio_objects" (`object_drag_ratios`)."""
    return {
        "drag_ratio": float(np.median(ratio)),
        "drag_ratio_objects": object_drag_ratios(object_ids, ratio),
    }


def drag_refusal(
    prob: GapProblem,
    effects: tuple[Effect, ...] | list[Effect],
    tracks: dict[str, Any] | None,
) -> str | None:
    """Why a `drag_scale` in a set may not join (None: it may, or none is in the set, or
    the tracks measure no object's drag): for an object, its mean factor over the
    object's throws is off 1 by more than DRAG_AGREE, and the tracks' drag ratio
    (`object_drag_ratios`) is within DRAG_Z standard errors of 1 or off 1 the other way.

    Args:
        prob: the problem (its throws and their object ids).
        effects: the set's fitted effects.
        tracks: the tracks' evidence (`cell.gap.tracks.track_phase`) or None.
    """
    per_obj = (tracks or {}).get("drag_ratio_objects") or {}
    drag = [e for e in effects if e.name == "drag_scale"]
    if not per_obj or not drag:
        return None
    ids = np.asarray(prob.table.text("object_id")).astype(str)
    f_all: Any = getattr(drag[0].per_throw(prob.batch), "factor", 1.0)
    factor = np.broadcast_to(np.asarray(f_all, dtype=float), (len(ids),))
    halves = None
    for o, (r, se, _) in per_obj.items():
        f = factor[ids == o]
        if f.size == 0:
            continue
        fo = float(np.mean(f))
        seen = abs(r - 1.0) > DRAG_Z * se and (r - 1.0) * (fo - 1.0) > 0
        if abs(fo - 1.0) > DRAG_AGREE and not seen:
            if halves is None and (tracks or {}).get("_bend_parts") is not None:
                halves = halves_share(prob, drag[0], tracks["_bend_parts"])  # type: ignore[index]
            beta, b_se = (halves or {}).get(o, (float("nan"), float("nan")))
            if beta > max(DRAG_Z * b_se, BETA_MIN):  # the halves bend as the factor does
                continue
            return (
                f"factor {fo:.2f} for {o} disagrees with the drag its tracks show, "
                f"{r:.3f} ± {se:.3f} × the configured"
                + (f" (their halves bend {beta:.2f} ± {b_se:.2f} of its way)" if halves else "")
            )
    return None


def halves_share(prob: GapProblem, drag: Effect, parts: tuple[Any, ...]
                 ) -> dict[str, tuple[float, float]]:  # fmt: skip
    """Per object (id): (β, its standard error), the share of the drag factor's own bend
    over the halves of the object's tracks that the tracks' halves show (module docstring):
    β = Σ s / Σ c over its tracks, s the mean of each half's seen deviation dotted with the
    other half's claimed one, c the two claimed ones' product; the error from the scatter of
    s − β·c. Objects with fewer than MIN_TRACKS tracks with both halves are left out."""
    from cell.gap.track_member import halves_deviation

    dev, seen, ok = halves_deviation(prob, [drag], parts)
    s = 0.5 * (np.sum(seen[0] * dev[1], axis=1) + np.sum(seen[1] * dev[0], axis=1))
    c = np.sum(dev[0] * dev[1], axis=1)
    ids = np.asarray(prob.table.text("object_id")).astype(str)[parts[0]]
    out: dict[str, tuple[float, float]] = {}
    for o in np.unique(ids):
        m = ok & (ids == o)
        if m.sum() < MIN_TRACKS or not c[m].sum() > 0:
            continue
        beta = float(s[m].sum() / c[m].sum())
        se = float(np.std(s[m] - beta * c[m]) * np.sqrt(m.sum()) / c[m].sum())
        out[str(o)] = (beta, se)
    return out
