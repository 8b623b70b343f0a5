"""Units of work for tests/test_parallel.py (importable by Ray's worker processes)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


def throw_or_die_once(unit: tuple[str, dict[str, Any]]) -> dict[str, Any]:
    """One scene throw's log record; the worker process running throw 2 dies the first
    time (no exception: the process is gone, as when a node is lost)."""
    from cell.workflows.campaign import campaign_records

    marker, setting = unit
    if setting["throw_id"].endswith("-0002") and not Path(marker).exists():
        Path(marker).write_text("died")
        os._exit(1)
    (record,) = campaign_records([setting])
    return record


def fails_on_three(k: int) -> int:
    """k, but unit 3 raises."""
    if k == 3:
        raise ValueError("unit three is bad")
    return k


def dies_on_two(unit: tuple[int, str]) -> int:
    """k * k, but the worker process running k = 2 dies, every time (each try leaves a
    line in the file `unit[1]` first)."""
    k, attempts = unit
    if k == 2:
        with open(attempts, "a") as f:
            f.write("died\n")
        os._exit(1)
    return k * k


def square(k: int) -> int:
    """k * k."""
    return k * k
