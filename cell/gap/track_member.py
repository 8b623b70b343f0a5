"""A flight effect whose own bend over the tracks the tracks' bend refutes.

The tracks' bend (`cell.gap.tracks._bend`) is what a flight effect does where the tracks
see it: each half of a track (its alternate samples), flown by the nominal model from its
first state over the track's span, against its own last position; the two halves' product
measures the bend's square free of the tracker's scatter. A flight effect fitted to the
landings bends the same flights by its own amount: flown from the same states over the same
spans with the effect and without it, the product of the two halves' differences is the
bend it claims. Where the tracks show no bend (their z-score under `Z_SIG`, 3) and the
effect's claim exceeds the tracks' mean product by more than `BEND_Z` of its standard
errors, the tracks refute the effect: it stands for something the landings show
and the flight does not (a step in the floor named `spin` at −78.6 rad/s, whose far throws
would bend by centimetres, against tracks bending 0.0011 m at z 0.5: the eleventh lab
round's E4, docs/HISTORY.md). `magnus63`'s drag factor the tracks' drag contradicts is the
same rule for one parameter (`cell.gap.track_drag`). Tracks that bend are left alone:
there a flight effect is right and its law may bend them more or less than they do (the
own table's rotor jet, z 7.5, was named `downwash` by its column law, whose claim exceeds
the jet's bend; refused, the first pass was `unknown` and 60 rows were left out).

The tracks' evidence carries what the rule reads under `_bend_parts` (the tracked throws'
indices, their halves' fits, drag constants, which have both halves, and spans); the report
leaves it out (`cell.gap.run`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.gap.track_gust import BEND_Z
from cell.gap.tracks import Z_SIG
from cell.model.effect_base import Effect
from cell.model.effects_apply import flight_accel
from cell.model.flight3d import sample_path

__all__ = ["halves_deviation", "member_bend", "bend_refusal"]


def halves_deviation(prob: GapProblem, effects: tuple[Effect, ...] | list[Effect],
                     parts: tuple[Any, ...]) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray]:  # fmt: skip
    """Over the tracked throws (`parts[0]`), each half's flight from its first state with the
    effects less the nominal one, at the half's end (two arrays (m, 3) [m]); the tracks'
    halves' ends less the nominal one (two (m, 3) [m]); which throws have both, finite (m,)."""
    idx, hv, kk, has_h, t_span = parts
    sub = prob.batch.take(idx)
    rpm = None if prob.rotor_rpm is None else np.asarray(prob.rotor_rpm)[idx]
    acc = flight_accel(sub, list(prob.base_effects) + list(effects), rpm)
    t = np.nan_to_num(t_span)[:, None]
    dev, seen = [], []
    for h in range(2):
        p0h, v0h, pe = (np.nan_to_num(x) for x in (hv[h, 0], hv[h, 1], hv[h, 2]))
        nom = sample_path(p0h, v0h, kk, t, step=prob.step)[:, 0, :]
        own = sample_path(p0h, v0h, kk, t, accel=acc, step=prob.step)[:, 0, :]
        dev.append(own - nom)
        seen.append(pe - nom)
    ok = has_h & np.all(np.isfinite(dev[0]) & np.isfinite(dev[1]), axis=1)
    ok &= np.all(np.isfinite(seen[0]) & np.isfinite(seen[1]), axis=1)
    return dev, seen, ok


def member_bend(prob: GapProblem, effects: tuple[Effect, ...] | list[Effect],
                parts: tuple[Any, ...]) -> tuple[float, float, float]:  # fmt: skip
    """(the effects' own bend² over the tracks (the halves' mean product) [m²], the
    tracks' mean product [m²] and its standard error [m²])."""
    dev, seen, ok = halves_deviation(prob, effects, parts)
    if ok.sum() < 2:
        return float("nan"), float("nan"), float("nan")
    claim = float(np.mean(np.sum(dev[0][ok] * dev[1][ok], axis=1)))
    prod = np.sum(seen[0][ok] * seen[1][ok], axis=1)
    return claim, float(np.mean(prod)), float(np.std(prod) / np.sqrt(prod.size))


def bend_refusal(prob: GapProblem, effects: tuple[Effect, ...] | list[Effect],
                 tracks: dict[str, Any] | None) -> str | None:  # fmt: skip
    """Why a set with a flight effect may not join (None: it may, or it has none, or the
    tracks give no bend): the tracks show no bend (their z-score under
    `cell.gap.tracks.Z_SIG`) and the set's own bend over them exceeds theirs by more than
    BEND_Z standard errors."""
    tr = tracks or {}
    parts, flight = tr.get("_bend_parts"), [e for e in effects if e.phase == "flight"]
    if parts is None or not flight or not float(tr.get("bend_z", np.inf)) < Z_SIG:
        return None  # tracks that bend, or may: a flight effect's law is judged elsewhere
    claim, seen, se = member_bend(prob, effects, parts)
    if not (np.isfinite(claim) and se > 0):
        return None
    z = (claim - seen) / se
    if z <= BEND_Z:
        return None
    return (
        f"it bends the tracked flights {np.sqrt(max(claim, 0.0)):.4f} m where the tracks bend "
        f"{np.sqrt(max(seen, 0.0)):.4f} m ({z:.1f} standard errors over, `BEND_Z` {BEND_Z:g})"
    )
