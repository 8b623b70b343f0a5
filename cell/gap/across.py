"""A tracking scale beside a landing effect, judged on the landing misses across the
impact velocity (`cell.gap.select`).

A scale s about the tracker's origin moves a landing at xy by (s − 1) · xy; a slide after
the landing (any law of the bounce) moves it along the impact velocity only. Along the
velocity the two are nearly alike on throws that fly away from the origin (a scale of
2 % and a slide a little longer give the same landings), so a scale beside a slide cuts
little of the held-out miss: the slide had taken the scale's part along the flight, at a
1/μ too long. Across the velocity a scale is all that moves the landings in proportion to
their distance from the origin (`across_scale`):

* the scale is refused where the misses across show none, within ACROSS_Z standard
  errors of 1 (`across_refusal`);
* a scale joining beside a landing effect whose held-out cut falls short of MIN_CUT
  (`cell.gap.select`) joins all the same where the misses across show it, off 1 by
  ACROSS_JOIN_Z standard errors, and the set's held-out cut is above zero
  (`across_joins`).
"""

from __future__ import annotations

import numpy as np

from cell.gap.problem import GapProblem
from cell.model.effects import Effect, TrackingScale

__all__ = ["ACROSS_Z", "across_scale", "across_refusal", "scale_beside_landing"]

# a tracking scale beside a landing effect: the scale the misses across the impact velocity
# show must be off 1 by this many standard errors (the two-sided 95 % level)
ACROSS_Z = 1.96


def across_scale(prob: GapProblem, effects: tuple[Effect, ...] | list[Effect]
                 ) -> tuple[float, float, int]:  # fmt: skip
    """The tracker scale the landing misses show across the model's horizontal impact
    velocity, the other effects (all of `effects` but a tracking scale) at their sizes.

    A scale s about the tracker's origin moves a landing at xy by (s − 1) · xy; a slide
    after the landing (any law of the bounce) moves it along the impact velocity only.
    Across that velocity (unit vector n per throw) the miss m is (s − 1) · (xy · n) plus
    scatter, so s − 1 is the least-squares slope of m · n on xy · n.

    Returns:
        (the scale [-], its standard error [-] from the scatter about the slope, the
        throws used: those with a finite miss and a horizontal impact velocity).
    """
    idx = np.arange(len(prob))
    others = [e for e in effects if not isinstance(e, TrackingScale)]
    land = prob.landing(idx, others)
    miss = prob.observed - land.xy
    vh = land.impact_velocity[:, :2]
    speed = np.linalg.norm(vh, axis=1)
    ok = np.all(np.isfinite(miss), axis=1) & np.all(np.isfinite(land.xy), axis=1) & (speed > 1e-6)
    if ok.sum() < 3:
        return float("nan"), float("nan"), int(ok.sum())
    n = np.c_[-vh[ok, 1], vh[ok, 0]] / speed[ok, None]
    m = np.sum(miss[ok] * n, axis=1)
    r = np.sum(land.xy[ok] * n, axis=1)
    rr = float(np.sum(r * r))
    if rr <= 0.0:
        return float("nan"), float("nan"), int(ok.sum())
    k = float(np.sum(m * r)) / rr
    se = float(np.sqrt(np.sum((m - k * r) ** 2) / (len(m) - 1) / rr))
    return 1.0 + k, se, int(ok.sum())


def scale_beside_landing(effects: tuple[Effect, ...] | list[Effect]) -> bool:
    """Whether a set holds a tracking scale beside a landing effect (the sets whose scale
    the misses across the impact velocity judge, `across_refusal`)."""
    return any(isinstance(e, TrackingScale) for e in effects) and any(
        e.phase == "landing" for e in effects
    )


def across_refusal(prob: GapProblem, effects: tuple[Effect, ...] | list[Effect]) -> str | None:
    """Why a tracking scale in a set beside a landing effect may not join (None: it may, or
    the set has no such pair): the landing misses across the impact velocity
    (`across_scale`) show no scale, within ACROSS_Z standard errors of 1."""
    if not scale_beside_landing(effects):
        return None
    s, se, _ = across_scale(prob, effects)
    if not np.isfinite(s) or not np.isfinite(se) or abs(s - 1.0) >= ACROSS_Z * se:
        return None
    return (
        f"beside a landing effect, the landing misses across the impact velocity show a "
        f"scale of {s:.4f} ± {se:.4f}: none"
    )
