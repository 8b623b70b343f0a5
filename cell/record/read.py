"""Read a `.rrd` recording back with Rerun's own reader (`rerun.chunk.RrdReader`).

`read_rows` gives every logged row of every entity as plain Python values
(columns named as Rerun names them, e.g. `Scalars:scalars`, `Points3D:positions`,
and the timelines `sim_time`, `item`), in the order of their row ids (the
order they were logged).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from cell.errors import InvalidInput
from cell.infile import check_input_file
from cell.record.stream import import_rerun

__all__ = ["read_rows", "entities"]

MAX_RECORDING_BYTES = 4 * 1024**3  # [B] read whole into memory: larger is refused unread


def read_rows(path: str | Path) -> dict[str, list[dict[str, Any]]]:
    """{entity path: [row, ...]} of the first recording in a `.rrd` file.

    Static rows carry no timeline columns. `sim_time` (a duration) comes back in
    seconds, `log_time` (a timestamp) in nanoseconds since the epoch.

    Raises:
        InvalidInput: the file is missing or not a Rerun recording.
    """
    import_rerun()
    import pyarrow as pa
    from rerun.chunk import RrdReader

    p = check_input_file(path, "recording", MAX_RECORDING_BYTES)  # a regular file, bounded
    try:
        chunks = list(RrdReader(p).stream())
    except (ValueError, OSError, RuntimeError) as exc:  # Rerun reports a bad file so
        raise InvalidInput(f"{path}: not a Rerun recording ({exc})") from None
    out: dict[str, list[tuple[Any, dict[str, Any]]]] = {}
    for ch in chunks:
        rb = ch.to_record_batch()
        entity = rb.schema.metadata[b"rerun:entity_path"].decode()
        cols = {}
        for name, col in zip(rb.schema.names, rb.columns, strict=True):
            if pa.types.is_duration(col.type):  # simulated time: seconds
                cols[name] = [
                    None if v is None else v / 1e9 for v in col.cast(pa.int64()).to_pylist()
                ]
            elif pa.types.is_timestamp(col.type):  # wall clock: ns since the epoch
                cols[name] = col.cast(pa.int64()).to_pylist()
            else:
                cols[name] = col.to_pylist()
        ids = cols.pop("rerun.controls.RowId")
        rows = out.setdefault(entity, [])
        for k, rid in enumerate(ids):
            rows.append((rid, {c: v[k] for c, v in cols.items()}))
    return {e: [r for _, r in sorted(rows, key=lambda x: x[0])] for e, rows in out.items()}


def entities(path: str | Path) -> list[str]:
    """The entity paths of a recording, sorted."""
    return sorted(read_rows(path))
