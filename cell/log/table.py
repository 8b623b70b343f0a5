"""The throw log's table: its columns, their checks, and `ThrowTable`.

`ThrowTable` is columnar: numeric columns are float arrays (an empty cell is
NaN where the format allows it), text columns are lists of str, and columns
the format does not know are kept as text in their original order. The
columns and what a cell may hold are docs/throw_log.md's; `parse_cells` checks rows
of text cells against them (the CSV reader `cell.log.csvio` and the store
build their tables with it).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cell.errors import InvalidInput, LogFormatError
from cell.kinds import PLATFORMS
from cell.log.units_row import units_row_problem
from cell.model.objects import (
    MAX_DENSITY_KG_M3,
    MIN_DENSITY_KG_M3,
    SHAPES,
    denser_than_any_solid,
    lighter_than_air,
    shape_code,
)
from cell.model.throw import ThrowBatch

__all__ = [
    "NONNEGATIVE",
    "NULLABLE",
    "NUMERIC_COLUMNS",
    "OPTIONAL_NUMERIC",
    "PLATFORMS",
    "POSITION_COLUMNS",
    "RANGES",
    "REQUIRED_COLUMNS",
    "ThrowTable",
    "comment_line",
    "log_number",
    "millimetres_hint",
    "other_separator",
    "parse_cells",
]

# the release's stroke [m], grip centre [m, W] and throw axis [rad]
_RELEASE_COLUMNS = ("stroke_m", "x_m", "y_m", "z_m", "elevation_rad", "azimuth_rad")
REQUIRED_COLUMNS = (
    "throw_id",
    "object_id",
    "shape",
    "mass_kg",
    "size_x_m",
    "size_y_m",
    "size_z_m",
    *_RELEASE_COLUMNS,
    "roll_rad",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "platform",
    "rotor_rpm",
    "land_z_m",
    "landed_x_m",
    "landed_y_m",
)
OPTIONAL_NUMERIC = ("time_s", "t_flight_s")
NUMERIC_COLUMNS = (
    tuple(c for c in REQUIRED_COLUMNS if c not in ("throw_id", "object_id", "shape", "platform"))
    + OPTIONAL_NUMERIC
)
# Columns whose cells may be empty (read as NaN).
NULLABLE = ("stroke_m", "landed_x_m", "landed_y_m") + OPTIONAL_NUMERIC
NONNEGATIVE = ("mass_kg", "size_x_m", "size_y_m", "size_z_m", "rotor_rpm")
# [m] no position of a cell's throw is farther than this from the base: a release, a landing
# plane or a landing point in millimetres mostly lies beyond it (a 0.1 m landing is 100 mm)
_POS_M = 100.0
POSITION_COLUMNS = ("x_m", "y_m", "z_m", "land_z_m", "landed_x_m", "landed_y_m")
_VEL_MPS = 100.0  # [m/s] nor any base or release speed faster
# Column -> (low, high): what a throw of a real cell can have; wider than any real throw and
# narrower than nonsense (a 10 rad elevation, a 5 m grip width, a 1e308 kg mass).
RANGES: dict[str, tuple[float, float]] = {
    "mass_kg": (0.0, 20.0),
    "size_x_m": (0.0, 1.0),
    "size_y_m": (0.0, 1.0),
    "size_z_m": (0.0, 1.0),
    "stroke_m": (0.0, 0.5),
    "elevation_rad": (-math.pi / 2, math.pi / 2),
    "azimuth_rad": (-2 * math.pi, 2 * math.pi),
    "roll_rad": (-2 * math.pi, 2 * math.pi),
    "rotor_rpm": (0.0, 100_000.0),
    **{c: (-_POS_M, _POS_M) for c in POSITION_COLUMNS},
    **{c: (-_VEL_MPS, _VEL_MPS) for c in ("vx_mps", "vy_mps", "vz_mps")},
}


@dataclass
class ThrowTable:
    """A throw log in memory.

    Attributes:
        columns: column names in order (required first, then the others).
        data: column name -> float array (numeric) or list of str (text).
        path: where it was read from, for messages ("" if built in memory).
    """

    columns: list[str]
    data: dict[str, Any]
    path: str = ""
    _index: dict[str, int] = field(default_factory=dict, repr=False)

    def __len__(self) -> int:
        return len(self.data["throw_id"])

    def num(self, column: str) -> np.ndarray:
        """A numeric column as a float array."""
        return np.asarray(self.data[column], dtype=float)

    def text(self, column: str) -> list[str]:
        """A text column as a list of str."""
        return list(self.data[column])

    @property
    def landed(self) -> np.ndarray:
        """Observed landing points [m, W], shape (n, 2) (NaN where not logged)."""
        return np.stack([self.num("landed_x_m"), self.num("landed_y_m")], axis=-1)

    def require_varied(self, n_min: int, purpose: str) -> None:
        """Refuse a log with fewer than `n_min` distinct throws (release state and landing).

        Args:
            n_min: the fewest distinct throws `purpose` can work with.
            purpose: what needs them, for the message ("the diagnosis", "identification").

        Raises:
            InvalidInput: too few distinct throws (identical rows count once).
        """
        named = ("mass_kg", *_RELEASE_COLUMNS, "landed_x_m", "landed_y_m")
        cols = [c for c in named if c in self.data]
        rows = np.column_stack([self.num(c) for c in cols]) if len(self) else np.empty((0, 0))
        distinct = len({tuple(np.round(r, 9)) for r in rows})
        if distinct < n_min:
            raise InvalidInput(
                f"{self.path}: {purpose} needs at least {n_min} distinct throws; this log has "
                f"{len(self)} rows of which {distinct} distinct (identical throws count once)"
            )
        self._require_varied_landings(n_min, purpose)

    def _require_varied_landings(self, n_min: int, purpose: str) -> None:
        """Refuse observed landings that do not vary with the throw: at least `n_min` of
        them logged, fewer than `n_min` distinct points among them (a column filled with
        one value, a logger stuck). Their scatter would read as a noise floor of zero."""
        seen = self.landed[np.all(np.isfinite(self.landed), axis=1)]
        points = {tuple(np.round(r, 9)) for r in seen}
        if len(seen) < n_min or len(points) >= n_min:
            return
        shown = ", ".join(f"({x:g}, {y:g}) m" for x, y in sorted(points)[:3])
        more = ", ..." if len(points) > 3 else ""
        raise InvalidInput(
            f"{self.path}: {purpose} needs landings that vary with the throw; the "
            f"{len(seen)} landings logged are {len(points)} point"
            f"{'s' if len(points) != 1 else ''} ({shown}{more}) in columns 'landed_x_m', "
            "'landed_y_m': is a fixed value written there? Leave a landing not observed "
            "empty (docs/throw_log.md)"
        )

    def take(self, idx: np.ndarray | list[int]) -> ThrowTable:
        """The rows at these indices (or boolean mask), as a new table."""
        ii = np.arange(len(self))[np.asarray(idx)]
        data: dict[str, Any] = {}
        for c in self.columns:
            col = self.data[c]
            data[c] = col[ii] if isinstance(col, np.ndarray) else [col[i] for i in ii]
        return ThrowTable(columns=list(self.columns), data=data, path=self.path)

    def with_columns(self, extra: dict[str, Any]) -> ThrowTable:
        """A copy with columns added or replaced (added ones go last)."""
        cols = list(self.columns) + [c for c in extra if c not in self.columns]
        data = dict(self.data)
        data.update(extra)
        return ThrowTable(columns=cols, data=data, path=self.path)

    def to_batch(self, *, objects: dict[str, Any] | None = None) -> ThrowBatch:
        """The throws as a model batch.

        Args:
            objects: optional per-object_id overrides {object_id: ObjectParams}
                (identified η_o); rows of other objects use their logged values.

        Raises:
            LogFormatError: a row with no stroke (another launcher's throw).
        """
        stroke = self.num("stroke_m")
        if np.any(np.isnan(stroke)):
            i = int(np.flatnonzero(np.isnan(stroke))[0])
            raise LogFormatError(
                self.path, i + 1, "stroke_m", "empty: the model needs the stroke of every throw"
            )
        mass = self.num("mass_kg")
        size = np.stack([self.num("size_x_m"), self.num("size_y_m"), self.num("size_z_m")], -1)
        codes = np.array([SHAPES.index(s) for s in self.data["shape"]], dtype=int)
        if objects:
            for j, oid in enumerate(self.data["object_id"]):
                o = objects.get(oid)
                if o is not None:
                    mass[j] = o.mass
                    size[j] = o.size
        return ThrowBatch.build(
            stroke=stroke,
            position=np.stack([self.num("x_m"), self.num("y_m"), self.num("z_m")], -1),
            elevation=self.num("elevation_rad"),
            azimuth=self.num("azimuth_rad"),
            roll=self.num("roll_rad"),
            base_velocity=np.stack(
                [self.num("vx_mps"), self.num("vy_mps"), self.num("vz_mps")], -1
            ),
            land_z=self.num("land_z_m"),
            shape=codes,
            mass=mass,
            size=size,
        )

    @classmethod
    def from_records(cls, records: list[dict[str, Any]], path: str = "") -> ThrowTable:
        """Build and validate a table from dicts (values as numbers or strings)."""
        header = list(REQUIRED_COLUMNS)
        for r in records:
            for k in r:
                if k not in header:
                    header.append(k)
        rows = [[_cell(r.get(c, "")) for c in header] for r in records]
        return parse_cells(header, rows, path)


def millimetres_hint(v: float) -> str:
    """What to say of a position `v` [m] beyond `_POS_M`: a value that would fit in metres
    read as millimetres is most likely in millimetres ("" otherwise)."""
    if abs(v) > _POS_M and abs(v) / 1000.0 <= _POS_M:
        return (
            f"; positions are in metres, world frame W (z up, the floor at z = 0): "
            f"is it {v / 1000.0:g} m written in millimetres?"
        )
    return ""


_DECIMAL_COMMA = re.compile(r"[-+]?\d+,\d+")
_DIGIT_GROUPS = re.compile(r"[-+]?[0-9][0-9_]*(\.[0-9_]*)?([eE][-+]?[0-9]+)?")
_WITH_UNIT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*[^\W\d_][/^²³\w]*")


def log_number(cell: str) -> float:
    """A log's number cell (stripped) as `float`, which also takes forms no CSV writer
    makes and a reader is likely to misread: digit-group underscores (`0.0_6` is 0.06 to
    Python) and digits of other scripts (`٣`, full-width `３`). ValueError for those, as
    for any text that is not a number."""
    if "_" in cell or not cell.isascii():
        raise ValueError(cell)
    return float(cell)


def number_text_hint(cell: str) -> str:
    """What to say of a cell that is not a number but looks like one written another way
    ("" otherwise): a decimal comma, or a number with its unit."""
    if _DECIMAL_COMMA.fullmatch(cell):
        return f" (a decimal comma? numbers take a decimal point: {cell.replace(',', '.')})"
    if "_" in cell and _DIGIT_GROUPS.fullmatch(cell):
        return f" (digit groups? write the digits alone: {cell.replace('_', '')})"
    if _WITH_UNIT.fullmatch(cell):
        return (
            " (a number with a unit: the unit is the column's, _m metres, _kg kilograms, _s "
            "seconds, _rad radians, _mps m/s; write the number alone, in that unit)"
        )
    return ""


def _unit_hint(column: str, v: float) -> str:
    """What to say of a value `v` beyond its column's range where another unit would put it
    in range: positions or extents in millimetres, a mass in grams, an angle in degrees."""
    lo, hi = RANGES[column]
    if column in POSITION_COLUMNS:
        return millimetres_hint(v)
    if column.startswith("size_") and lo <= v / 1000.0 <= hi:
        return f"; extents are in metres: is it {v / 1000.0:g} m written in millimetres?"
    if column == "mass_kg" and lo <= v / 1000.0 <= hi:
        return f"; is it {v / 1000.0:g} kg written in grams?"
    if column.endswith("_rad") and lo <= math.radians(v) <= hi:
        return f"; angles are in radians: is it {v:g}° ({math.radians(v):.4g} rad) in degrees?"
    return ""


def other_separator(header: Sequence[str]) -> str:
    """The separator a one-column CSV header was written with, as a message names it
    ("';'", "tabs", "'|'"), where it holds one; "" otherwise (a spreadsheet's export in
    another locale, read with commas as one column)."""
    if len(header) != 1:
        return ""
    shown = {";": "';'", "\t": "tabs", "|": "'|'"}
    return next((name for sep, name in shown.items() if sep in header[0]), "")


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, (float, np.floating)):  # NumPy scalars: repr would name the type
        f = float(v)
        return "" if math.isnan(f) else repr(f)
    if isinstance(v, np.integer):
        return str(int(v))
    return str(v)


# a data row that is the header again (its names, in any order)
HEADER_AGAIN = (
    "is a header row again (two files written one after the other?); keep the first "
    "header only, and check the throw ids of the two are distinct"
)


def _more_headers(rows: list[list[str]], r: int, names: list[str]) -> str:
    """The data rows after row `r` (1 = the first) that are the header again too, said at
    once (three sessions appended make two; naming the first alone told one at a time)."""
    more = [k for k, row in enumerate(rows[r:], start=r + 1) if repeats_header(row, names)]
    if not more:
        return ""
    shown = ", ".join(str(k) for k in more[:5]) + (", …" if len(more) > 5 else "")
    return f"; row{'s' if len(more) > 1 else ''} {shown} too ({len(more) + 2} files in all?)"


def comment_line(line: str | None) -> str | None:
    """The refusal of a row of the wrong width whose text (its cells joined by commas)
    begins with `#`: a comment line, which neither a throw log nor a tracks file has
    (None: not one)."""
    text = (line or "").strip()
    if not text.startswith("#"):
        return None
    shown = text if len(text) <= 40 else text[:37] + "..."
    return (
        f"is a comment line ({shown!r}): a log has none (docs/throw_log.md); delete the "
        "line, or keep the note in a column of its own (any other column is kept as text)"
    )


def repeats_header(cells: Iterable[str | None], names: list[str]) -> bool:
    """Whether a data row's `cells` are the header's names again, in any order (`names`:
    the header, sorted; a missing cell is empty): two files appended one after the other."""
    return sorted((c or "").strip() for c in cells) == names


def parse_cells(header: list[str], rows: list[list[str]], path: str) -> ThrowTable:
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    sep = other_separator(header)
    if missing and sep:
        raise LogFormatError(
            path,
            None,
            None,
            f"the header is one column separated by {sep}, not commas: a throw log is "
            "comma-separated, with '.' for the decimal point (docs/throw_log.md)",
        )
    if missing and header and comment_line(header[0]):
        raise LogFormatError(path, None, None, "the first line " + str(comment_line(header[0])))
    if missing:
        raise LogFormatError(
            path, None, missing[0], f"required column missing (all missing: {', '.join(missing)})"
        )
    dup = [c for c in header if header.count(c) > 1]
    if dup:
        raise LogFormatError(path, None, dup[0], "column appears twice in the header")
    pos = {c: i for i, c in enumerate(header)}
    n = len(rows)
    data: dict[str, Any] = {}
    names = sorted(header)
    for r, row in enumerate(rows, start=1):
        if row[0].strip() in pos and repeats_header(row, names):
            raise LogFormatError(path, r, None, HEADER_AGAIN + _more_headers(rows, r, names))
        if units := units_row_problem(header, row, NUMERIC_COLUMNS):
            raise LogFormatError(path, r, None, units)
        if len(row) != len(header):
            why = (
                comment_line(",".join(row)) or f"has {len(row)} cells; the header has {len(header)}"
            )
            raise LogFormatError(path, r, None, why)
    for c in header:
        cells = [row[pos[c]].strip() for row in rows]
        if c in NUMERIC_COLUMNS:
            arr = np.empty(n)
            for r, s in enumerate(cells, start=1):
                if s == "":
                    if c in NULLABLE:
                        arr[r - 1] = np.nan
                        continue
                    raise LogFormatError(path, r, c, "is empty; a number is required")
                try:
                    v = log_number(s)
                except ValueError:
                    raise LogFormatError(
                        path, r, c, f"{s!r} is not a number" + number_text_hint(s)
                    ) from None
                if not math.isfinite(v):
                    raise LogFormatError(path, r, c, f"{s!r} is not a finite number")
                if c in NONNEGATIVE and v < 0:
                    raise LogFormatError(path, r, c, f"{v} is negative; must be ≥ 0")
                lo, hi = RANGES.get(c, (-math.inf, math.inf))
                if not lo <= v <= hi:
                    raise LogFormatError(
                        path,
                        r,
                        c,
                        f"{v} is outside the valid range [{lo:g}, {hi:g}]" + _unit_hint(c, v),
                    )
                arr[r - 1] = v
            data[c] = arr
        else:
            data[c] = cells
    for c in ("mass_kg", "size_x_m", "size_y_m", "size_z_m"):
        bad = np.flatnonzero(data[c] <= 0)
        if bad.size:
            raise LogFormatError(path, int(bad[0]) + 1, c, f"{data[c][bad[0]]} must be > 0")
    sizes = np.c_[data["size_x_m"], data["size_y_m"], data["size_z_m"]]
    # over whole columns (a log may hold millions of rows), then said for the first row
    volume = np.prod(sizes, axis=1)  # [m³] each row's box
    dense_rows = np.flatnonzero(data["mass_kg"] > MAX_DENSITY_KG_M3 * volume)
    if dense_rows.size:
        k = int(dense_rows[0])
        m = float(data["mass_kg"][k])
        dense = denser_than_any_solid(m, sizes[k]) or f"{m:g} kg is denser than any solid"
        raise LogFormatError(
            path, k + 1, "mass_kg", f"{dense}: is it {m / 1000.0:g} kg written in grams?"
        )
    light_rows = np.flatnonzero(data["mass_kg"] < MIN_DENSITY_KG_M3 * volume)
    if light_rows.size:
        k = int(light_rows[0])
        m = float(data["mass_kg"][k])
        light = lighter_than_air(m, sizes[k]) or f"{m:g} kg is lighter than the air"
        raise LogFormatError(path, k + 1, "mass_kg", light)
    for r, s in enumerate(data["shape"], start=1):
        if s not in SHAPES:
            raise LogFormatError(
                path, r, "shape", f"unknown shape {s!r}; valid: {', '.join(SHAPES)}"
            )
        shape_code(s)
    for r, s in enumerate(data["platform"], start=1):
        if s not in PLATFORMS:
            raise LogFormatError(
                path, r, "platform", f"unknown platform {s!r}; valid: {', '.join(PLATFORMS)}"
            )
    seen: dict[str, int] = {}
    for r, s in enumerate(data["throw_id"], start=1):
        if s == "":
            raise LogFormatError(path, r, "throw_id", "is empty; a unique id is required")
        if s in seen:
            raise LogFormatError(
                path, r, "throw_id", f"duplicate id {s!r} (first at row {seen[s]})"
            )
        seen[s] = r
    for r, s in enumerate(data["object_id"], start=1):
        if s == "":
            raise LogFormatError(path, r, "object_id", "is empty; an object id is required")
    ordered = list(REQUIRED_COLUMNS) + [c for c in header if c not in REQUIRED_COLUMNS]
    return ThrowTable(columns=ordered, data=data, path=path)
