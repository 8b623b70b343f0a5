"""Array back-ends so that each formula is written once.

The band law and the flight dynamics are written against the small `Ops`
namespace below. `NUMPY` evaluates them on arrays (vectorised over throws);
`casadi_ops()` evaluates the very same code on CasADi symbols for the throw
optimiser. No formula is duplicated between the two.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields
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

    @classmethod
    def of(cls, module: Any, **other: Callable[..., Any]) -> Ops:
        """The operations as `module`'s functions of the same names, but those in `other`."""
        return cls(**{f.name: other.get(f.name) or getattr(module, f.name) for f in fields(cls)})


NUMPY = Ops.of(np, atan2=np.arctan2, fmax=np.maximum)


def casadi_ops() -> Ops:
    """The CasADi back-end (imported lazily: casadi is only needed to plan)."""
    import casadi as ca

    return Ops.of(ca, where=lambda c, a, b: ca.if_else(c, a, b))
