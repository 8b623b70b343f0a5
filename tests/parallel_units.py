"""Units of work for tests/test_parallel.py (importable by Ray's worker processes)."""

from __future__ import annotations

import os
from pathlib import Path


def die_once(unit: tuple[str, int]) -> int:
    """k², but the worker process running unit 2 dies the first time (no exception:
    the process is gone, as when a node is lost)."""
    marker, k = unit
    if k == 2 and not Path(marker).exists():
        Path(marker).write_text("died")
        os._exit(1)
    return k * k


def fails_on_three(k: int) -> int:
    """k, but unit 3 raises."""
    if k == 3:
        raise ValueError("unit three is bad")
    return k
