"""Planning in real time: each item's planning wall time (`plan_s`), the run's figures of
it, and the real-time rate (`cell.results.realtime_cycles`, docs/realtime.md).

No speed is asserted here (speed goals are figures of `cell bench`): the checks are that
`plan_s` counts the platform's work and not the plant's stepping (a platform that sleeps a
known time in `decide`, a plant that sleeps in its steps), that the summary's figures are
those of the items' values, and the real-time formula against a hand computation.
"""

from __future__ import annotations

import dataclasses
import json
import math
import statistics
import time
from pathlib import Path
from typing import Any

import pytest

from cell.cli import main
from cell.jobs import load_job, parse_job
from cell.loop import ItemLoop
from cell.results import ItemResult, rate_per_hour, realtime_cycles, summarise
from cell.sim.bins import BinSpec
from cell.sim.kinematic import KinematicPlant
from tests.test_kinematic_plant import JOB, Thrower

DECIDE_S = 0.05  # [s] the platform's decision sleeps this long
STEP_SLEEP_S = 0.002  # [s] the slow plant sleeps this long in each step it is asked for


class SlowPlant(KinematicPlant):
    """A kinematic plant whose stepping takes wall time (a sleep per call), counted in its
    `step_wall_s` as the plant's own."""

    def step(self, n: int = 1) -> None:
        t0, before = time.perf_counter(), self.step_wall_s
        time.sleep(STEP_SLEEP_S)
        super().step(n)
        self.step_wall_s = before + time.perf_counter() - t0  # the sleep is the plant's


class Deliberate(Thrower):
    """The kinematic plant's thrower, deciding for DECIDE_S of wall time."""

    def decide(self, index: int, obj: Any, target: Any) -> Any:
        time.sleep(DECIDE_S)
        return super().decide(index, obj, target)


def _run(tmp_path: Path) -> Any:
    job = parse_job(JOB, str(tmp_path / "job.yaml"))
    plant = SlowPlant([BinSpec(b.id, b.position, b.size, b.rim_height) for b in job.bins])
    pf = Deliberate(plant, {})
    loop = ItemLoop(job, pf, plant, on_landed=pf.on_landed)
    pf.on_moved = loop.land
    t0 = plant.step_wall_s
    summary = loop.run()
    return summary, plant.step_wall_s - t0


def test_plan_s_counts_the_decision_and_not_the_plants_stepping(tmp_path: Path) -> None:
    summary, stepping = _run(tmp_path)
    plans = [r.plan_s for r in summary.results]
    assert len(plans) == 4 and all(math.isfinite(p) for p in plans)
    # each decision slept DECIDE_S: the item's planning time is at least that
    assert min(plans) >= DECIDE_S
    # the plant slept in each of its steps, 2 calls an item in the platform's pick and
    # carry: counted as the plant's; were it counted as planning, plan_s would be over
    # DECIDE_S + 2 STEP_SLEEP_S each
    assert stepping >= 4 * 2 * STEP_SLEEP_S
    assert sum(plans) < summary.wall_time_s - 4 * 2 * STEP_SLEEP_S + 1e-9
    assert summary.plan_workers == 1  # a platform without `plan_workers` plans serially


SMALL_JOB = """\
cell: {robot: panda}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, count: 2, bin: far}
  - {object: cyl70, count: 1, bin: near}
"""
# SMALL_JOB's bins and its first item alone
ONE_ITEM_JOB = SMALL_JOB.split("items:")[0] + "items:\n  - {object: cube50, count: 1, bin: far}\n"


def test_run_json_has_each_items_plan_s_and_its_figures(tmp_path: Path) -> None:
    job = tmp_path / "job.yaml"
    job.write_text(SMALL_JOB)
    out = tmp_path / "out.json"
    fast = ["--no-cycle-search", "--no-turn-release"]  # the figures are checked, not these
    assert main(["run", str(job), "--no-log", "--json", str(out)] + fast) == 0
    d = json.loads(out.read_text())
    plans = [r["plan_s"] for r in d["results"]]
    assert len(plans) == 3 and all(math.isfinite(p) and p >= 0.0 for p in plans)
    assert d["plan_s_median"] == pytest.approx(statistics.median(plans))
    assert d["plan_s_max"] == max(plans)
    assert min(plans) <= d["plan_s_p95"] <= max(plans)
    assert d["cores"] >= 1
    # the real-time rate never exceeds the simulated one
    assert 0.0 <= d["items_per_hour_realtime"] <= d["items_per_hour"]
    # nor is it more than the items in their bins over the sum of the simulated cycles
    # and all the planning (none of it hidden)
    cycles = sum(r["cycle_time_s"] for r in d["results"])
    assert d["items_per_hour_realtime"] >= rate_per_hour(d["in_bin"], cycles + sum(plans))


@pytest.mark.parametrize("workers", [1, 2])
def test_run_says_the_plan_workers_it_planned_on(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], workers: int
) -> None:
    # beside `cores` in the JSON and on the printed "planning per item" line, the
    # `--plan-workers` given (the suite's $CELL_PLAN_WORKERS is 1: it is not what is read),
    # on one item: the count is said once for the run, whatever its items
    job = tmp_path / "job.yaml"
    job.write_text(ONE_ITEM_JOB)
    out = tmp_path / "out.json"
    fast = ["--no-cycle-search", "--no-turn-release", "--plan-workers", str(workers)]
    assert main(["run", str(job), "--no-log", "--json", str(out)] + fast) == 0
    d = json.loads(out.read_text())
    assert d["plan_workers"] == workers
    line = next(x for x in capsys.readouterr().out.splitlines() if "planning per item" in x)
    said = "1 plan worker)" if workers == 1 else "2 plan workers)"
    assert line.endswith(f"(wall time, {d['cores']} cores, {said}")


def test_realtime_cycles_by_hand() -> None:
    # item 0 planned in 1 s before the arm starts; item 1's plan (3 s) is longer than item
    # 0's 2 s motion; item 2's (0.5 s) hides behind item 1's; item 3's 2.5 s behind
    # item 2's 2.4 s not quite; the last item's motion has no plan after it to wait for
    cycles = [2.0, 2.0, 2.4, 1.5]
    plans = [1.0, 3.0, 0.5, 2.5]
    # the arm starts item 0 at 1.0; item 1's plan, begun then, ends at 4.0 (arm free at
    # 3.0): item 1 starts at 4.0; item 2's plan is ready at 4.5, the arm at 6.0; item 3's
    # at 6.0 + 2.5 = 8.5, the arm at 8.4; the run ends at 8.5 + 1.5 = 10.0
    assert realtime_cycles(cycles, plans) == pytest.approx([4.0, 2.0, 2.5, 1.5])
    assert sum(realtime_cycles(cycles, plans)) == pytest.approx(10.0)
    # no planning: the simulated cycles; a plan not measured counts as none
    assert realtime_cycles(cycles, [0.0] * 4) == cycles
    assert realtime_cycles(cycles, [math.nan] * 4) == cycles
    assert realtime_cycles([], []) == []
    with pytest.raises(ValueError, match="3 cycles but 2"):
        realtime_cycles([1.0, 1.0, 1.0], [0.0, 0.0])


def test_summary_figures_are_those_of_the_items() -> None:
    plans = [0.3, 0.1, 2.0, 0.2, math.nan]
    cycles = [2.0, 2.5, 1.8, 2.2, 2.0]
    results = [
        ItemResult(i, "cube50", "b", "throw", in_bin=i != 1, cycle_time_s=c, plan_s=p)
        for i, (c, p) in enumerate(zip(cycles, plans, strict=True))
    ]
    s = summarise(results, 10.0)
    assert s.plan_s_median == pytest.approx(0.25)  # of the four measured
    # the 95th percentile, linearly between order statistics: 0.3 + 0.85 (2.0 − 0.3)
    assert s.plan_s_p95 == pytest.approx(0.3 + 0.85 * 1.7)
    assert s.plan_s_max == 2.0
    # real-time cycles: 2.0 + 0.3, max(2.5, 2.0), max(1.8, 0.2), 2.2 (NaN: none), 2.0
    real = 2.3 + 2.5 + 1.8 + 2.2 + 2.0
    assert s.items_per_hour_realtime == pytest.approx(4 * 3600.0 / real)
    assert s.items_per_hour == pytest.approx(4 * 3600.0 / sum(cycles))
    assert s.items_per_hour_realtime <= s.items_per_hour
    d = s.as_dict()
    assert [r["plan_s"] for r in d["results"]][:4] == plans[:4]


def test_bench_sorts_figures_count_each_layout_as_a_run_of_its_own() -> None:
    from cell.bench.bench_realtime import realtime_figures

    def item(cycle: float, plan: float, in_bin: bool = True) -> dict[str, Any]:
        return {"cycle_time_s": cycle, "plan_s": plan, "in_bin": in_bin}

    layouts = [
        {"items": [item(2.0, 1.0), item(2.0, 3.0)]},  # 1 + max(2, 3) + 2 = 6 s
        {"items": [item(1.5, 0.5, False), item(2.5, 1.0)]},  # 0.5 + max(1.5, 1) + 2.5 = 4.5 s
    ]
    f = realtime_figures(layouts)
    assert f["items_per_hour_realtime"] == pytest.approx(3 * 3600.0 / (6.0 + 4.5))
    assert f["plan_s_max"] == 3.0
    assert f["plan_s_median"] == pytest.approx(1.0)
    assert f["cores"] >= 1
    # a layout written before plan_s was measured: no figures rather than wrong ones
    assert realtime_figures([{"items": [{"cycle_time_s": 2.0, "in_bin": True}]}]) == {}


def test_a_run_plans_on_one_blas_thread_whoever_calls_it(monkeypatch: pytest.MonkeyPatch) -> None:
    """`cell bench --only realtime` ran its jobs through `Orchestrator.run` with the process's
    BLAS threads (two here), where `cell run` set one: two in each planning process fought
    over the 2 cores, the demo's `plan_s` p95 1.0 s against `cell run`'s 0.55 s.
    `Orchestrator.run` now runs on one, whoever calls it; the run itself is the real one
    (one item of the demo, through the bench)."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from cell.bench import bench_realtime

    seen: list[int] = []
    real_run = ItemLoop.run

    def run(self: ItemLoop, *args: Any, **kw: Any) -> Any:
        seen.extend(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
        return real_run(self, *args, **kw)

    monkeypatch.setattr(ItemLoop, "run", run)
    job = load_job(Path(__file__).resolve().parents[1] / "tasks" / "bins.yaml")
    with threadpool_limits(limits=2):
        assert {p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"} == {2}
        f = bench_realtime._run_job(dataclasses.replace(job, max_items=1), "t")
    assert seen and set(seen) == {1}
    assert f["t_items"] == 1.0
