"""Array back-ends so that each formula is written once.

The band law and the flight dynamics are written against the small `Ops`
namespace below. `NUMPY` evaluates them on arrays (vectorised over throws);
`casadi_ops()` evaluates the very same code on CasADi symbols for the throw
optimiser. No formula is duplicated between the two.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Ops", "NUMPY", "casadi_ops"]


@dataclass(frozen=True)
class Ops:
    """The handful of operations the model's formulas use."""

    sqrt: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    sin: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    where: Callable[[Any, Any, Any], Any]
    fmax: Callable[[Any, Any], Any]


NUMPY = Ops(
    sqrt=np.sqrt,
    cos=np.cos,
    sin=np.sin,
    atan2=np.arctan2,
    where=np.where,
    fmax=np.maximum,
)


def casadi_ops() -> Ops:
    """The CasADi back-end (imported lazily: casadi is only needed to plan)."""
    import casadi as ca

    return Ops(
        sqrt=ca.sqrt,
        cos=ca.cos,
        sin=ca.sin,
        atan2=ca.atan2,
        where=lambda c, a, b: ca.if_else(c, a, b),
        fmax=ca.fmax,
    )
