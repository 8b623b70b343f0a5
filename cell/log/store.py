"""The durable throw-log store: every throw the cell makes, in one SQLite file.

Each `append` is its own transaction, so a crash, a SIGKILL or a Ctrl-C in the
middle of a run loses no throw already appended. `import_table` validates the
whole table first and then writes it in one transaction: an import is either
all in the store or not at all. The file is in WAL mode with full
synchronisation, so readers (`cell log show`) never block the writer.

Every docs/throw_log.md column is kept: the required ones and the known optional
ones (`mesh`, `time_s`, `session`, `t_flight_s`) as typed SQL columns (an empty
cell is NULL), any other column as text in a JSON object per row. The column
order of the logs that went in is remembered, so an export has the columns in
the order they came.
"""

from __future__ import annotations

import json
import logging
import math
import os
import sqlite3
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any
from urllib.parse import quote

import numpy as np

from cell.errors import InvalidInput, LogFormatError, plural
from cell.infile import check_input_file, check_path_length
from cell.log.table import NUMERIC_COLUMNS, REQUIRED_COLUMNS, ThrowTable

__all__ = ["DEFAULT_DB", "StoreWriteError", "ThrowStore", "default_db_path"]

log = logging.getLogger(__name__)

DEFAULT_DB = "cell_log.sqlite"
_ENV = "CELL_LOG_DB"
_SCHEMA_VERSION = "1"
MAX_STORE_BYTES = 16 * 1024**3  # [B] ~70 million throws; a larger file is refused unopened
APPLICATION_ID = 0x43454C4C  # "CELL" in the SQLite header: marks a throw-log store
OPTIONAL_TEXT = ("mesh", "session")
OPTIONAL_NUM = ("time_s", "t_flight_s")
_TYPED = REQUIRED_COLUMNS + OPTIONAL_TEXT + OPTIONAL_NUM
_NOT_NULL_TEXT = ("throw_id", "object_id", "shape", "platform")


def default_db_path(path: str | Path | None = None) -> Path:
    """The store file: `path` if given, else $CELL_LOG_DB, else ./cell_log.sqlite."""
    if path:
        return Path(path)
    return Path(os.environ.get(_ENV) or DEFAULT_DB)


def _sql_type(col: str) -> str:
    if col in NUMERIC_COLUMNS:
        nullable = col not in REQUIRED_COLUMNS or col in ("stroke_m", "landed_x_m", "landed_y_m")
        return "REAL" if nullable else "REAL NOT NULL"
    return "TEXT NOT NULL" if col in _NOT_NULL_TEXT else "TEXT"


_CREATE = [
    "CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS throws (seq INTEGER PRIMARY KEY AUTOINCREMENT, "
    + ", ".join(f'"{c}" {_sql_type(c)}' + (" UNIQUE" if c == "throw_id" else "") for c in _TYPED)
    + ", extras TEXT NOT NULL DEFAULT '{}', source TEXT NOT NULL DEFAULT '')",
    "CREATE TABLE IF NOT EXISTS columns (name TEXT PRIMARY KEY, pos INTEGER NOT NULL)",
    "CREATE TABLE IF NOT EXISTS tracks (throw_id TEXT NOT NULL REFERENCES throws(throw_id), "
    "t_s REAL NOT NULL, x_m REAL NOT NULL, y_m REAL NOT NULL, z_m REAL NOT NULL)",
    "CREATE INDEX IF NOT EXISTS tracks_throw ON tracks(throw_id)",
    "CREATE INDEX IF NOT EXISTS throws_object ON throws(object_id)",
]
_INSERT = (
    "INSERT INTO throws ("
    + ", ".join(f'"{c}"' for c in _TYPED)
    + ", extras, source) VALUES ("
    + ", ".join("?" for _ in _TYPED)
    + ", ?, ?)"
)


def _num(v: Any) -> float | None:
    f = float(v)
    return None if math.isnan(f) else f


def _unwritable(path: Path) -> str:
    """Why a store at `path` cannot be written, where its folder says ("" otherwise): a
    store is written with its -wal and -shm files beside it (WAL mode), so its folder
    must be writable, whether the store exists or not."""
    folder = path.resolve().parent
    try:
        read_only = bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except OSError:
        return ""
    if read_only:
        why = f"the folder {folder} is on a read-only file system"
    elif not os.access(folder, os.W_OK):
        why = f"the folder {folder} is not writable"
    else:
        return ""
    return (
        f": {why}, and a store is written with its -wal and -shm files beside it; give "
        "--db a file in a writable folder (or set $CELL_LOG_DB; `cell run --no-log` records "
        "no throws)"
    )


class StoreWriteError(OSError):
    """A write the store's file refused (a full disk, a quota, a file-size limit, the file
    gone read-only): what was committed before it is kept, this write is not. An OSError,
    not a `CellError`: a run stops at it (`cell run`), never scoring it as an item's
    failure; the command line says it as `cell: error: PATH: ...` (exit 2)."""


def _write_failed(path: Path, exc: sqlite3.Error) -> StoreWriteError:
    """The error of a write to the store at `path` that SQLite refused with `exc`."""
    why = str(exc)
    if "disk I/O error" in why or "full" in why:  # ENOSPC says "full"; EFBIG an I/O error
        why += ": a full disk, a quota or a file-size limit (`ulimit -f`)?"
    return StoreWriteError(
        0,
        f"cannot write the throw-log store ({why}); the throws committed before are kept, "
        f"this write is not{_unwritable(path)}",
        str(path),
    )


class ThrowStore:
    """A throw log in an SQLite file.

    Args:
        path: the file (created with its tables if missing); None = `default_db_path()`.

    Raises:
        InvalidInput: the file exists but is not a throw store (or not SQLite).
    """

    def __init__(self, path: str | Path | None = None, *, read_only: bool = False) -> None:
        self.path = default_db_path(path)
        self.read_only = read_only
        check_path_length(self.path, "--db")
        if self.path.is_dir():
            raise InvalidInput(f"{self.path}: is a folder; give a throw-log store file (--db PATH)")
        if self.path.exists():  # a regular file (never a device or FIFO), opened unread
            check_input_file(self.path, "throw-log store (SQLite)", MAX_STORE_BYTES)
        if self.path.exists() and self.path.stat().st_size > 0:
            self._conn = self._open_existing()
            if read_only:
                return
            self._conn.close()
        elif read_only:
            raise InvalidInput(f"{self.path}: no throw-log store here")
        try:
            self._conn = sqlite3.connect(str(self.path), isolation_level=None, timeout=30.0)
            self._conn.execute("PRAGMA journal_mode=WAL")
            self._conn.execute("PRAGMA synchronous=FULL")
            self._conn.execute("PRAGMA foreign_keys=ON")
            with self._transaction():
                for stmt in _CREATE:
                    self._conn.execute(stmt)
                self._conn.execute(
                    "INSERT OR IGNORE INTO meta VALUES ('schema_version', ?)", (_SCHEMA_VERSION,)
                )
                self._conn.execute(f"PRAGMA application_id = {APPLICATION_ID}")
        except sqlite3.OperationalError as exc:
            raise InvalidInput(
                f"{self.path}: cannot write the throw-log store ({exc}){_unwritable(self.path)}"
            ) from None
        except sqlite3.DatabaseError as exc:
            raise InvalidInput(f"{self.path}: not a throw-log store ({exc})") from None

    def _open_existing(self) -> sqlite3.Connection:
        """Open an existing file read-only and check that it is a throw store of this version.

        Nothing is written to a file that is not one (no tables, no journal mode change).
        """
        uri = "file:" + quote(str(self.path.resolve())) + "?mode=ro"
        if not Path(str(self.path) + "-wal").exists():
            # no writer has it open (a store in WAL mode has a -wal file while one does): read
            # the file as it is, so a read leaves no -wal/-shm file behind (a read-only
            # connection cannot remove the ones it creates)
            uri += "&immutable=1"
        try:
            conn = sqlite3.connect(uri, uri=True, isolation_level=None, timeout=30.0)
            app_id = conn.execute("PRAGMA application_id").fetchone()[0]
            tables = {r[0] for r in conn.execute("SELECT name FROM sqlite_master")}
        except sqlite3.OperationalError as exc:
            raise InvalidInput(
                f"{self.path}: cannot read the throw-log store ({exc}); a store in WAL mode "
                "needs its folder writable, or its -shm file present, to be read"
            ) from None
        except sqlite3.DatabaseError as exc:
            raise InvalidInput(f"{self.path}: not a throw-log store ({exc})") from None
        ours = app_id == APPLICATION_ID or (app_id == 0 and {"meta", "throws"} <= tables)
        if not ours:
            conn.close()
            raise InvalidInput(
                f"{self.path}: an SQLite file, but not a throw-log store (application id "
                f"{app_id:#x}, tables {sorted(tables)[:5]}); give a store made by `cell` "
                "(--db PATH) or a new file name"
            )
        version = conn.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()
        if version is None or version[0] != _SCHEMA_VERSION:
            conn.close()
            raise InvalidInput(
                f"{self.path}: store schema version {version and version[0]!r}; "
                f"this cell reads version {_SCHEMA_VERSION}"
            )
        return conn

    # -- plumbing -----------------------------------------------------------------
    def close(self) -> None:
        """Close the connection (everything appended is already committed)."""
        self._conn.close()

    def __enter__(self) -> ThrowStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @contextmanager
    def _transaction(self) -> Iterator[sqlite3.Connection]:
        if self.read_only:
            raise InvalidInput(f"{self.path}: opened read-only; nothing can be written to it")
        try:
            self._conn.execute("BEGIN IMMEDIATE")
        except sqlite3.OperationalError as exc:
            raise InvalidInput(f"{self.path}: the store is read-only here ({exc})") from None
        try:
            yield self._conn
            self._conn.execute("COMMIT")
        except sqlite3.OperationalError as exc:  # the file refused the write
            self._rollback()
            raise _write_failed(self.path, exc) from None
        except BaseException:
            self._rollback()
            raise

    def _rollback(self) -> None:
        """Undo the open transaction, if SQLite has not already (a failed COMMIT may)."""
        if self._conn.in_transaction:
            try:
                self._conn.execute("ROLLBACK")
            except sqlite3.Error as exc:  # the write's own error is the one said
                log.warning("%s: rollback failed: %s", self.path, exc)

    def existing_ids(self, ids: list[str]) -> set[str]:
        """Those of `ids` already in the store (to refuse a campaign before it runs)."""
        return self._existing_ids(list(ids))

    def _existing_ids(self, ids: list[str]) -> set[str]:
        found: set[str] = set()
        for k in range(0, len(ids), 500):
            chunk = ids[k : k + 500]
            marks = ",".join("?" * len(chunk))
            q = f"SELECT throw_id FROM throws WHERE throw_id IN ({marks})"
            found.update(r[0] for r in self._conn.execute(q, chunk))
        return found

    def _rows(self, table: ThrowTable, source: str) -> Iterator[tuple[Any, ...]]:
        extra_cols = [c for c in table.columns if c not in _TYPED]
        cols = {c: table.data[c] for c in table.columns}
        n = len(table)
        for i in range(n):
            vals: list[Any] = []
            for c in _TYPED:
                col = cols.get(c)
                if col is None:
                    vals.append(None)
                elif c in NUMERIC_COLUMNS:
                    vals.append(_num(col[i]))
                else:
                    vals.append(col[i] if (col[i] != "" or c in _NOT_NULL_TEXT) else None)
            extras = {c: str(cols[c][i]) for c in extra_cols}
            vals.append(json.dumps(extras, ensure_ascii=False))
            vals.append(source)
            yield tuple(vals)

    def _remember_columns(self, columns: list[str]) -> None:
        pos = self._conn.execute("SELECT COALESCE(MAX(pos), -1) FROM columns").fetchone()[0]
        for c in columns:
            if c in REQUIRED_COLUMNS:
                continue
            cur = self._conn.execute(
                "INSERT OR IGNORE INTO columns VALUES (?, ?)", (c, int(pos) + 1)
            )
            if cur.rowcount:
                pos += 1

    # -- writing ------------------------------------------------------------------
    def append(self, record: dict[str, Any], *, track: np.ndarray | None = None) -> None:
        """Validate one throw and commit it in its own transaction.

        Args:
            record: column -> value (docs/throw_log.md columns; numbers or strings;
                None or NaN for an empty cell; unknown columns are kept as text).
            track: optional observed flight samples, shape (k, 4): t_s, x_m, y_m, z_m.

        Raises:
            LogFormatError: a bad value (naming the store, row 1 and the column) or a
                throw_id already in the store; nothing is written then.
        """
        where = f"{self.path} (append)"
        table = ThrowTable.from_records([record], path=where)
        tid = table.data["throw_id"][0]
        tracks = {tid: np.asarray(track, float).reshape(-1, 4)} if track is not None else {}
        if tracks and not np.all(np.isfinite(tracks[tid])):
            raise LogFormatError(where, 1, "track", "track samples must be finite numbers")
        self._write(table, tracks, where, source="append")

    def import_table(
        self,
        table: ThrowTable,
        tracks: dict[str, np.ndarray] | None = None,
        *,
        tracks_path: str = "",
        progress: Callable[[int], None] | None = None,
    ) -> int:
        """Add a whole (validated) table, and its tracks, in one transaction.

        Args:
            table: the throws (e.g. from `read_throws_csv`).
            tracks: {throw_id: (k, 4) array of t_s, x_m, y_m, z_m}; every throw_id
                must be in `table` or already in the store.
            tracks_path: the tracks file, for messages.
            progress: called with the number of rows written so far, inside the
                transaction (for a progress bar).

        Returns:
            The number of throws added.

        Raises:
            LogFormatError: a throw_id already in the store, or a track of an unknown
                throw; the store is unchanged then.
        """
        return self._write(
            table, tracks or {}, tracks_path, source=table.path or "import", progress=progress
        )

    def _write(
        self,
        table: ThrowTable,
        tracks: dict[str, np.ndarray],
        tracks_path: str,
        *,
        source: str,
        progress: Callable[[int], None] | None = None,
    ) -> int:
        ids = table.text("throw_id")
        known = self._existing_ids(ids)
        if known:
            r = next(i for i, t in enumerate(ids, start=1) if t in known)
            raise LogFormatError(
                table.path, r, "throw_id", f"duplicate id {ids[r - 1]!r}: already in {self.path}"
            )
        id_set = set(ids)
        unknown = [t for t in tracks if t not in id_set]
        if unknown:
            unknown = sorted(set(unknown) - self._existing_ids(unknown))
        if unknown:
            raise LogFormatError(
                tracks_path or table.path,
                None,
                "throw_id",
                f"track of throw {unknown[0]!r}, which is neither in the log nor in the store",
            )
        n = len(table)
        with self._transaction() as conn:
            self._remember_columns(table.columns)
            rows = self._rows(table, source)
            done = 0
            while done < n:
                chunk = [next(rows) for _ in range(min(1000, n - done))]
                try:
                    conn.executemany(_INSERT, chunk)
                except sqlite3.IntegrityError as exc:  # a concurrent writer took an id
                    raise LogFormatError(table.path, None, "throw_id", str(exc)) from None
                done += len(chunk)
                if progress is not None:
                    progress(done)
            for tid, arr in tracks.items():
                conn.executemany(
                    "INSERT INTO tracks VALUES (?, ?, ?, ?, ?)",
                    [(tid, *map(float, row)) for row in np.asarray(arr, float).reshape(-1, 4)],
                )
        log.info("%s: %s committed from %s", self.path, plural(n, "throw"), source)
        return n

    # -- reading ------------------------------------------------------------------
    def __len__(self) -> int:
        return int(self._conn.execute("SELECT COUNT(*) FROM throws").fetchone()[0])

    def table(self, *, object_id: str | None = None, session: str | None = None) -> ThrowTable:
        """The stored throws (optionally of one object and/or session), in the order added."""
        where, args = [], []
        if object_id is not None:
            where.append("object_id = ?")
            args.append(object_id)
        if session is not None:
            where.append("session = ?")
            args.append(session)
        q = (
            "SELECT "
            + ", ".join(f'"{c}"' for c in _TYPED)
            + ", extras FROM throws"
            + (" WHERE " + " AND ".join(where) if where else "")
            + " ORDER BY seq"
        )
        rows = self._conn.execute(q, args).fetchall()
        order = [r[0] for r in self._conn.execute("SELECT name FROM columns ORDER BY pos")]
        extras = [json.loads(r[-1]) for r in rows]
        data: dict[str, Any] = {}
        for j, c in enumerate(_TYPED):
            vals = [r[j] for r in rows]
            if c in NUMERIC_COLUMNS:
                data[c] = np.array([np.nan if v is None else v for v in vals], dtype=float)
            else:
                data[c] = ["" if v is None else str(v) for v in vals]
        for c in order:
            if c not in _TYPED:
                data[c] = [str(e.get(c, "")) for e in extras]
        columns = list(REQUIRED_COLUMNS) + [c for c in order if c not in REQUIRED_COLUMNS]
        data = {c: data[c] for c in columns}
        return ThrowTable(columns=columns, data=data, path=str(self.path))

    def tracks(self, throw_ids: list[str] | None = None) -> dict[str, np.ndarray]:
        """Observed flight samples {throw_id: (k, 4) array of t_s, x_m, y_m, z_m}, in the
        order they were added: a track out of time order is exported as it came, for the
        diagnosis to mend or set aside and say so (`cell.gap.track_check`)."""
        rows = self._conn.execute(
            "SELECT throw_id, t_s, x_m, y_m, z_m FROM tracks ORDER BY throw_id, rowid"
        ).fetchall()
        keep = set(throw_ids) if throw_ids is not None else None
        out: dict[str, list[tuple[float, ...]]] = {}
        for tid, *vals in rows:
            if keep is None or tid in keep:
                out.setdefault(tid, []).append(tuple(vals))
        return {k: np.asarray(v, float) for k, v in out.items()}

    def counts(self) -> dict[str, Any]:
        """How many throws there are, in all and per object, platform and session.

        Returns:
            {"throws": n, "tracks": throws with a track, "object_id": {id: n},
            "platform": {name: n}, "session": {id: n}} (a missing session is "").
        """
        out: dict[str, Any] = {"throws": len(self)}
        out["tracks"] = int(
            self._conn.execute("SELECT COUNT(DISTINCT throw_id) FROM tracks").fetchone()[0]
        )
        for col in ("object_id", "platform", "session"):
            q = f"SELECT COALESCE(\"{col}\", ''), COUNT(*) FROM throws GROUP BY 1 ORDER BY 1"
            out[col] = {str(k): int(v) for k, v in self._conn.execute(q)}
        return out
