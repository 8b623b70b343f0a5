"""Throw logs: the THROW_LOG.md interchange format (CSV) and the durable store."""

from cell.log.csvio import (
    NUMERIC_COLUMNS,
    PLATFORMS,
    REQUIRED_COLUMNS,
    ThrowTable,
    read_throws_csv,
    read_tracks_csv,
    write_throws_csv,
)

__all__ = [
    "NUMERIC_COLUMNS",
    "PLATFORMS",
    "REQUIRED_COLUMNS",
    "ThrowTable",
    "read_throws_csv",
    "read_tracks_csv",
    "write_throws_csv",
]
