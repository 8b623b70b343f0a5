"""Honest accounting: cycles cover the whole run, only sorted items count."""

from __future__ import annotations

import json

from cell.cli import main
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

ALL_FAIL = """
bins:
  - {id: tall, position_m: [-0.70, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.90}
items:
  - {object: cube50, count: 1, bin: tall}
"""

MIXED = """
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: tall, position_m: [-0.70, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.90}
items:
  - {object: cube50, count: 1, bin: far}
  - {object: cube50, count: 1, bin: tall}
  - {object: cyl70, count: 1, bin: near}
"""


def test_a_run_whose_items_all_fail_sorts_nothing_and_exits_non_zero(tmp_path):
    job, out = tmp_path / "job.yaml", tmp_path / "out.json"
    job.write_text(ALL_FAIL)
    code = main(["run", str(job), "--no-log", "--json", str(out)])
    s = json.loads(out.read_text())
    assert code != 0
    assert s["in_bin"] == 0 and s["items_per_hour"] == 0.0
    assert s["results"][0]["failure"] == "ik"


def test_cycles_add_up_to_the_whole_run_and_only_sorted_items_count():
    orch = Orchestrator(parse_job(MIXED, "mixed.yaml"))
    t_start = orch.scene.t
    try:
        s = orch.run()
        t_end = orch.scene.t
    finally:
        orch.close()
    assert abs(s.sim_time_s - (t_end - t_start)) < 1e-6  # no time is left out
    assert [r.failure for r in s.results] == ["", "ik", ""]
    assert s.results[1].cycle_time_s > 0  # the failed item's time counts too
    assert abs(s.items_per_hour - 3600.0 * 2 / s.sim_time_s) < 1e-6
