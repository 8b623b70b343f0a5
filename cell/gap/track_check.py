"""Which tracks the diagnosis can use, and why not the others.

A track is a (k, 4) array of t [s], x, y, z [m] (`cell.log.csvio.read_tracks_csv`, or
built in code). Real tracks come unsorted, with repeated time stamps, lost samples
(NaN rows), gaps, a single sample, or no flight at all; none of them stops the
diagnosis: each is mended where it can be (sorted; repeated and non-finite samples
dropped, and said so) or set aside with the reason.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from cell.yamltree import on_screen, unseen_problem

__all__ = [
    "MIN_SAMPLES",
    "MIN_SPAN_S",
    "CheckedTrack",
    "check_track",
    "check_tracks",
    "clock_step",
]

MIN_SAMPLES = 8  # a whole-track fit frees up to 9 parameters from 3 coordinates per sample
MIN_SPAN_S = 0.1  # [s] a shorter track does not show gravity
MIN_TRAVEL_M = 0.02  # [m] a track that moves less is not a flight
MAX_GAP_SHARE = 0.5  # a gap longer than this share of the span leaves the flight unseen
MAX_SAMPLES = 200_000  # samples per track read at most
UP_CURVE_G = 0.3  # a free flight's height never bends upward (drag stays under gravity)
APART_FACTOR = 3.0  # samples of one stamp this many stamp-to-stamp steps apart: two objects


@dataclass(frozen=True)
class CheckedTrack:
    """A track as the diagnosis uses it, or why it cannot.

    Attributes:
        samples: the (k, 4) samples kept, sorted by time (None: unusable).
        why: why the track cannot be used (None: usable).
        notes: what was mended (sorted, samples dropped), in words.
    """

    samples: np.ndarray | None
    why: str | None
    notes: tuple[str, ...] = ()


def check_track(raw: object) -> CheckedTrack:
    """Check and mend one track.

    Args:
        raw: the track, anything array-like of shape (k, 4): t [s], x, y, z [m].

    Returns:
        The track kept (sorted, non-finite and repeated samples dropped) or why not.
    """
    try:
        arr = np.asarray(raw, dtype=float)
    except (TypeError, ValueError):
        return CheckedTrack(None, "not a table of numbers (t_s, x_m, y_m, z_m)")
    if arr.size == 0:
        return CheckedTrack(None, "no samples")
    if arr.ndim == 1 and arr.shape[0] == 4:
        return CheckedTrack(None, "a single sample (a flight needs at least 8)")
    if arr.ndim != 2 or arr.shape[1] != 4:
        return CheckedTrack(None, f"samples of shape {arr.shape}, not (k, 4): t_s, x_m, y_m, z_m")
    if arr.shape[0] > MAX_SAMPLES:
        return CheckedTrack(None, f"{arr.shape[0]} samples: more than {MAX_SAMPLES} in one track")
    notes = []
    fin = np.all(np.isfinite(arr), axis=1)
    if not fin.all():
        notes.append(f"{int((~fin).sum())} of {arr.shape[0]} samples not finite (dropped)")
        arr = arr[fin]
    if arr.shape[0] and np.any(np.diff(arr[:, 0]) < 0):
        # a sample written again whole (a logger replaying its buffer) is a repeat, which
        # the sort and the repeats' drop mend; only the others can show a clock's step
        _, first = np.unique(arr, axis=0, return_index=True)
        step = clock_step(arr[np.sort(first), 0])
        if step:
            return CheckedTrack(None, step, tuple(notes))
        notes.append("samples not in time order (sorted)")
        arr = arr[np.argsort(arr[:, 0], kind="stable")]
    n_rep = 0
    if arr.shape[0] > 1:
        rep = np.r_[False, np.diff(arr[:, 0]) <= 0]
        two = _two_places(arr, rep)
        if two:
            return CheckedTrack(None, two, tuple(notes))
        if rep.any():
            n_rep = int(rep.sum())
            notes.append(f"{n_rep} repeated time stamps (later ones dropped)")
            arr = arr[~rep]
    why = _unusable(arr)
    if why and n_rep:  # a time column copied down, or written at a coarse resolution
        n = arr.shape[0] + n_rep
        why = (
            f"{why}, once {n_rep} of its {n} samples were dropped for repeating a time "
            f"stamp ({arr.shape[0]} distinct t_s from {arr[0, 0]:g} s): is t_s filled in "
            "for every sample, to the millisecond?"
        )
    return CheckedTrack(None if why else arr, why, tuple(notes))


def clock_step(t: np.ndarray) -> str | None:
    """Why a track whose time goes back cannot be mended by sorting (None: it can).

    Samples written out of order (shuffled, reversed, chunks swapped) sort into one
    flight. A track whose time, in the order written, runs forward, steps back and runs
    forward again over the same times (a tracker's clock stepped back, two flights under
    one id) does not: sorting would interleave two runs of samples that each hold a
    flight's stretch, or shift one against the other. Two runs in time order of at least
    `MIN_SAMPLES` samples each, over overlapping times, are that.

    Args:
        t: the finite samples' times [s] in the order written.
    """
    starts = np.r_[0, np.flatnonzero(np.diff(t) < 0) + 1]
    ends = np.r_[starts[1:], t.size]
    runs = [(int(a), int(b)) for a, b in zip(starts, ends, strict=True) if b - a >= MIN_SAMPLES]
    for i, (a, b) in enumerate(runs):
        for c, d in runs[i + 1 :]:
            if max(t[a], t[c]) < min(t[b - 1], t[d - 1]):
                return (
                    f"time goes back: from {t[c - 1]:.4g} s to {t[c]:.4g} s at sample {c + 1} "
                    f"of {t.size}, and the {d - c} samples from there overlap in time the "
                    f"{b - a} before (a tracker's clock stepped back, or two flights under one "
                    "throw_id?); sorting would mix them: give each flight its own throw_id, "
                    "its t_s from its release"
                )
    return None


def _two_places(arr: np.ndarray, rep: np.ndarray) -> str | None:
    """Why a track whose repeated time stamps hold samples far apart is no one object's
    (None: it may be). `arr` (k, 4) sorted by time, `rep` marks each sample whose stamp
    repeats the one before.

    A repeated stamp is mended by keeping its first sample: a sample written again, or a
    time written at a coarse resolution, whose samples lie about as far apart as the
    track moves from stamp to stamp. Samples of one stamp a median over
    `APART_FACTOR` times that step and `MIN_TRAVEL_M` apart are two places at one time:
    two objects tracked under one throw_id, which keeping the first would mix.
    """
    if not rep.any():
        return None
    first = np.maximum.accumulate(np.where(rep, 0, np.arange(rep.size)))  # each stamp's first
    apart = np.linalg.norm(arr[rep, 1:4] - arr[first[rep], 1:4], axis=1)
    kept = arr[~rep, 1:4]
    if kept.shape[0] < 2:
        return None
    step = float(np.median(np.linalg.norm(np.diff(kept, axis=0), axis=1)))
    far = float(np.median(apart))
    if far <= max(APART_FACTOR * step, MIN_TRAVEL_M):
        return None
    t = float(arr[rep, 0][int(np.argmax(apart))])
    return (
        f"two places at one time: {int(rep.sum())} of its {rep.size} samples repeat a time "
        f"stamp {far:.3f} m (median) from the sample first written at it ({float(apart.max()):.3f} m "
        f"at t = {t:.4g} s), where the track moves {step:.3f} m from one stamp to the next "
        "(two objects tracked under one throw_id?): give each object's flight its own throw_id"
    )


def _unusable(arr: np.ndarray) -> str | None:
    """Why the sorted finite samples arr (k, 4) cannot carry a flight (None: they can)."""
    k = arr.shape[0]
    if k == 0:
        return "no finite samples"
    if k < MIN_SAMPLES:
        return f"too short: {k} sample{'s' if k != 1 else ''} (a flight needs {MIN_SAMPLES})"
    span = float(arr[-1, 0] - arr[0, 0])
    if span < MIN_SPAN_S:
        return f"too short: {span * 1000:.0f} ms of flight (gravity needs {MIN_SPAN_S:.1f} s)"
    travel = float(np.max(np.ptp(arr[:, 1:4], axis=0)))
    if travel < MIN_TRAVEL_M:
        return f"not a flight: the object moves {travel * 1000:.0f} mm over the track"
    gap = float(np.max(np.diff(arr[:, 0])))
    if gap > MAX_GAP_SHARE * span:
        return f"a gap of {gap:.2f} s in a track of {span:.2f} s: the flight is not seen"
    t = arr[:, 0] - arr[0, 0]
    z_acc = 2.0 * float(np.polynomial.polynomial.polyfit(t, arr[:, 3], 2)[2])
    if z_acc > UP_CURVE_G * 9.80665:
        return (
            f"no descent under gravity: the height's path bends upward ({z_acc:+.1f} m/s²); "
            "is z up, and is this a free flight?"
        )
    return None


def check_tracks(
    throw_ids: list[str], tracks: Mapping[str, object] | None
) -> tuple[dict[str, np.ndarray], list[dict[str, str]], list[dict[str, str]]]:
    """Check every track given.

    Args:
        throw_ids: the throws of the log.
        tracks: {throw_id: samples} as read.

    Returns:
        (the usable tracks by throw id, the unusable ones [{"throw_id", "why"}], what was
        mended [{"throw_id", "note"}]); a track of a throw not in the log is unusable.
    """
    usable: dict[str, np.ndarray] = {}
    bad: list[dict[str, str]] = []
    mended: list[dict[str, str]] = []
    known = set(throw_ids)
    for tid, raw in (tracks or {}).items():
        if tid not in known:
            why = "no throw with this id in the throw log"
            unseen = unseen_problem(str(tid))  # a character that shows nothing, said
            if unseen.startswith("holds"):
                why += f": {on_screen(str(tid))!r} {unseen}"
            bad.append({"throw_id": on_screen(str(tid)), "why": why})
            continue
        c = check_track(raw)
        mended.extend({"throw_id": str(tid), "note": nt} for nt in c.notes)
        if c.samples is None:
            bad.append({"throw_id": str(tid), "why": str(c.why)})
        else:
            usable[tid] = c.samples
    return usable, bad, mended
