"""`cell log`: the durable throw store: import, export and show."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from cell.cli.common import add_json_arg, json_to_stdout, plural, print_json, write_json

T = TypeVar("T")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "log",
        help="the throw-log store (SQLite): import, export, show",
        description="The store is --db PATH, else $CELL_LOG_DB, else ./cell_log.sqlite.",
    )
    p.add_argument("--db", metavar="PATH", help="store file")
    lsub = p.add_subparsers(dest="log_command", metavar="ACTION", required=True)
    imp = lsub.add_parser("import", help="add a throws.csv (all rows or none)")
    imp.add_argument("file", help="throws.csv (docs/throw_log.md)")
    imp.add_argument("--tracks", metavar="TRACKS.csv", help="observed flight samples")
    imp.set_defaults(func=run_import)
    exp = lsub.add_parser("export", help="write the stored throws as a throws.csv")
    exp.add_argument("-o", "--output", required=True, help="throws.csv to write")
    exp.add_argument("--tracks", metavar="TRACKS.csv", help="also write the tracks")
    exp.add_argument("--object", metavar="ID", help="only this object's throws")
    exp.add_argument("--session", metavar="ID", help="only this session's throws")
    exp.set_defaults(func=run_export)
    show = lsub.add_parser("show", help="counts per object, platform and session")
    add_json_arg(show, "the counts")
    show.set_defaults(func=run_show)
    for sp in (imp, exp, show):  # --db also after the action; SUPPRESS keeps the parent's value
        sp.add_argument("--db", metavar="PATH", default=argparse.SUPPRESS, help="store file")


def _require_store(db: str | None) -> None:
    """Reading a store that does not exist is an error (opening it would create an empty one)."""
    from cell.errors import InvalidInput
    from cell.log.store import default_db_path

    path = default_db_path(db)
    if not path.exists():
        raise InvalidInput(
            f"{path}: no throw-log store here; give --db PATH (or set CELL_LOG_DB), "
            "or fill one with `cell log import FILE.csv` or `cell run`"
        )


def run_import(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from cell.log import ThrowStore, read_throws_csv, read_tracks_csv

    table = read_throws_csv(args.file)
    tracks = read_tracks_csv(args.tracks) if args.tracks else {}
    with (
        ThrowStore(args.db) as store,
        tqdm(total=len(table), desc="import", unit="throw", leave=False, disable=None) as bar,
    ):
        n = store.import_table(
            table, tracks, tracks_path=args.tracks or "", progress=lambda k: bar.update(k - bar.n)
        )
        total = len(store)
        path = store.path
    print(
        f"imported {plural(n, 'throw')} ({plural(len(tracks), 'track')}) from {args.file} "
        f"into {path}; {total} in all"
    )
    return 0


def _read_store(db: str | None, read: Callable[[Any], T]) -> tuple[T, Path]:
    """What `read` takes from the store `db`, opened read-only (it must exist), and the
    store's path."""
    _require_store(db)
    from cell.log import ThrowStore

    with ThrowStore(db, read_only=True) as store:
        return read(store), store.path


def run_export(args: argparse.Namespace) -> int:
    import csv

    from cell.log import write_throws_csv

    def read(store: Any) -> tuple[Any, dict[str, Any]]:
        table = store.table(object_id=args.object, session=args.session)
        return table, (store.tracks(table.text("throw_id")) if args.tracks else {})

    (table, tracks), path = _read_store(args.db, read)
    write_throws_csv(table, args.output)
    if args.tracks:
        with open(args.tracks, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
            for tid, arr in tracks.items():
                for row in arr:
                    w.writerow([tid, *(repr(float(v)) for v in row)])
    print(
        f"exported {plural(len(table), 'throw')} ({plural(len(tracks), 'track')}) from {path} "
        f"to {args.output}"
    )
    return 0


def run_show(args: argparse.Namespace) -> int:
    counts, path = _read_store(args.db, lambda store: store.counts())
    doc = {"store": str(path), **counts}
    if json_to_stdout(args):
        print_json(doc)
        return 0
    print(f"{path}: {plural(counts['throws'], 'throw')}, {counts['tracks']} with a track")
    for key, title in (("object_id", "object"), ("platform", "platform"), ("session", "session")):
        print(f"\nper {title}:")
        for k, v in counts[key].items():
            print(f"  {k or '(none)':24s} {v:6d}")
    write_json(args, doc)
    return 0
