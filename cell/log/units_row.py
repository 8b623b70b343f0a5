"""A row of units under a log's header: told as such, not as a number missing.

Some labs' exports put the units in a second header row (`,,,kg,m,m,m,m,...`). Read as
the first throw, its `mass_kg` cell 'kg' was refused as "'kg' is not a number", which
says neither that the row is units nor where the log keeps its units (in the column
names: `_m` metres, `_kg` kilograms, `_rad` radians, `_mps` m/s, `_s` seconds, `_rpm`).
`units_row_problem` tells such a row by its numeric columns: none holds a number and at
least `MIN_UNIT_CELLS` hold a unit's name. Units other than a column's own (`mm` under a
`_m` column, `g` under `mass_kg`) are named, since the values under them would then be in
another unit too.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

__all__ = ["MIN_UNIT_CELLS", "units_row_problem"]

MIN_UNIT_CELLS = 3  # numeric cells naming a unit for a row to be a row of units

# a unit's name as written in a header row: letters, '/', '^', powers, '°', in brackets or not
_UNIT = re.compile(r"[\[(]?\s*(?:[a-zA-Z°µ%]+(?:[/·*^]?[a-zA-Z°µ²³0-9-]*)*)\s*[\])]?")
_OWN = {  # a column's suffix: the unit names it is written in
    "_m": {"m", "meter", "meters", "metre", "metres"},
    "_kg": {"kg"},
    "_rad": {"rad", "radian", "radians"},
    "_mps": {"m/s", "mps", "m s^-1", "m·s^-1", "m*s^-1", "m s-1"},
    "_s": {"s", "sec", "second", "seconds"},
    "_rpm": {"rpm", "1/min", "min^-1"},
}


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _own(column: str, unit: str) -> bool:
    bare = unit.strip("[]() ").lower()
    for suffix, names in _OWN.items():
        if column.endswith(suffix):
            return bare in names
    return True  # a column of no suffix (rotor_rpm has one): not checked


def units_row_problem(header: Sequence[str], row: Sequence[str], numeric: Sequence[str]) -> str:
    """Why data `row` (cells in `header`'s order) is a row of units ("" where it is not):
    none of its `numeric` columns holds a number and `MIN_UNIT_CELLS` or more a unit."""
    cells = {c: (row[i] if i < len(row) else "").strip() for i, c in enumerate(header)}
    nums = [c for c in header if c in numeric]
    if any(_is_number(cells[c]) for c in nums):
        return ""
    units = [c for c in nums if cells[c] and _UNIT.fullmatch(cells[c])]
    if len(units) < MIN_UNIT_CELLS:
        return ""
    shown = ", ".join(repr(cells[c]) for c in units[:4]) + (", …" if len(units) > 4 else "")
    other = [f"{cells[c]!r} under {c!r}" for c in units if not _own(c, cells[c])]
    why = (
        f"is a row of units ({shown}) under the header, not a throw: a log's units are in "
        "its column names (_m metres, _kg kilograms, _rad radians, _mps m/s, _s seconds, "
        "rotor_rpm revolutions per minute; docs/throw_log.md); delete the row"
    )
    if other:
        why += (
            f", and write the values in the columns' units ({', '.join(other[:3])}: "
            "those columns' values are in another unit)"
        )
    return why
