"""Read and write throw logs in the docs/throw_log.md format (CSV).

The table type and its column checks are in `cell.log.table` (re-exported here).
"""

from __future__ import annotations

import csv
import logging
import math
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput, LogFormatError
from cell.infile import check_input_file
from cell.log.fileformat import other_format
from cell.log.object_ids import ids_alike_by_case
from cell.log.table import (
    HEADER_AGAIN,
    NUMERIC_COLUMNS,
    PLATFORMS,
    RANGES,
    REQUIRED_COLUMNS,
    ThrowTable,
    comment_line,
    log_number,
    millimetres_hint,
    number_text_hint,
    other_separator,
    parse_cells,
    repeats_header,
)
from cell.log.track_time import next_time, track_time_problem
from cell.outfile import write_whole

__all__ = [
    "REQUIRED_COLUMNS",
    "NUMERIC_COLUMNS",
    "PLATFORMS",
    "ThrowTable",
    "read_throws_csv",
    "write_throws_csv",
    "read_tracks_csv",
]

log = logging.getLogger(__name__)


def read_throws_csv(path: str | Path) -> ThrowTable:
    """Read and validate a throws.csv.

    Raises:
        LogFormatError: naming the file, the row (1 = first data row) and the column.
    """
    p = _readable(path)
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            try:
                header = [h.strip() for h in next(reader)]
            except StopIteration:
                raise LogFormatError(p, None, None, "is empty; a header row is required") from None
            if any("\x00" in h for h in header):  # UTF-16 without its mark reads as UTF-8
                raise LogFormatError(p, None, None, _not_utf8(p))
            rows = [row for row in reader if any(cell.strip() for cell in row)]
    except FileNotFoundError:
        raise LogFormatError(p, None, None, "no such file") from None
    except UnicodeDecodeError:
        raise LogFormatError(p, None, None, _not_utf8(p)) from None
    except csv.Error as exc:
        raise _csv_error(p, exc, blank=lambda row: not any(c.strip() for c in row)) from None
    table = parse_cells(header, rows, p)
    for sentence in ids_alike_by_case(table.text("object_id"), p):
        log.warning(sentence)
    return table


def _csv_error(p: str, exc: csv.Error, blank: Any) -> LogFormatError:
    """The error for a file the csv module refused: a cell over its field limit (a text or
    a file pasted into a cell) by row and column, found by reading the file again with the
    limit lifted; else the csv module's own words. `blank(row)`: a row the reader skips
    (not counted in the row numbers)."""
    limit = csv.field_size_limit()
    plain = LogFormatError(p, None, None, f"is not a readable CSV text file ({exc})")
    if "field larger than field limit" not in str(exc):
        return plain

    def why(cell: str) -> str:
        return (
            f"a cell of {len(cell):,} characters, over the {limit:,} a CSV cell may hold (a "
            "text or a file pasted into a cell?); a cell holds one value"
        )

    try:
        csv.field_size_limit(2**31 - 1)
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = next(reader, [])
            j = _long(header, limit)
            if j:
                return LogFormatError(p, None, None, f"the header's cell {j}: {why(header[j - 1])}")
            rows = (row for row in reader if not blank(row))
            for r, row in enumerate(rows, start=1):
                j = _long(row, limit)
                if j:
                    col = header[j - 1].strip() if j <= len(header) else f"cell {j}"
                    return LogFormatError(p, r, col, why(row[j - 1]))
    except (OSError, UnicodeDecodeError, csv.Error):
        pass
    finally:
        csv.field_size_limit(limit)
    return plain


def _long(row: list[str], limit: int) -> int:
    """The 1-based index of the first cell over `limit` characters (0: none)."""
    return next((j for j, c in enumerate(row, 1) if len(c) > limit), 0)


def _not_utf8(path: str) -> str:
    """Why a log is not UTF-8 text, and how to save it so: a UTF-16 file (a spreadsheet's
    "Unicode text") by its byte-order mark, a binary file by a NUL byte in its first 8 kB,
    else the first line that is not UTF-8."""
    with open(path, "rb") as fh:
        start = fh.read(8192)
    what = "is not a readable CSV text file: "
    save = "; save it as 'CSV UTF-8'"
    if start[:4] in (b"\xff\xfe\x00\x00", b"\x00\x00\xfe\xff"):
        return what + "UTF-32" + save
    if start[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return what + "UTF-16 (a spreadsheet's 'Unicode text')" + save
    # text of ASCII characters in UTF-16 without its byte-order mark: every other byte NUL
    even, odd = start[0::2], start[1::2]
    if len(start) >= 4 and (set(even) == {0} or set(odd) == {0}):
        order = "big" if set(even) == {0} else "little"
        return what + f"UTF-16 ({order}-endian, without a byte-order mark)" + save
    if b"\x00" in start:
        return what + "binary data (NUL bytes), not text"
    what += "not UTF-8"
    with open(path, "rb") as fh:  # line by line: no UTF-8 character spans a newline
        for line, raw in enumerate(fh, start=1):
            try:
                raw.decode("utf-8")
            except UnicodeDecodeError as exc:
                bad = raw[exc.start : exc.start + 1].hex()
                what += f" (byte 0x{bad} on line {line}: Latin-1 or Windows-1252?)"
                break
    return what + "; save it as 'CSV UTF-8'"


MAX_CSV_BYTES = 512 * 1024 * 1024  # [B] a log of ~2 million throws; larger is refused unread


def _readable(path: str | Path) -> str:
    """Check that `path` is a regular file this process can read, of a bounded size, before
    opening it (a folder, a device such as /dev/zero or a FIFO is refused by name, unopened),
    and that it is not a file of another format (`cell.log.fileformat`: a gzipped CSV, a
    Parquet table, JSON lines ...), named by its first bytes."""
    p = str(path)
    try:
        check_input_file(p, "file", MAX_CSV_BYTES)
    except InvalidInput as exc:
        text = str(exc)
        raise LogFormatError(p, None, None, text.removeprefix(f"{p}: ")) from None
    if other := other_format(p):
        raise LogFormatError(p, None, None, other)
    return p


def _fmt(v: Any) -> str:
    if isinstance(v, (float, np.floating)):
        return "" if math.isnan(float(v)) else repr(float(v))
    return str(v)


def write_throws_csv(table: ThrowTable, path: str | Path) -> None:
    """Write a table in the docs/throw_log.md format (floats at full precision, NaN as empty)."""

    def write(p: Path) -> None:
        with open(p, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(table.columns)
            cols = [table.data[c] for c in table.columns]
            for i in range(len(table)):
                w.writerow([_fmt(col[i]) for col in cols])

    write_whole(path, write)


def _time_why(p: str, r: int, row: dict, t: float, out: dict[str, list[list[float]]]) -> str:
    """Why track time `t` of data row `r` is refused, from the step to its track's sample
    before it (or, for its first, the one after it)."""
    tid = (row.get("throw_id") or "").strip()
    before = out.get(tid)
    nxt = before[-1][0] if before else next_time(p, r, tid)
    return track_time_problem(t, None if nxt is None else t - nxt)


def _number(cell: str | None) -> bool:
    """Whether a cell reads as a number."""
    try:
        log_number((cell or "").strip())
    except (TypeError, ValueError):
        return False
    return True


_LOST = ("", "nan", "NaN", "NAN", "inf", "-inf")  # a position cell a tracker left lost


def read_tracks_csv(path: str | Path, *, keep_lost: bool = False) -> dict[str, np.ndarray]:
    """Read a tracks.csv into {throw_id: array (k, 4) of t_s, x_m, y_m, z_m}.

    The samples stay in the order written: a track out of time order is the diagnosis's to
    mend or set aside, and to say which (`cell.gap.track_check`).

    Args:
        path: the file.
        keep_lost: keep an empty or NaN position cell as NaN, a lost sample (the
            diagnosis drops it and says so, `cell.gap.track_check`); else it is an error.

    Raises:
        LogFormatError: a missing column, a non-numeric cell, a time (or, without
            `keep_lost`, a position) that is not a finite number, a time beyond
            `MAX_TRACK_TIME_S` of the release, a position beyond the throw log's range
            (`RANGES`: ±100 m).
    """
    p = _readable(path)
    need = ("throw_id", "t_s", "x_m", "y_m", "z_m")
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            header = reader.fieldnames or []
            if any("\x00" in h for h in header):  # UTF-16 without its mark reads as UTF-8
                raise LogFormatError(p, None, None, _not_utf8(p))
            for c in need:
                if c not in header:
                    raise LogFormatError(
                        p,
                        None,
                        c,
                        "required column missing"
                        + (
                            ": the header is one column; a tracks file is comma-separated"
                            if other_separator(header)
                            else ""
                        ),
                    )
            out: dict[str, list[list[float]]] = {}
            lo, hi = RANGES["x_m"]  # a tracked position [m]: the log's positions' range
            names = sorted(header)  # a row that is the header again (`repeats_header`)
            for r, row in enumerate(reader, start=1):
                extra = [x for x in row.get(None) or () if x.strip()]  # empty: trailing commas
                # fewer cells than named: with keep_lost, a time without its position is a
                # lost sample (dropped and said by the track check), else an error
                short = None in row.values() and not (keep_lost and row["t_s"] is not None)
                first = (row.get(header[0]) or "").strip()
                if first in names and repeats_header((row.get(c) for c in header), names):
                    raise LogFormatError(p, r, None, HEADER_AGAIN)
                line = [row[h] for h in header if row[h] is not None] + list(extra)
                comment = comment_line(",".join(line))
                if comment and (extra or None in row.values() or not _number(row["t_s"])):
                    raise LogFormatError(p, r, None, comment)
                if extra or short:
                    cells = len(header) + len(extra) - list(row.values()).count(None)
                    raise LogFormatError(
                        p, r, None, f"has {cells} cells; the header has {len(header)}"
                    )
                vals = []
                for c in need[1:]:
                    cell = row[c]
                    if keep_lost and c != "t_s" and (cell is None or cell.strip() in _LOST):
                        vals.append(math.nan)  # a lost sample: the track check drops it
                        continue
                    try:
                        vals.append(log_number(cell.strip()))
                    except (TypeError, ValueError):
                        raise LogFormatError(
                            p, r, c, f"{cell!r} is not a number" + number_text_hint(cell.strip())
                        ) from None
                    if (c == "t_s" or not keep_lost) and not math.isfinite(vals[-1]):
                        raise LogFormatError(p, r, c, f"{cell!r} is not a finite number")
                    if c == "t_s" and track_time_problem(vals[-1]):
                        raise LogFormatError(p, r, c, _time_why(p, r, row, vals[-1], out))
                    if c != "t_s" and math.isfinite(vals[-1]) and not lo <= vals[-1] <= hi:
                        raise LogFormatError(
                            p,
                            r,
                            c,
                            f"{vals[-1]} is outside the valid range [{lo:g}, {hi:g}]"
                            + millimetres_hint(vals[-1]),
                        )
                # padded ids read as the log reads its own (its cells stripped)
                out.setdefault(row["throw_id"].strip(), []).append(vals)
    except UnicodeDecodeError:
        raise LogFormatError(p, None, None, _not_utf8(p)) from None
    except csv.Error as exc:
        raise _csv_error(p, exc, blank=lambda row: row == []) from None
    return {k: np.asarray(v) for k, v in out.items()}
