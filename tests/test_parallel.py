"""Campaigns on Ray (cell.parallel): a local Ray of 2 workers gives what the serial
run gives; a worker process that dies is retried and nothing is lost or doubled."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

from cell.bench.bench_sort import layout_units, run_layout, summarise_layouts  # noqa: E402
from cell.parallel import CampaignFailed, run_campaign  # noqa: E402

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))  # parallel_units, for the driver (workers get PYTHONPATH)


@pytest.fixture(scope="module")
def local_ray():
    ray.init(
        num_cpus=2,
        include_dashboard=False,
        log_to_driver=False,
        runtime_env={"env_vars": {"PYTHONPATH": os.pathsep.join([str(HERE), str(HERE.parent)])}},
    )
    yield
    ray.shutdown()


def _strip(layouts):
    """The layouts as JSON text without their wall times (NaN != NaN as floats)."""
    return json.dumps([{k: v for k, v in lay.items() if k != "wall_time_s"} for lay in layouts])


def test_a_campaign_on_two_workers_equals_the_serial_run(local_ray):
    units = layout_units(2, seed=5, max_items=3)
    serial = run_campaign(run_layout, units, workers=1, progress=False)
    on_ray = run_campaign(run_layout, units, workers=2, progress=False)
    assert _strip(serial) == _strip(on_ray)
    a, b = summarise_layouts(serial), summarise_layouts(on_ray)
    for d in (a, b):
        d.pop("wall_time_s")
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    assert a["items"] == 6


def test_a_killed_worker_is_retried_and_the_store_has_one_row_per_throw(local_ray, tmp_path):
    from parallel_units import throw_or_die_once

    from cell.log.store import ThrowStore
    from cell.sim.campaign import campaign_plan

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


def test_a_scene_campaign_on_ray_throws_what_the_serial_one_throws(local_ray):
    from cell.sim.campaign import campaign_plan
    from cell.sim.campaign import run_campaign as scene_campaign

    plan = campaign_plan(6, seed=3)
    a = scene_campaign(plan)
    b = scene_campaign(plan, workers=2)
    assert len(a) == len(b) == 6
    for col in ("object_id", "landed_x_m", "landed_y_m", "t_flight_s"):
        assert list(a.data[col]) == list(b.data[col])


def test_gap_check_on_ray_gives_the_serial_verdicts(local_ray):
    from cell.gap.check import run_check

    kw = dict(n=120, seed=1, repeats=2)
    a = run_check(("none", "band_mass"), **kw)
    b = run_check(("none", "band_mass"), workers=2, **kw)
    strip = [{k: v for k, v in r.__dict__.items() if k != "seconds"} for r in a]
    assert strip == [{k: v for k, v in r.__dict__.items() if k != "seconds"} for r in b]
