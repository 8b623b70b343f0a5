"""Campaigns on Ray (cell.parallel): a local Ray of 2 workers gives what the serial
run gives; a worker process that dies is retried and nothing is lost or doubled; a unit
lost twice, and Ctrl-C, stop the campaign keeping what the driver handled."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

ray = pytest.importorskip("ray")

from cell.parallel import CampaignFailed, run_campaign  # noqa: E402

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))  # parallel_units, for the driver (workers get PYTHONPATH)


@pytest.fixture(scope="module")
def local_ray():
    ray.init(
        address="local",  # a new Ray, even if `ray start` runs one on this machine
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        runtime_env={"env_vars": {"PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}},
    )
    yield
    ray.shutdown()


def _strip(layouts):
    """The layouts as JSON text without their wall-clock figures (the wall time, each
    item's planning time; NaN != NaN as floats)."""
    from cell.results import WALL_CLOCK_KEYS

    return json.dumps(
        [
            {
                **{k: v for k, v in lay.items() if k not in WALL_CLOCK_KEYS},
                "items": [
                    {k: v for k, v in it.items() if k not in WALL_CLOCK_KEYS}
                    for it in lay.get("items", [])
                ],
            }
            for lay in layouts
        ]
    )


def _bench_sort(tmp_path, tag, capsys, *extra):
    """`cell bench sort` on 3 test-set layouts of 1 item each: its figures without the
    wall time, and each layout's result (--out) as JSON text without its wall time. Seeds
    1005-1007 (arms ur5, panda, ur5 in turn): 4.0, 2.3 and 2.5 CPU-s a layout in a warm
    process, where 1004 (the fourth layout this test ran before) took 3.8."""
    from cell.cli import main

    out = tmp_path / tag
    argv = ["bench", "sort", "--layouts", "3", "--seed", "1005", "--robots", "ur5,panda"]
    argv += ["--max-items", "1"]
    assert main([*argv, "--json", "--out", str(out), *extra]) == 0
    figures = json.loads(capsys.readouterr().out)
    from cell.results import WALL_CLOCK_KEYS

    for k in WALL_CLOCK_KEYS:
        figures.pop(k, None)
    layouts = [json.loads((out / f"layout_{s}.json").read_text()) for s in range(1005, 1008)]
    return json.dumps(figures, sort_keys=True), _strip(layouts)


def test_cli_bench_sort_on_two_workers_equals_the_serial_run(local_ray, tmp_path, capsys):
    # 3 layouts on 2 workers: a worker process runs the third layout after another one,
    # as the serial run does its second and third (one item a layout: what one layout
    # leaves in a process shows in the next one's item)
    serial = _bench_sort(tmp_path, "serial", capsys)
    on_ray = _bench_sort(tmp_path, "ray", capsys, "--workers", "2")
    assert serial[1] == on_ray[1]  # every layout, item for item, to the last digit
    assert serial[0] == on_ray[0]
    figures = json.loads(serial[0])
    assert figures["set"] == "test" and figures["seeds"] == [1005, 1007]
    assert figures["items"] == 3 and figures["layouts"] == 3


def test_a_scene_campaign_on_ray_throws_what_the_serial_one_throws(local_ray):
    from cell.workflows.campaign import campaign_plan
    from cell.workflows.campaign import run_campaign as scene_campaign

    plan = campaign_plan(6, seed=3)
    a = scene_campaign(plan)
    b = scene_campaign(plan, workers=2)
    assert len(a) == len(b) == 6
    for col in ("object_id", "landed_x_m", "landed_y_m", "t_flight_s"):
        assert list(a.data[col]) == list(b.data[col])


def test_gap_check_on_ray_gives_the_serial_verdicts(local_ray):
    from cell.gap.check import run_check

    kw = dict(n=60, seed=1, repeats=2)
    a = run_check(("none", "band_mass"), **kw)
    b = run_check(("none", "band_mass"), workers=2, **kw)
    strip = [{k: v for k, v in r.__dict__.items() if k != "seconds"} for r in a]
    assert strip == [{k: v for k, v in r.__dict__.items() if k != "seconds"} for r in b]


def _calibrate(tmp_path, tag, capsys, *extra):
    from cell.cli import main

    files = {k: tmp_path / f"{tag}.{k}" for k in ("yaml", "csv", "sqlite")}
    # 8 ad-hoc throws for the mass rule, one chunk of cell.workflows.campaign.CHUNK (the
    # campaign's 16 are the two chunks on two workers; the default 160 adds minutes, and
    # no new path)
    argv = ["calibrate", "--n", "16", "--adhoc", "8", "--seed", "4", "--json"]
    argv += ["-o", str(files["yaml"])]
    argv += ["--log", str(files["csv"]), "--db", str(files["sqlite"]), *extra]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    summary.pop("output")
    return summary, files


def test_cli_calibrate_on_two_workers_writes_what_the_serial_run_writes(
    local_ray, tmp_path, capsys
):
    from cell.log.store import ThrowStore

    serial, a = _calibrate(tmp_path, "serial", capsys)
    on_ray, b = _calibrate(tmp_path, "ray", capsys, "--workers", "2")
    assert serial == on_ray  # the identified parameters, the gaps, the mass rule
    assert serial["throws"] == 16
    assert a["csv"].read_text() == b["csv"].read_text()  # the log, row for row
    assert a["yaml"].read_text() == b["yaml"].read_text()
    # the driver appended both chunks as they arrived: one row per throw, the same rows
    with ThrowStore(a["sqlite"]) as sa, ThrowStore(b["sqlite"]) as sb:
        ta, tb = sa.table(), sb.table()
        assert len(sa) == len(sb) == 16
    ids = tb.text("throw_id")
    assert sorted(ids) == ta.text("throw_id") and len(set(ids)) == 16
    order = sorted(range(16), key=lambda k: ids[k])
    for col in ("object_id", "landed_x_m", "landed_y_m", "t_flight_s", "stroke_m"):
        assert list(ta.data[col]) == [tb.data[col][k] for k in order]


def test_cli_calibrate_refuses_a_store_that_holds_the_campaign_already(tmp_path, capsys):
    from cell.cli import main
    from cell.log.store import ThrowStore
    from cell.workflows.campaign import campaign_plan
    from cell.workflows.campaign import run_campaign as scene_campaign

    db = tmp_path / "s.sqlite"
    with ThrowStore(db) as store:
        store.import_table(scene_campaign(campaign_plan(1, seed=4)))
    argv = ["calibrate", "--n", "16", "--seed", "4", "--db", str(db), "--workers", "2"]
    assert main(argv + ["-o", str(tmp_path / "e.yaml")]) == 2
    err = capsys.readouterr().err
    assert "already holds 1 throw of" in err and "cal004-0000" in err
    with ThrowStore(db) as store:
        assert len(store) == 1  # nothing thrown, nothing written


def test_an_address_where_no_ray_answers_is_refused_at_once(tmp_path, capsys):
    import socket

    from cell.cli import main

    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    argv = ["calibrate", "--n", "10", "--ray-address", f"127.0.0.1:{port}"]
    assert main(argv + ["-o", str(tmp_path / "e.yaml")]) == 2
    err = capsys.readouterr().err
    assert f"--ray-address 127.0.0.1:{port}: no Ray cluster answers there" in err
    assert "ray start --head" in err


def test_bench_ray_figures(local_ray):
    from cell.bench import available
    from cell.bench.bench_ray import run

    assert "ray" in available()
    fig = run(quick=True)  # on the module's Ray: its start is not measured here
    assert np.isnan(fig["ray_start_s"])
    for key in ("ray_task_overhead_ms", "ray_roundtrip_ms", "store_chunk_append_ms"):
        assert 0 < fig[key] < 1e4, key
    assert 0 < fig["scene_chunk_cpu_s"] < 600


def test_cli_learn_fits_on_two_workers_give_the_serial_table(local_ray, tmp_path, capsys):
    from cell.cli import main
    from cell.log import write_throws_csv
    from cell.model import DEFAULT_EE
    from cell.residual.campaign import shape_stretch_hook
    from cell.synth import Campaign, NoiseModel, World, draw_campaign

    noise = NoiseModel(along_rel=0.005, across_rel=0.0025, floor_m=0.003)
    world = World(ee=DEFAULT_EE, noise=noise, predict=shape_stretch_hook(0.1))
    log = tmp_path / "throws.csv"
    write_throws_csv(draw_campaign(world, Campaign(n=140, stroke_m=(0.04, 0.10)), seed=4), log)
    docs = []
    for extra in ([], ["--workers", "2"]):
        argv = ["learn", str(log), "-o", str(tmp_path / "r.skops"), "--grid", "small"]
        assert main([*argv, "--compare", "svr", "--json", *extra]) == 0
        docs.append(json.loads(capsys.readouterr().out))
    assert set(docs[0]) == {"svr", "saved"}
    assert len(docs[0]["svr"]["folds"]) == 7  # 14 objects, 2 held out a fold
    assert docs[0] == docs[1]  # every fold's figures and chosen hyper-parameters


# Last, the tests that end worker processes: a worker dies (killed, or always dying), or
# the campaign stops early (a unit that raises, Ctrl-C), which cancels the tasks still out
# and ends the workers running them. A new worker imports the cell again: until here the
# tests' units run on workers that imported it for the first test; below, only the first
# test needs the cell on a worker, on its dead one's replacement (the retried throw)
def test_a_killed_worker_is_retried_and_the_store_has_one_row_per_throw(local_ray, tmp_path):
    from parallel_units import throw_or_die_once

    from cell.log.store import ThrowStore
    from cell.workflows.campaign import campaign_plan

    marker = tmp_path / "died"
    plan = campaign_plan(5, seed=2)
    store = ThrowStore(tmp_path / "throws.sqlite")
    try:
        # the driver is the only writer: one transaction per row, as results arrive
        out = run_campaign(
            throw_or_die_once,
            [(str(marker), p) for p in plan],
            workers=2,
            on_result=lambda i, rec: store.append(rec),
            progress=False,
        )
        ids = store.table().text("throw_id")
        assert len(store) == len(plan)
    finally:
        store.close()
    assert marker.exists()  # one worker process did die mid-campaign
    assert [r["throw_id"] for r in out] == [p["throw_id"] for p in plan]
    assert sorted(ids) == sorted(p["throw_id"] for p in plan)  # one row per throw


def test_a_unit_that_raises_is_reported_by_name(local_ray):
    from parallel_units import fails_on_three

    with pytest.raises(CampaignFailed, match="unit 3"):
        run_campaign(fails_on_three, list(range(5)), workers=2, progress=False)


def test_ctrl_c_cancels_the_campaign_and_keeps_what_was_handled(local_ray):
    from parallel_units import square

    got: list[int] = []

    def handle(i: int, r: int) -> None:
        got.append(r)
        if len(got) == 2:
            raise KeyboardInterrupt  # as Ctrl-C in the driver while results arrive

    with pytest.raises(KeyboardInterrupt):
        run_campaign(square, list(range(40)), workers=2, on_result=handle, progress=False)
    assert len(got) == 2
    # the same Ray runs the next campaign to the end: nothing of the cancelled one is left
    assert run_campaign(square, list(range(6)), workers=2, progress=False) == [0, 1, 4, 9, 16, 25]


def test_a_unit_whose_worker_always_dies_is_retried_once_then_reported_as_lost(local_ray, tmp_path):
    from parallel_units import dies_on_two

    attempts = tmp_path / "attempts"
    got: dict[int, int] = {}
    with pytest.raises(
        CampaignFailed, match=r"unit 2 \(\(2, .*\) was lost: its worker died 2 time"
    ):
        run_campaign(
            dies_on_two,
            [(k, str(attempts)) for k in range(6)],
            workers=2,
            on_result=got.__setitem__,
            progress=False,
        )
    assert attempts.read_text() == "died\n" * 2  # the first try and Ray's one retry
    assert 2 not in got
    assert all(v == k * k for k, v in got.items())  # what was handled before is right
