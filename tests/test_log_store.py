"""The durable throw-log store: round trips, validation, all-or-nothing imports,
and durability against a process killed with SIGKILL."""

from __future__ import annotations

import collections
import csv
import os
import signal
import sqlite3
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from cell.cli import main
from cell.errors import InvalidInput, LogFormatError
from cell.log import ThrowStore, read_throws_csv, read_tracks_csv, write_throws_csv
from cell.log.csvio import ThrowTable
from cell.log.store import APPLICATION_ID
from cell.synth import Campaign, default_world, draw_campaign

OBJECTS = ("cube30", "cuboid_c", "cyl50", "sphere70")


def record(i: int, **over: object) -> dict[str, object]:
    """One valid throw record."""
    rec: dict[str, object] = {
        "throw_id": f"t{i:04d}",
        "object_id": "cube50",
        "shape": "cube",
        "mass_kg": 0.06,
        "size_x_m": 0.05,
        "size_y_m": 0.05,
        "size_z_m": 0.05,
        "stroke_m": 0.03 + 0.0001 * i,
        "x_m": 0.0,
        "y_m": 0.01 * i,
        "z_m": 0.6,
        "elevation_rad": 0.5,
        "azimuth_rad": 0.1,
        "roll_rad": 0.0,
        "vx_mps": 0.0,
        "vy_mps": 0.0,
        "vz_mps": 0.0,
        "platform": "arm",
        "rotor_rpm": 0.0,
        "land_z_m": 0.0,
        "landed_x_m": 1.0 + 0.001 * i,
        "landed_y_m": 0.1,
    }
    rec.update(over)
    return rec


def same_table(a: ThrowTable, b: ThrowTable) -> None:
    """Assert two tables hold the same columns (in order) and values (NaN = NaN)."""
    assert a.columns == b.columns
    assert len(a) == len(b)
    for c in a.columns:
        x, y = a.data[c], b.data[c]
        if isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y, err_msg=c)
        else:
            assert list(x) == list(y), c


@pytest.fixture()
def campaign_csv(tmp_path: Path) -> tuple[Path, Path, ThrowTable]:
    """A small synthetic log with an extra column, plus a tracks file."""
    table = draw_campaign(default_world(), Campaign(n=40, objects=OBJECTS), seed=5)
    table = table.with_columns({"operator": [f"op{i % 3}" for i in range(len(table))]})
    throws = tmp_path / "throws.csv"
    write_throws_csv(table, throws)
    tracks = tmp_path / "tracks.csv"
    with open(tracks, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
        for tid in table.text("throw_id")[:3]:
            for k in range(4):
                w.writerow([tid, 0.05 * k, 0.1 * k, 0.0, 0.6 + 0.01 * k])
    return throws, tracks, read_throws_csv(throws)


def test_append_keeps_every_column_and_empty_cells(tmp_path: Path) -> None:
    recs = [
        record(0, session="s1", note="first"),
        record(1, landed_y_m=float("nan"), stroke_m=None, t_flight_s=0.51),
        record(2, session="s2", mesh="duck_vhacd.obj", time_s=12.5),
    ]
    with ThrowStore(tmp_path / "s.sqlite") as store:
        for r in recs:
            store.append(r)
        got = store.table()
    want = ThrowTable.from_records(recs)
    # the store lists columns in the order it first saw them: compare by name
    assert set(got.columns) == set(want.columns)
    same_table(got, ThrowTable(columns=got.columns, data={c: want.data[c] for c in got.columns}))
    assert np.isnan(got.num("stroke_m")[1]) and np.isnan(got.num("landed_y_m")[1])
    assert got.text("note") == ["first", "", ""]


def test_append_takes_numpy_scalars(tmp_path: Path) -> None:
    rec = record(
        3, elevation_rad=np.float64(0.5), mass_kg=np.float32(0.0625), rotor_rpm=np.int64(0)
    )
    with ThrowStore(tmp_path / "s.sqlite") as store:
        store.append(rec)
        t = store.table()
    assert t.num("elevation_rad")[0] == 0.5 and t.num("mass_kg")[0] == 0.0625


def test_import_export_round_trip_with_tracks(tmp_path: Path, campaign_csv) -> None:
    throws, tracks, table = campaign_csv
    db = tmp_path / "s.sqlite"
    assert main(["log", "--db", str(db), "import", str(throws), "--tracks", str(tracks)]) == 0
    out, out_tracks = tmp_path / "out.csv", tmp_path / "out_tracks.csv"
    assert (
        main(["log", "export", "--db", str(db), "-o", str(out), "--tracks", str(out_tracks)]) == 0
    )
    same_table(read_throws_csv(out), table)
    a, b = read_tracks_csv(tracks), read_tracks_csv(out_tracks)
    assert a.keys() == b.keys()
    for k in a:
        np.testing.assert_array_equal(a[k], b[k])
    # filters
    sub = tmp_path / "sub.csv"
    assert main(["log", "--db", str(db), "export", "-o", str(sub), "--object", "cyl50"]) == 0
    assert set(read_throws_csv(sub).text("object_id")) == {"cyl50"}


def test_counts_match_an_independent_count(tmp_path: Path, campaign_csv, capsys) -> None:
    _, _, table = campaign_csv
    with ThrowStore(tmp_path / "s.sqlite") as store:
        store.import_table(table)
        store.append(record(0, platform="drone", rotor_rpm=9000.0))
        counts = store.counts()
    objs = collections.Counter(table.text("object_id")) + collections.Counter(["cube50"])
    sess = collections.Counter(table.text("session")) + collections.Counter([""])
    assert counts["throws"] == len(table) + 1
    assert counts["object_id"] == dict(objs)
    assert counts["session"] == dict(sess)
    assert counts["platform"] == {"arm": len(table), "drone": 1}
    assert main(["log", "--db", str(tmp_path / "s.sqlite"), "show"]) == 0
    text = capsys.readouterr().out
    assert f"{len(table) + 1} throws" in text and "drone" in text


def _corrupt(path: Path, kind: str) -> tuple[int | None, str]:
    """Spoil a throws.csv in place; return the (row, column) the error must name."""
    rows = list(csv.reader(open(path, newline="")))
    header = rows[0]
    if kind == "missing column":
        j = header.index("mass_kg")
        rows = [r[:j] + r[j + 1 :] for r in rows]
        want: tuple[int | None, str] = (None, "mass_kg")
    elif kind == "text in a number":
        rows[7][header.index("stroke_m")] = "fast"
        want = (7, "stroke_m")
    else:  # duplicate id
        rows[9][0] = rows[4][0]
        want = (9, "throw_id")
    with open(path, "w", newline="") as fh:
        csv.writer(fh).writerows(rows)
    return want


@pytest.mark.parametrize("kind", ["missing column", "text in a number", "duplicate id"])
def test_bad_csv_names_the_place_and_leaves_the_store_unchanged(
    tmp_path: Path, campaign_csv, capsys, kind: str
) -> None:
    throws, _, table = campaign_csv
    db = tmp_path / "s.sqlite"
    with ThrowStore(db) as store:
        store.import_table(table.take(np.arange(10)))
        before = store.table()
    bad = tmp_path / "bad.csv"
    write_throws_csv(table.take(np.arange(10, 40)), bad)
    row, column = _corrupt(bad, kind)
    with pytest.raises(LogFormatError) as exc:
        with ThrowStore(db) as store:
            store.import_table(read_throws_csv(bad))
    assert exc.value.path == str(bad) and exc.value.row == row and exc.value.column == column
    assert main(["log", "--db", str(db), "import", str(bad)]) == 2
    err = capsys.readouterr().err
    assert str(bad) in err and f"'{column}'" in err and (row is None or f"row {row}" in err)
    with ThrowStore(db) as store:
        same_table(store.table(), before)


def test_duplicate_of_a_stored_throw_or_orphan_track_is_rejected_whole(
    tmp_path: Path, campaign_csv
) -> None:
    throws, _, table = campaign_csv
    db = tmp_path / "s.sqlite"
    with ThrowStore(db) as store:
        store.import_table(table.take(np.arange(5)))
        with pytest.raises(LogFormatError) as exc:
            store.import_table(table)  # rows 1-5 are already stored
        assert exc.value.row == 1 and exc.value.column == "throw_id"
        orphan = {"no-such-throw": np.zeros((2, 4))}
        with pytest.raises(LogFormatError, match="no-such-throw"):
            store.import_table(table.take(np.arange(5, 40)), orphan, tracks_path="tr.csv")
        with pytest.raises(LogFormatError, match="duplicate"):
            store.append(record(0, throw_id=table.text("throw_id")[0]))
        assert len(store) == 5 and store.tracks() == {}


def test_not_a_store_and_the_default_path(tmp_path: Path, monkeypatch) -> None:
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"this is not a database" * 100)
    with pytest.raises(InvalidInput, match="junk.sqlite"):
        ThrowStore(junk)
    monkeypatch.chdir(tmp_path)
    with ThrowStore() as store:
        assert store.path == Path("cell_log.sqlite")
    monkeypatch.setenv("CELL_LOG_DB", str(tmp_path / "env.sqlite"))
    with ThrowStore() as store:
        store.append(record(1))
    assert (tmp_path / "env.sqlite").exists()


# -- durability: a real process killed with SIGKILL -----------------------------------

_CHILD_RUN = textwrap.dedent(
    """
    import sys
    sys.path.insert(0, {root!r})
    from cell.log import ThrowStore
    sys.path.insert(0, {tests!r})
    from test_log_store import record
    store = ThrowStore({db!r})
    for i in range(100000):
        store.append(record(i))
        print(f"committed t{{i:04d}}", flush=True)
    """
)

_CHILD_IMPORT = textwrap.dedent(
    """
    import sys, time
    sys.path.insert(0, {root!r})
    from cell.log import ThrowStore, read_throws_csv
    store = ThrowStore({db!r})
    table = read_throws_csv({csv!r})
    def progress(done):
        print(f"inside {{done}}", flush=True)
        time.sleep(30)  # killed here, with rows written but not committed
    store.import_table(table, progress=progress)
    print("finished", flush=True)
    """
)


def _spawn(code: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, bufsize=1
    )


def _integrity(db: Path) -> str:
    con = sqlite3.connect(db)
    try:
        return con.execute("PRAGMA integrity_check").fetchone()[0]
    finally:
        con.close()


def test_sigkill_mid_run_loses_no_committed_throw(tmp_path: Path) -> None:
    db = tmp_path / "run.sqlite"
    root = str(Path(__file__).resolve().parents[1])
    proc = _spawn(_CHILD_RUN.format(root=root, tests=str(Path(__file__).parent), db=str(db)))
    committed = []
    assert proc.stdout is not None
    while len(committed) < 40:
        line = proc.stdout.readline()
        assert line, "the child died before committing 40 throws"
        committed.append(line.split()[1])
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=10)
    assert proc.returncode == -signal.SIGKILL
    assert _integrity(db) == "ok"
    with ThrowStore(db) as store:
        table = store.table()
    ids = table.text("throw_id")
    assert set(committed) <= set(ids)
    # every stored throw is whole, exactly as appended
    for i, tid in enumerate(ids):
        assert tid == f"t{i:04d}"
        assert table.num("landed_x_m")[i] == pytest.approx(1.0 + 0.001 * i, abs=0)


def test_sigkill_mid_import_leaves_nothing_half_imported(tmp_path: Path, campaign_csv) -> None:
    throws, _, table = campaign_csv
    db = tmp_path / "imp.sqlite"
    with ThrowStore(db) as store:
        store.append(record(0))
    big = tmp_path / "big.csv"
    write_throws_csv(table, big)
    root = str(Path(__file__).resolve().parents[1])
    proc = _spawn(_CHILD_IMPORT.format(root=root, db=str(db), csv=str(big)))
    assert proc.stdout is not None
    line = proc.stdout.readline()
    assert line.startswith("inside"), line
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=10)
    assert _integrity(db) == "ok"
    with ThrowStore(db) as store:
        assert store.table().text("throw_id") == ["t0000"]
        # the killed import left no lock and no rows behind: it can simply be redone
        assert store.import_table(read_throws_csv(big)) == len(table)
        assert len(store) == len(table) + 1


def _sqlite_file_of_something_else(path: Path) -> bytes:
    conn = sqlite3.connect(str(path))
    conn.execute("CREATE TABLE inventory (sku TEXT, qty INTEGER)")
    conn.execute("INSERT INTO inventory VALUES ('a', 3)")
    conn.commit()
    conn.close()
    return path.read_bytes()


def test_log_show_leaves_a_foreign_sqlite_file_byte_identical(tmp_path: Path, capsys) -> None:
    foreign = tmp_path / "inventory.sqlite"
    before = _sqlite_file_of_something_else(foreign)
    for argv in (
        ["log", "show", "--db", str(foreign)],
        ["log", "export", "--db", str(foreign), "-o", str(tmp_path / "out.csv")],
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "not a throw-log store" in err and str(foreign) in err
        assert "Traceback" not in err
    assert foreign.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["inventory.sqlite"]
    # opening it for writing is refused too, before anything is written
    with pytest.raises(InvalidInput, match="not a throw-log store"):
        ThrowStore(foreign)
    assert foreign.read_bytes() == before


def test_a_new_store_carries_the_application_id_and_reads_back_read_only(tmp_path: Path) -> None:
    db = tmp_path / "s.sqlite"
    with ThrowStore(db) as store:
        store.append(record(0))
    header = db.read_bytes()[68:72]  # SQLite header: application id, big-endian
    assert int.from_bytes(header, "big") == APPLICATION_ID
    with ThrowStore(db, read_only=True) as store:
        assert len(store) == 1
        with pytest.raises(InvalidInput, match="read-only"):
            store.append(record(1))
    with ThrowStore(db) as store:
        assert len(store) == 1


def test_a_folder_is_not_a_store(tmp_path: Path) -> None:
    with pytest.raises(InvalidInput, match="is a folder"):
        ThrowStore(tmp_path)
