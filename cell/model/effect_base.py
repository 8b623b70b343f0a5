"""The base of every effect (`cell.model.effects`): a frozen dataclass of float parameters
(SI units in their names) with bounds, a typical scale, a phase, a plausible range and the
member of its effect's family of laws it is."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import astuple, dataclass, fields
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from cell.errors import InvalidParameter

if TYPE_CHECKING:
    from cell.model.throw import ThrowBatch

__all__ = ["Effect"]


@dataclass(frozen=True)
class Effect:
    """Base of all effects: parameters are the dataclass fields (floats, SI)."""

    name: ClassVar[str] = ""
    phase: ClassVar[str] = ""
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ()
    scale: ClassVar[tuple[float, ...]] = ()  # typical size of each parameter
    hangs_on: ClassVar[str | None] = None  # logged quantity for the permutation control
    law: ClassVar[str] = ""  # the member of the effect's family of laws
    # plausible range of each parameter (None: the bounds): what a real cell can have
    plausible: ClassVar[tuple[tuple[float, float], ...] | None] = None
    # where a fit without a warm start begins (None: one typical size inside the neutral
    # size); for a law flat about its neutral size (`BounceImpact`)
    start: ClassVar[tuple[float, ...] | None] = None
    # the parameters a learned law of the throw may give a value per throw
    # (`cell.gap.laws`; None: the one parameter of a one-parameter effect, none of others)
    law_params: ClassVar[tuple[str, ...] | None] = None

    def vector(self) -> np.ndarray:
        """The parameters as an array, in field order."""
        return np.asarray(astuple(self), float)

    @classmethod
    def param_names(cls) -> tuple[str, ...]:
        """The parameter names, in field order."""
        return tuple(f.name for f in fields(cls))  # type: ignore[arg-type]

    @classmethod
    def from_vector(cls, x: Sequence[float] | np.ndarray) -> Effect:
        """The effect with these parameter values (field order)."""
        return cls(*[float(v) for v in x])

    @classmethod
    def neutral(cls) -> Effect:
        """The effect at the size where it does nothing."""
        return cls()

    def per_throw(self, batch: ThrowBatch, permutation: np.ndarray | None = None) -> Effect:
        """The effect as evaluated on a batch (a learned law gives one value per throw,
        `cell.gap.laws`); a plain effect is itself."""
        return self

    def params(self) -> dict[str, float]:
        """The parameters as a plain dict."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self)}

    def implausible(self) -> list[str]:
        """Parameters outside their plausible range."""
        rng = self.plausible or self.bounds
        return [
            f.name
            for f, (lo, hi) in zip(fields(self), rng, strict=True)
            if not lo <= getattr(self, f.name) <= hi
        ]

    def __post_init__(self) -> None:
        for f, (lo, hi) in zip(fields(self), self.bounds, strict=True):
            v = getattr(self, f.name)
            if not np.isfinite(v) or v < lo - 1e-12 or v > hi + 1e-12:
                raise InvalidParameter(
                    f"effect {self.name}: {f.name}={v!r} is outside its range [{lo}, {hi}]"
                )
