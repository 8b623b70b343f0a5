"""Values made once for the same exact inputs, kept by the bytes of those inputs.

The robot layer's planners are asked the same questions again and again within a decision
and across decisions (the same spline through the same waypoints, the same ruckig move, the
same toppra constraints); what they make is a function of the inputs' bits, and nothing
writes into it afterwards. `Kept` is the bounded table they share: a value made once per
key, all of it cleared when full; where `error` is given, a make that raised it is kept by
its message and raised again as that error.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Generic, TypeVar

import numpy as np

T = TypeVar("T")


def array_key(*arrays: object) -> bytes:
    """The bytes of each array as float64, C-ordered, one after the other."""
    return b"".join(np.ascontiguousarray(a, dtype=float).tobytes() for a in arrays)


class Kept(Generic[T]):
    """At most `max_size` values by their key's bytes (all cleared when full); a make that
    raised `error` kept by its message."""

    def __init__(self, max_size: int, error: type[Exception] | None = None) -> None:
        self.max_size = max_size
        self.error = error
        self._table: dict[bytes, T | str] = {}

    def __len__(self) -> int:
        return len(self._table)

    def clear(self) -> None:
        self._table.clear()

    def get(self, key: bytes, make: Callable[[], T]) -> T:
        """The value kept for `key`, made by `make()` where none is (or `error` raised
        again, by the message it was first raised with)."""
        found = self._table.get(key)
        if found is None:
            if len(self._table) >= self.max_size:
                self._table.clear()
            if self.error is None:
                found = make()
            else:
                try:
                    found = make()
                except self.error as exc:
                    found = str(exc)
            self._table[key] = found
        if isinstance(found, str) and self.error is not None:
            raise self.error(found)
        return found  # type: ignore[return-value]

    def put(self, key: bytes, value: T) -> None:
        """Keep `value` for `key` in place of what was kept (cleared first when full)."""
        if key not in self._table and len(self._table) >= self.max_size:
            self._table.clear()
        self._table[key] = value
