"""The sort orchestrator in the PyBullet cell: full cycles, bad jobs, and the log."""

import json
import re
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cell.cli import main
from cell.jobs import parse_job
from cell.log.store import ThrowStore
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: panda}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
%s
"""


def run_job(items: str, tmp_path: Path):
    job = parse_job(JOB % items, str(tmp_path / "job.yaml"))
    store = ThrowStore(tmp_path / "log.sqlite")
    orch = Orchestrator(job, store=store, session="test")
    try:
        summary = orch.run()
    finally:
        orch.close()
    return summary, store


def test_pick_and_throw_into_a_bin_beyond_reach(tmp_path):
    summary, store = run_job("  - {object: cube50, count: 1, bin: far}", tmp_path)
    r = summary.results[0]
    assert r.action == "throw" and r.bin_id == "far" and r.in_bin
    assert r.landing_error_m < 0.15  # the bin is 0.30 m wide
    table = store.table()
    assert len(table) == 1 and table.text("object_id") == ["cube50"]
    # the log holds the observed crossing of the rim plane, near the bin centre
    assert abs(table.num("landed_x_m")[0] - 1.40) < 0.15
    store.close()


def test_pick_and_place_into_a_near_bin(tmp_path):
    summary, store = run_job("  - {object: cyl70, count: 1, bin: near}", tmp_path)
    r = summary.results[0]
    assert r.action == "place" and r.in_bin and r.landing_error_m < 0.1
    assert len(store) == 0  # places are not throws
    store.close()


def test_bad_job_fails_with_the_named_field_before_anything_moves(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text((JOB % "  - {object: cube50, count: 1, bin: far}").replace("1.40", "fourteen"))
    db = tmp_path / "log.sqlite"
    assert main(["run", str(bad), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert "bad.yaml, line 4, bins[1].position_m[0]" in err and "must be a number" in err
    assert not db.exists()  # nothing was started


def test_run_json_summary_and_log(tmp_path):
    job = tmp_path / "job.yaml"
    job.write_text(
        JOB % "  - {object: sphere40, count: 1, bin: far}\n  - {object: cyl70, count: 1, bin: near}"
    )
    out = tmp_path / "out.json"
    db = tmp_path / "log.sqlite"
    fast = ["--no-cycle-search", "--no-turn-release"]  # the outputs are checked, not these
    assert main(["run", str(job), "--json", str(out), "--db", str(db)] + fast) == 0
    d = json.loads(out.read_text())
    for key in (
        "items",
        "placed",
        "thrown",
        "in_bin",
        "in_bin_rate",
        "mean_landing_error_m",
        "items_per_hour",
        "wall_time_s",
    ):
        assert key in d
    assert d["items"] == 2 and d["placed"] == 1 and d["thrown"] == 1
    assert d["in_bin"] == sum(r["in_bin"] for r in d["results"])
    with ThrowStore(db) as store:
        assert len(store) == 1


@pytest.mark.parametrize(
    ("signum", "code", "said"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")],
    ids=["ctrl-c", "sigterm"],
)
def test_an_interrupted_run_keeps_every_throw_already_recorded(tmp_path, signum, code, said):
    """Ctrl-C, or a SIGTERM (`kill`, `timeout`, a service manager), ends the run through
    its `finally`: every throw already recorded kept, the log intact, what was done said,
    and --json PATH holds the summary of the items finished, marked interrupted (it wrote
    nothing before)."""
    job = tmp_path / "job.yaml"
    # many items: the run must still be going when the second throw is on record (the loop
    # no longer waits for each flight, and a short run could finish before the SIGINT)
    job.write_text(JOB % "  - {object: cube50, count: 20, bin: far}")
    db = tmp_path / "log.sqlite"
    proc = subprocess.Popen(
        # the release search and the turn are not what is checked: off, for speed
        [sys.executable, "-m", "cell", "run", str(job), "--db", str(db)]
        + ["--no-cycle-search", "--no-turn-release", "--json", str(tmp_path / "run.json")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C as a terminal delivers it: an ignored SIGINT is inherited through exec,
        # and the test harness may have left it ignored (the run then ends with code 0)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        deadline = time.time() + 240
        n = 0
        while time.time() < deadline and proc.poll() is None:
            time.sleep(0.5)
            if db.exists():
                try:
                    with sqlite3.connect(db) as con:
                        n = con.execute("SELECT COUNT(*) FROM throws").fetchone()[0]
                except sqlite3.OperationalError:
                    n = 0
            if n >= 2:
                break
        assert n >= 2, "the run recorded no throws in time"
        assert proc.poll() is None, "the run ended before it could be interrupted"
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == code, err
    assert said in err
    with ThrowStore(db) as store:
        kept = len(store)
    assert n <= kept < 20
    said_kept = re.search(r"stopped after (\d+) of 20 items; (\d+) throws? kept in ", err)
    assert said_kept, err
    assert n <= int(said_kept[2]) <= kept
    part = json.loads((tmp_path / "run.json").read_text())
    assert part["interrupted"] is True and part["items_planned"] == 20
    assert part["plan_workers"] == 1  # the suite's $CELL_PLAN_WORKERS, as the run planned
    assert part["items"] == len(part["results"]) == int(said_kept[1])
    assert part["in_bin"] == sum(r["in_bin"] for r in part["results"])
    with sqlite3.connect(db) as con:
        assert con.execute("PRAGMA integrity_check").fetchone()[0] == "ok"


def test_a_job_drives_the_dynamixel_end_effector_in_step(tmp_path):
    """`cell run --ee dynamixel`: the hardware back-end (here on the emulated Protocol 2.0
    bus, through dynamixel-sdk) is commanded grasp, throw and place with the simulated one."""
    from cell.endeffector.factory import make_end_effector

    hw = make_end_effector("dynamixel", emulate=True, time_scale=8.0)
    calls = []
    for name in ("grasp", "throw", "place"):
        method = getattr(hw, name)

        def spy(*a, _m=method, _n=name):
            calls.append((_n, hw.status().latch_engaged))
            return _m(*a)

        setattr(hw, name, spy)
    job = parse_job(
        JOB % "  - {object: cube50, bin: far}\n  - {object: cyl70, bin: near}",
        str(tmp_path / "job.yaml"),
    )
    # the commands to the hardware are checked, not the release search or the turn: off
    orch = Orchestrator(job, end_effector=hw, cycle_search=False, turn_release=False)
    try:
        summary = orch.run()
    finally:
        orch.close()  # closes the hardware too: torque off
    assert [c[0] for c in calls] == ["grasp", "throw", "grasp", "place"]
    assert calls[1][1]  # the latch was engaged when the throw was commanded
    assert summary.in_bin == 2


def test_a_hardware_fault_mid_run_stops_the_run_with_torque_off(tmp_path, monkeypatch, capsys):
    """An overload on the spool after the first throw: the run stops (exit 3) with both servos'
    torque off and the throw already made kept, instead of failing every remaining item."""
    import dataclasses

    import cell.endeffector.factory as factory
    from cell.endeffector.dynamixel import DynamixelEndEffector, EmulatedBus, load_config

    cfg = load_config(factory.DEFAULT_DYNAMIXEL_CONFIG)
    cfg = dataclasses.replace(cfg, latency_timer_ms=factory.EMULATED_LATENCY_MS)
    emu = EmulatedBus.from_config(cfg, time_scale=8.0).start()
    hw = DynamixelEndEffector(cfg, port=emu.port, on_close=emu.stop)
    throw = hw.throw

    def throw_then_overload() -> None:
        throw()
        emu.servo(cfg.spool.id).set_hardware_error(1 << 5)  # overload: the servo shuts down

    hw.throw = throw_then_overload  # type: ignore[method-assign]
    monkeypatch.setattr(factory, "make_end_effector", lambda *a, **k: hw)
    job = tmp_path / "job.yaml"
    job.write_text(JOB % "  - {object: cube50, bin: far}\n  - {object: cyl70, bin: far, count: 3}")
    db = tmp_path / "log.sqlite"
    fast = ["--no-cycle-search", "--no-turn-release"]  # not what is checked: off, for speed
    code = main(["run", str(job), "--ee", "dynamixel", "--emulate", "--db", str(db)] + fast)
    err = capsys.readouterr().err
    assert code == 3, err
    assert "hardware fault" in err and "overload" in err and "Traceback" not in err
    assert "stopped after 1 of 4 items" in err
    for servo_id in (cfg.latch.id, cfg.spool.id):
        assert emu.servo(servo_id).value("torque_enable") == 0
    with ThrowStore(db, read_only=True) as store:
        assert len(store) == 1
