"""The cycle floor (`Orchestrator(floor=True)`, `cell bench sort --floor`): each item's
approach and throw's carry timed again as one direct move, beside the moves made.

Independent checks: the same job run without the floor (timing the floor must change
nothing the arm does), the bang-bang lower bound of a rest-to-rest move under each
joint's velocity and acceleration limits (a closed form no jerk-limited or path-following
move beats), the grip law itself (`grip_use`) on the direct move at the arm's full limits
(a carry's floor that would ask more of the grip must be slower), and the rate
recomputed from the items' cycles."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.arm.grip_limits import carry_hold
from cell.arm.tuning import TUNING
from cell.bench.bench_sort import floor_figures
from cell.catalogue import get_object
from cell.cli import main
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from cell.robot.carry import CARRY_MARGIN, grip_use
from cell.robot.motion import plan_move

# the UR5 (the departure's tests run the Panda too), a bin ahead and one behind the arm
JOB = """\
cell: {robot: ur5}
bins:
  - {id: ahead, position_m: [1.10, 0.50], size_m: [0.35, 0.35], rim_height_m: 0.10}
  - {id: behind, position_m: [-0.90, -0.90], size_m: [0.35, 0.35], rim_height_m: 0.12}
items:
  - {object: cube30, count: 1, bin: ahead}
  - {object: cyl40, count: 1, bin: behind}
seed: 3
"""


def bang_bang_s(q0: np.ndarray, q1: np.ndarray, v: np.ndarray, a: np.ndarray) -> float:
    """The least time [s] of a rest-to-rest move from q0 to q1 [rad] with each joint's
    speed within v [rad/s] and acceleration within a [rad/s²]: the slowest joint's
    triangle or trapezoid profile."""
    d = np.abs(np.asarray(q1) - np.asarray(q0))
    tri = d <= v * v / a
    t = np.where(tri, 2.0 * np.sqrt(d / a), d / v + v / a)
    return float(np.max(t))


def _run(tmp_path: Path, floor: bool, spy: list[Any] | None = None) -> tuple[Any, Orchestrator]:
    o = Orchestrator(parse_job(JOB, str(tmp_path / "job.yaml")), release="static", floor=floor)
    if spy is not None:
        time_floor = o._time_floor

        def spied(q_from: np.ndarray, t_from: float, settle_s: float = 0.0) -> None:
            before = o.floors.get(o._index, (0.0, 0.0))
            time_floor(q_from, t_from, settle_s)
            after = o.floors[o._index]
            spy.append((np.array(q_from), np.array(o.q), settle_s, after[1] - before[1]))

        o._time_floor = spied  # type: ignore[method-assign]
    try:
        return o.run(), o
    finally:
        o.close()


def test_timing_the_floor_changes_nothing_and_each_floor_keeps_to_the_arm_and_the_grip(
    tmp_path: Path,
) -> None:
    plain, _ = _run(tmp_path, floor=False)
    spy: list[Any] = []
    timed, orch = _run(tmp_path, floor=True, spy=spy)
    assert [r.action for r in timed.results] == ["throw", "throw"]
    for a, b in zip(plain.results, timed.results, strict=True):
        assert a.cycle_time_s == b.cycle_time_s
        assert a.landing_error_m == b.landing_error_m or (
            math.isnan(a.landing_error_m) and math.isnan(b.landing_error_m)
        )
    # an approach and a carry per item, each floor within the bang-bang bound and the move
    assert len(spy) == 4
    lim = orch.robot.limits
    for q0, q1, settle, floor in spy:
        assert floor >= bang_bang_s(q0, q1, lim.velocity, lim.acceleration) + settle - 1e-9
    for r in timed.results:
        spent, floor = orch.floors[r.index]
        assert 0.0 < floor <= spent < r.cycle_time_s
    # a carry's floor is no faster than the grip allows: where the direct move at the arm's
    # full limits would ask more of the grip than a carry may (the grip law, `grip_use`),
    # its floor is slower than that move
    # each item's approach is timed first, then its carry (after it, TUNING.settle_s)
    assert [settle for _, _, settle, _ in spy[1::2]] == [TUNING.settle_s] * 2
    carries = [(q0, q1, f) for q0, q1, _, f in spy[1::2]]
    over = 0
    for (q0, q1, floor), r in zip(carries, timed.results, strict=True):
        hold = carry_hold(orch.params, get_object(r.object_id), r.stroke_m, probed=True)
        direct = plan_move(q0, None, q1, None, orch.robot)
        if grip_use(direct, orch.robot, hold) > 1.0 / CARRY_MARGIN:
            over += 1
            assert floor > direct.duration + TUNING.settle_s + 1e-3
    assert over >= 1
    # the routes (the departure upward, the level swing, the stop over the pick) cost time
    assert sum(orch.floors[r.index][0] - orch.floors[r.index][1] for r in timed.results) > 0.0


def test_the_floor_rate_is_the_in_bin_count_over_the_floor_cycles() -> None:
    items = [
        {"in_bin": True, "floor_cycle_s": 1.5},
        {"in_bin": False, "floor_cycle_s": 2.5},
        {"in_bin": True, "floor_cycle_s": 2.0},
    ]
    figures = floor_figures(items)
    assert figures["floor_items_per_hour"] == pytest.approx(3600.0 * 2 / 6.0)
    assert figures["floor_sim_time_s"] == pytest.approx(6.0)
    # a campaign run without the floor has none to report
    assert floor_figures([{"in_bin": True, "cycle_time_s": 2.0}]) == {}
    assert floor_figures([]) == {}


def test_cli_bench_sort_with_the_floor_reports_a_rate_no_lower_than_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["bench", "sort", "--set", "tune", "--layouts", "1", "--seed", "12", "--max-items", "2"]
    assert main([*argv, "--floor", "--json", "--out", str(tmp_path)]) == 0
    figures = json.loads(capsys.readouterr().out)
    layout = json.loads((tmp_path / "layout_12.json").read_text())
    cycles = [it["cycle_time_s"] for it in layout["items"]]
    floors = [it["floor_cycle_s"] for it in layout["items"]]
    assert len(floors) == 2 and all(0.0 < f <= c for f, c in zip(floors, cycles, strict=True))
    k = sum(it["in_bin"] for it in layout["items"])
    assert figures["floor_items_per_hour"] == pytest.approx(3600.0 * k / sum(floors))
    assert figures["floor_items_per_hour"] >= figures["items_per_hour"]
    assert figures["per_layout"][0]["floor_items_per_hour"] == figures["floor_items_per_hour"]
