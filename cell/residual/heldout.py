"""Whether a learned residual beats the physics model alone on throws it did not train on.

The round-robin of thesis Table 5.1 (`cell.residual.evaluate`) gives, for every held-out
throw, its squared landing error with the model alone and with the learner's residual (the
learner trained on the other objects: the procedure `cell learn` saves, judged on objects it
never saw). A residual is worth adding to the plan only when it lowers that error by more
than the spread of the evidence, not merely on this draw of objects.

The unit of the evidence is the held-out *object*: the residual is a function of the object
(its mass, shape and grip), so the throws of one object share its correction's error, and a
test over throws would count one object's luck 20 or 40 times. The decision is a paired
cluster bootstrap: the held-out objects are drawn with replacement (`RESAMPLES` draws,
seeded), each draw's ratio RMSE with / RMSE without is computed over the drawn objects' throws
(both on the same throws: paired), and the residual beats the physics model when the upper
end of the 95 % percentile interval of that ratio is below 1. With few objects (a
round-robin needs four) the interval is coarse and on the narrow side; it is the evidence
there is.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import InvalidParameter

__all__ = ["LEVEL", "RESAMPLES", "HeldoutJudgement", "judge_heldout", "judge_summary"]

RESAMPLES = 2000  # bootstrap draws of the held-out objects
LEVEL = 0.95  # the interval's coverage (two-sided, percentile)


@dataclass(frozen=True)
class HeldoutJudgement:
    """A learner's residual against the physics model alone on the round-robin's held-out
    throws.

    Attributes:
        learner: the learner judged.
        n_throws: held-out throws (every usable throw, each held out once).
        n_objects: held-out objects (the bootstrap's unit).
        rmse_physics_m: landing RMSE of those throws with the model alone [m].
        rmse_residual_m: the same with the residual [m].
        ratio_interval: the 95 % bootstrap interval of rmse_residual / rmse_physics [-].
        resamples: bootstrap draws.
        seed: the draws' seed.
    """

    learner: str
    n_throws: int
    n_objects: int
    rmse_physics_m: float
    rmse_residual_m: float
    ratio_interval: tuple[float, float]
    resamples: int
    seed: int

    @property
    def ratio(self) -> float:
        """rmse_residual / rmse_physics on all held-out throws [-] (1 where both are 0)."""
        if self.rmse_physics_m == 0:
            return 1.0 if self.rmse_residual_m == 0 else float("inf")
        return self.rmse_residual_m / self.rmse_physics_m

    @property
    def beats_physics(self) -> bool:
        """The interval lies below 1: the residual lowers the held-out error beyond its
        spread over objects."""
        return self.ratio_interval[1] < 1.0

    def as_dict(self) -> dict[str, Any]:
        """The JSON form (`cell learn --json`, the model file's metadata)."""
        return {
            "learner": self.learner,
            "n_throws": self.n_throws,
            "n_objects": self.n_objects,
            "rmse_physics_m": self.rmse_physics_m,
            "rmse_residual_m": self.rmse_residual_m,
            "rmse_ratio": self.ratio,
            "rmse_ratio_interval_95": list(self.ratio_interval),
            "beats_physics": self.beats_physics,
            "test": (
                f"paired bootstrap over the held-out objects ({self.resamples} draws, seed "
                f"{self.seed}): beats when the 95 % interval of the RMSE ratio is below 1"
            ),
        }

    def text(self) -> str:
        """One line: the errors with and without, the interval, the verdict."""
        return (
            f"held-out landing RMSE ({self.n_throws} throws of {self.n_objects} objects, "
            f"each object unseen by its fold's {self.learner}): physics alone "
            f"{self.rmse_physics_m:.4f} m, with the residual {self.rmse_residual_m:.4f} m "
            f"(ratio {self.ratio:.3f}, 95 % interval {self.ratio_interval[0]:.3f}-"
            f"{self.ratio_interval[1]:.3f} over the objects): "
            + (
                "the residual beats the physics model alone"
                if self.beats_physics
                else "the residual does not beat the physics model alone"
            )
        )


def judge_heldout(
    learner: str,
    objects: np.ndarray,
    sq_err_physics_m2: np.ndarray,
    sq_err_residual_m2: np.ndarray,
    *,
    resamples: int = RESAMPLES,
    seed: int = 0,
) -> HeldoutJudgement:
    """Judge a residual on held-out throws (module docstring).

    Args:
        learner: the learner's name.
        objects: object id of each held-out throw, shape (n,).
        sq_err_physics_m2: each throw's squared landing error with the model alone [m²].
        sq_err_residual_m2: the same with the residual [m²].
        resamples: bootstrap draws.
        seed: their seed.

    Raises:
        InvalidParameter: mismatched or empty arrays, a non-finite error, fewer than two
            objects.
    """
    ids = np.asarray(objects)
    before = np.asarray(sq_err_physics_m2, float)
    after = np.asarray(sq_err_residual_m2, float)
    if not (ids.shape == before.shape == after.shape) or ids.ndim != 1 or ids.size == 0:
        raise InvalidParameter(
            f"held-out errors: objects {ids.shape}, physics {before.shape} and residual "
            f"{after.shape} must be one value per throw, at least one throw"
        )
    if not (np.all(np.isfinite(before)) and np.all(np.isfinite(after))):
        raise InvalidParameter("held-out errors must be finite")
    names, idx = np.unique(ids, return_inverse=True)
    if names.size < 2:
        raise InvalidParameter(
            f"judging a residual needs at least 2 held-out objects; got {names.size}"
        )
    if resamples < 1:
        raise InvalidParameter(f"resamples={resamples} must be ≥ 1")
    sum_b = np.bincount(idx, weights=before, minlength=names.size)
    sum_a = np.bincount(idx, weights=after, minlength=names.size)
    rng = np.random.default_rng(seed)
    draw = rng.integers(0, names.size, size=(resamples, names.size))
    counts = np.zeros((resamples, names.size))
    np.add.at(counts, (np.arange(resamples)[:, None], draw), 1.0)
    b, a = counts @ sum_b, counts @ sum_a
    ratio = np.sqrt(a / np.where(b > 0, b, np.nan))
    tail = 100 * (1 - LEVEL) / 2
    lo, hi = np.nanpercentile(ratio, [tail, 100 - tail])
    return HeldoutJudgement(
        learner=learner,
        n_throws=int(ids.size),
        n_objects=int(names.size),
        rmse_physics_m=float(np.sqrt(before.mean())),
        rmse_residual_m=float(np.sqrt(after.mean())),
        ratio_interval=(float(lo), float(hi)),
        resamples=resamples,
        seed=seed,
    )


def judge_summary(
    learner: str, summary: Any, groups: np.ndarray, *, seed: int = 0
) -> HeldoutJudgement:
    """`judge_heldout` on a learner's round-robin (`cell.residual.evaluate.LearnerSummary`):
    every fold's held-out throws, `groups` the object id of every row of the log."""
    rows = np.concatenate([f.test_rows for f in summary.folds])
    return judge_heldout(
        learner,
        np.asarray(groups)[rows],
        np.concatenate([f.sq_err_before_m2 for f in summary.folds]),
        np.concatenate([f.sq_err_after_m2 for f in summary.folds]),
        seed=seed,
    )
