"""More of the proposal's library (`cell.gap.propose`): a lift across the velocity, terms of
one object, the phases the tracks allow, and flagged rows that are one object's gap.

- **A lift across the velocity** (flight): an acceleration θ·|v|²·n̂, n̂ the unit vector
  across v in v's vertical plane, upwards (a Magnus lift of a ball spinning about a
  horizontal axis across its flight, a wing's lift); as `lift across v [1/m] = k · |v|² n̂`,
  and as a lift coefficient, `lift coefficient C_L [-] = k`, whose acceleration is
  θ · ½ρA/m · |v|² n̂ with A the object's reference area of the drag (`drag_area`): one
  C_L for objects of different A/m. A vertical flight has no such plane: nil there.
- **Terms of one object**: the library's constant speed error, lift coefficient and landing
  shift ∝ v, and as a second set those with the speed error over the log's order (a drift
  of one object: a bag that leaks), acting on one object's throws only (`· [object = X]`).
  They are tried
  object by object, greedily (`object_law`): the law with the object's terms added is kept
  where its held-out score (`cell.gap.propose.TERM_PENALTY` per term) with one more term's
  penalty for the object chosen is below the law without them; at most MAX_OBJECTS objects;
  a law whose lift coefficient exceeds LIFT_CL_MAX in size is not kept.
- **The phases the tracks allow**: where tracks place the gap in a phase (a significant
  share, `cell.gap.tracks.phase_evidence`), the library holds that phase's terms and those
  of the other phases the tracks find significant only; a measurement gap (a tracker's
  scale) or tracks that cannot tell leave the whole library.
- **Flagged rows that are one object's gap**: rows flagged as outliers that concentrate in
  one object beyond chance (`one_object_rows`: a binomial tail below OBJECT_ALPHA over the
  objects) are that object's gap, not outliers: the proposal is fitted with them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.stats import binom

from cell.model.objects import drag_area
from cell.model.params import aero_factor_kg_per_m

if TYPE_CHECKING:
    from cell.gap.problem import GapProblem
    from cell.model.throw import ThrowBatch

__all__ = [
    "LIFT_CL",
    "LIFT_CL_MAX",
    "allowed_phases",
    "lift_terms",
    "object_columns",
    "one_object_rows",
    "up_across",
]

LIFT_CL = "lift coefficient C_L [-] = k"
# |C_L| above this is no lift an object's spin gives (a spinning ball's stays under about
# 0.6); a law of one object that needs more is not kept (it stands for something else)
LIFT_CL_MAX = 1.5
MAX_OBJECTS = 3  # objects given terms of their own in one law
MIN_OBJECT_THROWS = 5  # an object with fewer throws has no terms of its own
OBJECT_ALPHA = 0.001  # the chance, over the objects, of calling a log's scatter one object's
# the library's terms that also come for one object (their columns masked to its throws):
# a speed error growing over the log on one object's throws is its mass drifting (a bag
# that leaks, `speed error [share] = k · order · [object = X]`)
OBJECT_SOURCES = ("speed error [share] = k", LIFT_CL, "landing shift [s] = k · v_h")
# tried as a second set of the object's terms, with OBJECT_SOURCES (one more column in the
# same set changes which terms the bounds leave to the first: `s:scale+hop` lost its law)
OBJECT_DRIFT = "speed error [share] = k · order"


def up_across(v: np.ndarray) -> np.ndarray:
    """Unit vectors (m, 3) across v (m, 3) in v's vertical plane, upwards: v × (v × ẑ)
    turned up, (−v_z v_x, −v_z v_y, v_h²) / (|v| v_h); nil where v is vertical or nil."""
    vh2 = v[:, 0] ** 2 + v[:, 1] ** 2
    n = np.c_[-v[:, 2] * v[:, 0], -v[:, 2] * v[:, 1], vh2]
    size = np.sqrt(vh2) * np.linalg.norm(v, axis=1)
    return np.where(size[:, None] > 1e-12, n / np.where(size > 1e-12, size, 1.0)[:, None], 0.0)


def lift_terms(b: ThrowBatch, h: float) -> list[tuple[str, Callable[..., np.ndarray]]]:
    """The lift terms' names and their accelerations at θ = h [m/s² per (m/s)²]."""
    # ½ρA/m [1/m]: the acceleration of a unit lift coefficient per |v|²
    per_cl = aero_factor_kg_per_m(1.0, drag_area(b.shape, b.size)) / np.asarray(b.mass, float)

    def plain(p: np.ndarray, v: np.ndarray, i: np.ndarray) -> np.ndarray:
        return h * np.sum(v * v, axis=1)[:, None] * up_across(v)

    def coeff(p: np.ndarray, v: np.ndarray, i: np.ndarray) -> np.ndarray:
        return (h * per_cl[i] * np.sum(v * v, axis=1))[:, None] * up_across(v)

    return [("lift across v [1/m] = k · |v|² n̂", plain), (LIFT_CL, coeff)]


def allowed_phases(tracks: dict[str, Any] | None, floor_m: float) -> set[str] | None:
    """The phases whose terms the library holds: those the tracks find significant, where
    they place the gap in the launch, the flight or the landing; None (all) otherwise."""
    if not tracks or not tracks.get("phase"):
        return None
    from cell.gap.tracks import phase_evidence

    ev = phase_evidence(tracks, floor_m)
    if ev["phase"] not in ("launch", "flight", "landing"):
        return None
    return {ev["phase"]} | {p for p, s in ev["significant"].items() if s}


def object_columns(prob: GapProblem, terms: list[dict[str, Any]], a_all: np.ndarray
                   ) -> list[tuple[str, list[dict[str, Any]], np.ndarray]]:  # fmt: skip
    """Each object's own terms (its name, the terms, their columns (2n, q)): the library's
    OBJECT_SOURCES columns (rows throw-major x, y) on that object's throws only, and again
    with OBJECT_DRIFT's (two sets of one object, tried alike). None where the log has one
    object."""
    oid = np.asarray(prob.table.text("object_id"))
    names = list(dict.fromkeys(oid.tolist()))
    src = [j for j, t in enumerate(terms) if t["term"] in OBJECT_SOURCES]
    drift = [j for j, t in enumerate(terms) if t["term"] == OBJECT_DRIFT]
    if len(names) < 2 or not src:
        return []
    out = []
    for o in names:
        on = oid == o
        if on.sum() < MIN_OBJECT_THROWS:
            continue
        rows = np.repeat(on, 2)[:, None]
        for js in (src, src + drift) if drift else (src,):
            ts = [{"phase": terms[j]["phase"], "term": f"{terms[j]['term']} · [object = {o}]"}
                  for j in js]  # fmt: skip
            out.append((o, ts, np.where(rows, a_all[:, js], 0.0)))
    return out


def one_object_rows(prob: GapProblem, flagged: np.ndarray) -> np.ndarray:
    """The flagged rows of the objects whose share of the flags is beyond chance: k of an
    object's m throws flagged, K of the log's n, P(Binomial(m, K/n) ≥ k) below
    OBJECT_ALPHA / the number of objects."""
    flagged = np.asarray(flagged, bool)
    out = np.zeros(flagged.size, bool)
    n, big_k = flagged.size, int(flagged.sum())
    if big_k == 0 or big_k == n:
        return out
    oid = np.asarray(prob.table.text("object_id"))
    names = list(dict.fromkeys(oid.tolist()))
    if len(names) < 2:
        return out
    for o in names:
        on = oid == o
        k = int((flagged & on).sum())
        if k >= 2 and binom.sf(k - 1, int(on.sum()), big_k / n) < OBJECT_ALPHA / len(names):
            out |= flagged & on
    return out
