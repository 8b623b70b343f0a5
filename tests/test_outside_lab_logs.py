"""Inputs of a lab with its own launcher and tracker, written without the cell: a tracker
whose clock steps back within a track, comment lines in a log or a tracks file, and a log
whose landing columns hold one point for every throw."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidInput, LogFormatError
from cell.gap.problem import build_problem
from cell.gap.track_check import check_tracks
from cell.log import read_throws_csv, read_tracks_csv, write_throws_csv
from cell.model.params import DEFAULT_EE
from cell.synth import Campaign, default_world, draw_campaign
from tests.cli_exit import cell_exit

G = 9.81  # [m/s²]


def _parabola(hz: float = 120.0) -> np.ndarray:
    """A drag-free flight sampled at hz from its release: (k, 4) of t_s, x_m, y_m, z_m,
    in closed form (launch 3 m/s along x and 4 m/s up from 1 m, down to the floor)."""
    t_land = (4.0 + np.sqrt(16.0 + 2.0 * G * 1.0)) / G
    t = np.arange(0.0, t_land, 1.0 / hz)
    return np.c_[t, 3.0 * t, 0.0 * t, 1.0 + 4.0 * t - 0.5 * G * t * t]


def _write_tracks(path: Path, tracks: dict[str, np.ndarray]) -> Path:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["throw_id", "t_s", "x_m", "y_m", "z_m"])
        for tid, arr in tracks.items():
            w.writerows([tid, *(f"{v:.6f}" for v in s)] for s in arr)
    return path


def test_a_track_whose_clock_steps_back_is_set_aside_and_a_shuffled_one_sorted(
    tmp_path: Path,
) -> None:
    """A track whose time, as written, steps back 15 ms half-way (a tracker's clock reset)
    was sorted by the reader without a word and fitted as one flight (the lab's 40 tracked
    throws of a ball with no effect, 14 of them so: verdict `unknown`, noise floor
    0.069 m against the lab's 0.014 m); it is set aside naming the step. A track written
    in shuffled order is still sorted, and now says so (the reader had sorted it before the
    check could); samples written again whole (a logger replaying its buffer) are repeats,
    dropped and said."""
    good = _parabola()
    stepped = good.copy()
    half = len(good) // 2
    stepped[half:, 0] -= 0.015
    shuffled = good[np.random.default_rng(1000).permutation(len(good))]
    replayed = np.vstack([good[:60], good[40:60], good[60:]])  # 20 samples written again
    path = _write_tracks(
        tmp_path / "tracks.csv",
        {"clean": good, "clock": stepped, "shuffled": shuffled, "replayed": replayed},
    )
    tracks = read_tracks_csv(path, keep_lost=True)
    usable, bad, mended = check_tracks(["clean", "clock", "shuffled", "replayed"], tracks)
    why = {b["throw_id"]: b["why"] for b in bad}
    assert set(why) == {"clock"}, why
    t_before, t_after = good[half - 1, 0], good[half, 0] - 0.015
    assert why["clock"].startswith(
        f"time goes back: from {t_before:.4g} s to {t_after:.4g} s at sample {half + 1} "
        f"of {len(good)}"
    ), why["clock"]
    assert {"throw_id": "shuffled", "note": "samples not in time order (sorted)"} in mended
    assert {
        "throw_id": "replayed",
        "note": "20 repeated time stamps (later ones dropped)",
    } in mended
    # sorted back, the shuffled and the replayed tracks are the clean one, sample for sample
    assert np.allclose(usable["shuffled"], usable["clean"], atol=1e-6)
    assert np.allclose(usable["replayed"], usable["clean"], atol=1e-6)


def test_two_flights_under_one_id_are_not_merged_into_one(tmp_path: Path) -> None:
    """Two throws' tracks written under one throw_id, each from its release: sorted, they
    made one zig-zag track; each run is a flight, so the track is set aside, said why."""
    a = _parabola()
    b = a.copy()
    b[:, 1] += 0.5  # the second throw from 0.5 m further along x
    tracks = read_tracks_csv(_write_tracks(tmp_path / "t.csv", {"t1": np.vstack([a, b])}))
    usable, bad, _ = check_tracks(["t1"], tracks)
    assert not usable
    assert bad[0]["why"].startswith("time goes back: ") and "two flights" in bad[0]["why"]


@pytest.fixture(scope="module")
def log_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("lab") / "log.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=30), seed=1000), path)
    return path


def test_a_comment_line_is_named_as_one(log_csv: Path, tmp_path: Path, capsys) -> None:
    """A `#` line in a log was refused as a row of the wrong number of cells ("row 1: has 2
    cells; the header has 22"); it is named as a comment line, in a log, as its first line,
    and in a tracks file."""
    lines = log_csv.read_text().splitlines()
    inside = tmp_path / "inside.csv"
    inside.write_text("\n".join([lines[0], "# lab run 7, launcher B", *lines[1:]]) + "\n")
    with pytest.raises(LogFormatError) as exc:
        read_throws_csv(inside)
    assert "row 1: is a comment line ('# lab run 7, launcher B')" in str(exc.value)
    first = tmp_path / "first.csv"
    first.write_text("\n".join(["# lab run 7", *lines]) + "\n")
    with pytest.raises(LogFormatError, match=r"first line is a comment line \('# lab run 7'\)"):
        read_throws_csv(first)
    tid = lines[1].split(",")[0]
    tr = tmp_path / "tracks.csv"
    tr.write_text(
        f"throw_id,t_s,x_m,y_m,z_m\n{tid},0,0,0,1\n# lost lock, re-acquired\n{tid},0.1,0,0,1\n"
    )
    assert cell_exit(["gap", str(log_csv), "--tracks", str(tr)]) == 2
    err = capsys.readouterr().err
    assert "row 2: is a comment line ('# lost lock, re-acquired')" in err, err


def test_landings_all_at_one_point_are_refused_not_given_a_floor_of_zero(
    log_csv: Path, tmp_path: Path, capsys
) -> None:
    """A log whose landing columns hold one point for every throw (a logger stuck): `cell
    gap` gave a noise floor of 0.000 m, B 3.65 m and `unknown` with a 97 % speed error
    proposed, and `cell identify` and `cell learn` fitted it; each refuses it now, naming
    the columns and the point, and nothing is written."""
    with log_csv.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows:
        r["landed_x_m"], r["landed_y_m"] = "1.25", "0.4"
    stuck = tmp_path / "stuck.csv"
    with stuck.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with pytest.raises(InvalidInput, match=r"1 point \(\(1.25, 0.4\) m\) in columns 'landed_x_m'"):
        read_throws_csv(stuck).require_varied(20, "the diagnosis")
    read_throws_csv(log_csv).require_varied(20, "the diagnosis")  # the log as drawn passes
    out = tmp_path / "out.yaml"
    for argv in (
        ["gap", str(stuck), "--json", str(tmp_path / "g.json")],
        ["identify", str(stuck), "-o", str(out)],
        ["learn", str(stuck), "-o", str(tmp_path / "r.skops")],
    ):
        assert cell_exit(argv) == 2, argv
        err = capsys.readouterr().err
        assert "needs landings that vary with the throw" in err, err
    assert not out.exists() and not (tmp_path / "g.json").exists()


def test_the_store_gives_a_track_back_in_the_order_it_came(log_csv: Path, tmp_path: Path) -> None:
    """`cell log export --tracks` sorted every track by time (`ORDER BY t_s`): a track whose
    clock stepped back came out of the store looking like one flight, and `cell gap` on the
    export used it. It comes back as imported, and the diagnosis sets it aside again."""
    tid = read_throws_csv(log_csv).text("throw_id")[0]
    stepped = _parabola()
    stepped[len(stepped) // 2 :, 0] -= 0.015
    tracks = _write_tracks(tmp_path / "tracks.csv", {tid: stepped})
    db, out, out_tracks = tmp_path / "s.sqlite", tmp_path / "o.csv", tmp_path / "o_tracks.csv"
    assert cell_exit(["log", "--db", str(db), "import", str(log_csv), "--tracks", str(tracks)]) == 0
    argv = ["log", "export", "--db", str(db), "-o", str(out), "--tracks", str(out_tracks)]
    assert cell_exit(argv) == 0
    back = read_tracks_csv(out_tracks, keep_lost=True)
    np.testing.assert_allclose(back[tid], read_tracks_csv(tracks)[tid], atol=1e-9)
    _, bad, _ = check_tracks([tid], back)
    assert bad and bad[0]["why"].startswith("time goes back: "), bad


def test_throws_dropped_are_counted_by_why(log_csv: Path, tmp_path: Path, caplog) -> None:
    """Throws the diagnosis drops were "N dropped: no landing logged, or no stroke and no
    track", also where a track was given and set aside; each reason is counted now."""
    with log_csv.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    for r in rows[:5]:
        r["stroke_m"] = ""
    for r in rows[5:8]:
        r["landed_x_m"] = r["landed_y_m"] = ""
    path = tmp_path / "partly.csv"
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with caplog.at_level("WARNING", logger="cell.gap.problem"):
        build_problem(read_throws_csv(path), DEFAULT_EE, seed=1000)
    assert (
        "8 throws dropped: 3 with no landing logged; 5 with no stroke (another launcher's) "
        "and no track given (--tracks)"
    ) in caplog.text, caplog.text
