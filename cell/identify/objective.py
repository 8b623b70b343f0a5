"""The objective identification minimises, evaluated whole: the start against the end.

Each stage and the truncated-SVD step minimise the whitened landing residuals (weights from
the documented noise at the model's own predicted reach, `ThrowData.weigh`) plus the
Gaussian priors' rows: (z − anchor)/prior_rel for η_ee's stage-1 vector, (x − 1)/σ for each
free object factor (σ the cross-validated width; a factor of width 0 is held at 1). The
weights are renewed between stages and the priors' widths chosen between passes, so no
single solve sees the whole path: `compare` scores the start and the end under the same
weights and widths (those of the final step), and the fit keeps the start when it ends
worse on them. The landing RMSE is not this objective: under the documented noise a short
throw (σ near the 5 mm floor) weighs up to hundreds of times a far one, so a fit may lower
the objective and raise the unweighted RMSE.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from cell.identify.problem import ThrowData, ee_to_vector
from cell.model.params import EndEffectorParams

__all__ = ["Comparison", "compare", "keep_better", "objective"]

log = logging.getLogger(__name__)


def objective(
    data: ThrowData,
    ee: EndEffectorParams,
    factors: np.ndarray,
    anchor: np.ndarray,
    prior_rel: float,
    prior_std: np.ndarray,
) -> float:
    """The sum of squares identification minimises at (ee, factors), under the weights
    `data` holds: whitened residuals, η_ee's prior rows, the free factors' prior rows
    (a held factor away from 1 costs infinity: the fit cannot reach it)."""
    batch = data.batch_with(data.objects_from_factors(factors))
    cost = float(np.sum(data.wres(batch, ee) ** 2))
    cost += float(np.sum(((ee_to_vector(ee) - anchor) / prior_rel) ** 2))
    free = prior_std > 0
    if np.any(factors[~free] != 1.0):
        return float("inf")
    return cost + float(np.sum(((factors[free] - 1.0) / prior_std[free]) ** 2))


@dataclass(frozen=True)
class Comparison:
    """The start and the end of a fit on one objective.

    Attributes:
        start: the objective at the start parameters.
        end: the objective at the fitted ones.
        chi2_by_object: per object id, (throws, whitened squared residual a throw at the
            parameters returned; the noise model expects 2, x and y).
    """

    start: float
    end: float
    chi2_by_object: dict[str, tuple[int, float]]

    @property
    def start_better(self) -> bool:
        """The fit ended worse on its objective than where it began."""
        return self.start < self.end


def compare(
    data: ThrowData,
    start: EndEffectorParams,
    ee: EndEffectorParams,
    factors: np.ndarray,
    anchor: np.ndarray,
    prior_rel: float,
    prior_std: np.ndarray,
) -> Comparison:
    """`objective` at the start (η_ee `start`, every factor 1) and at (ee, factors), under
    the weights `data` holds, and each object's share at the end."""
    ones = np.ones_like(factors)
    batch = data.batch_with(data.objects_from_factors(factors))
    per = np.sum(data.wres(batch, ee) ** 2, axis=1)
    by_object = {
        oid: (int(np.sum(data.obj == j)), float(np.mean(per[data.obj == j])))
        for j, oid in enumerate(data.object_ids)
        if np.any(data.obj == j)
    }
    return Comparison(
        start=objective(data, start, ones, anchor, prior_rel, prior_std),
        end=objective(data, ee, factors, anchor, prior_rel, prior_std),
        chi2_by_object=by_object,
    )


def keep_better(
    data: ThrowData,
    start: EndEffectorParams,
    ee: EndEffectorParams,
    factors: np.ndarray,
    anchor: np.ndarray,
    prior_rel: float,
    prior_std: np.ndarray,
) -> tuple[EndEffectorParams, np.ndarray, Comparison]:
    """(ee, factors), or the start (`start`, every factor 1) where the fit ended worse on
    its objective (`compare`), said in a warning; and the comparison."""
    cmp = compare(data, start, ee, factors, anchor, prior_rel, prior_std)
    if not cmp.start_better:
        return ee, factors, cmp
    log.warning(
        "the fit ended worse on its objective (%.6g) than the start (%.6g): the start kept",
        cmp.end,
        cmp.start,
    )
    ones = np.ones_like(factors)
    again = compare(data, start, start, ones, anchor, prior_rel, prior_std)
    return start, ones, replace(cmp, chi2_by_object=again.chi2_by_object)
