"""A sort job's `limits` section (docs/jobs.md): the place reach, the most items a run
takes and the time an item may take, each bounded, with its default where not given."""

from __future__ import annotations

from cell.jobschema import LIMIT_KEYS, PLACE_REACH_M
from cell.yamltree import Checker, Node

__all__ = ["MAX_ITEMS", "limits_section"]

MAX_ITEMS = 100_000  # items in one job (a count, or limits.max_items); more is refused unbuilt


def limits_section(c: Checker, top: dict[str, Node]) -> tuple[float, int, float]:
    """The `limits` section.

    Returns:
        (place reach [m], max items, time limit per item [s]), defaults where not given.
    """
    lim = (
        c.mapping(top["limits"], "limits", dict.fromkeys(LIMIT_KEYS, "")) if "limits" in top else {}
    )
    reach = (
        c.number(lim["place_reach_m"], "limits.place_reach_m", lo=0.2, hi=1.2)
        if "place_reach_m" in lim
        else PLACE_REACH_M
    )
    max_items = (
        c.integer(lim["max_items"], "limits.max_items", 1, MAX_ITEMS)
        if "max_items" in lim
        else 1000
    )
    tlim = (
        c.number(lim["item_time_limit_s"], "limits.item_time_limit_s", lo=1.0)
        if "item_time_limit_s" in lim
        else 20.0
    )
    return reach, max_items, tlim
