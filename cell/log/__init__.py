"""Throw logs: the docs/throw_log.md interchange format (CSV) and the durable store."""

from cell.log.csvio import read_throws_csv, read_tracks_csv, write_throws_csv
from cell.log.store import DEFAULT_DB, ThrowStore, default_db_path
from cell.log.table import (
    NUMERIC_COLUMNS,
    PLATFORMS,
    REQUIRED_COLUMNS,
    ThrowTable,
)

__all__ = [
    "DEFAULT_DB",
    "NUMERIC_COLUMNS",
    "PLATFORMS",
    "REQUIRED_COLUMNS",
    "ThrowStore",
    "ThrowTable",
    "default_db_path",
    "read_throws_csv",
    "read_tracks_csv",
    "write_throws_csv",
]
