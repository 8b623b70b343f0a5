"""`cell bench`: speed and accuracy figures, one flat JSON object.

Each benchmark is a module in this package with `run(quick: bool) -> dict`
returning flat figures (names carry their unit). BENCHES lists them in order;
a module that is not built yet is skipped.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

__all__ = ["BENCHES", "available"]

BENCHES = ("predict", "identify", "plan", "robot", "gap", "scene_reach", "ray", "realtime")


def available() -> dict[str, Callable[[bool], dict[str, float]]]:
    """The benchmark functions that exist, by name."""
    out = {}
    for name in BENCHES:
        try:
            mod = importlib.import_module(f"cell.bench.bench_{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"cell.bench.bench_{name}":
                continue
            raise
        out[name] = mod.run
    return out
