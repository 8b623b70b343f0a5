"""Throw optimisation (thesis §4.2): a target in, the release state σ* out.

`plan_throw` is the entry point; `ThrowBounds` the bounds of σ; the NLP of
eq. 4.1 lives in `nlp` (CasADi/IPOPT, physics in `casadi_model`), the fast
inverse in `fast`.
"""

from cell.optimize.bounds import DEFAULT_BOUNDS, SIGMA_COLUMNS, ThrowBounds
from cell.optimize.plan import MISS_TOL, ThrowPlan, plan_throw
from cell.optimize.reach import reach_range

__all__ = [
    "DEFAULT_BOUNDS",
    "MISS_TOL",
    "SIGMA_COLUMNS",
    "ThrowBounds",
    "ThrowPlan",
    "plan_throw",
    "reach_range",
]
