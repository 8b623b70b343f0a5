"""The kinematic plant (`cell.sim.kinematic.KinematicPlant`) and the item loop on it.

The plant moves a released item by the model's drag-free flight: its landings are checked
against the parabola's closed form. On it, the loop (`cell.loop.ItemLoop`) is checked
without PyBullet: a throwing platform that overlaps its items has each flight scored
through the hook the loop hands it (`land`, called after each of its moves, as the arm's
mover does), cycles that run pick to pick and add up to the plant's time, items per hour
counting only items in their bins, the landing error from the decision's goal, and the
landing told to `on_landed`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.decision import Decision
from cell.jobs import parse_job
from cell.loop import ItemLoop
from cell.model.params import G
from cell.results import landing
from cell.sim.bins import BinSpec
from cell.sim.kinematic import KinematicPlant

STATION = np.array([0.4, -0.4, 0.6])  # [m, W] where the platform releases each item
FLIGHT_S = 0.8  # [s] from the release to the rim plane
CARRY_S = 0.5  # [s] each item's pick and carry: the last item still flies meanwhile

JOB = """\
cell: {robot: panda}
bins:
  - {id: near, position_m: [1.2, 0.3], size_m: [0.3, 0.3], rim_height_m: 0.1}
  - {id: far, position_m: [2.0, -0.8], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cube50, count: 2, bin: near}
  - {object: cyl50, count: 2, bin: far}
seed: 0
"""


def velocity_to(p0: np.ndarray, goal: np.ndarray, t_s: float) -> np.ndarray:
    """The launch velocity [m/s] that puts a drag-free centre from p0 at `goal` [m, W]
    after t_s [s]: the parabola's closed form."""
    return (goal - p0 + np.array([0.0, 0.0, 0.5 * G * t_s * t_s])) / t_s


def test_a_released_item_crosses_the_rim_plane_where_the_parabola_does() -> None:
    bin_ = BinSpec("b", (1.5, 0.2), (0.3, 0.3), 0.12)
    plant = KinematicPlant([bin_])
    from cell.catalogue import get_object

    item = plant.spawn_item(get_object("cube50"), STATION)
    goal = np.array([1.47, 0.23, 0.12])
    plant.launch(item, velocity_to(STATION, goal, 0.9))
    out = plant.watch_until_rest(item)
    cross, z = landing(out, 0.12)
    assert z == 0.12
    # between two steps 1/240 s apart the chord is off the parabola by g dt²/8 at most
    assert cross[:2] == pytest.approx(goal[:2], abs=1e-6)
    assert cross[2] == pytest.approx(0.9, abs=1e-6)
    assert out.bin_id == "b" and out.rested
    assert out.rest_xyz[2] == pytest.approx(bin_.wall + 0.025)  # on the floor plate


def test_an_item_thrown_past_the_bins_rests_on_the_floor_in_none() -> None:
    from cell.catalogue import get_object

    plant = KinematicPlant([BinSpec("b", (1.5, 0.2), (0.3, 0.3), 0.12)])
    item = plant.spawn_item(get_object("cube50"), STATION)
    plant.launch(item, velocity_to(STATION, np.array([3.0, 1.0, 0.025]), 1.0))
    out = plant.watch_until_rest(item)
    assert out.bin_id is None
    assert out.rest_xyz == pytest.approx((3.0, 1.0, 0.025), abs=1e-9)
    assert out.t_rest == pytest.approx(1.0, abs=1.5 / 240)


class Thrower:
    """A platform that throws each item from STATION to its bin's goal in FLIGHT_S,
    taking CARRY_S of plant time to pick and carry it, and calling the loop's hook after
    that move (`on_moved`); `aims` may send an item elsewhere than its goal."""

    name = "thrower"
    overlaps = True
    rotor_rpm = 0.0

    def __init__(self, plant: KinematicPlant, aims: dict[int, tuple[float, float]]) -> None:
        self.plant, self.aims = plant, aims
        self.on_moved: Callable[[], None] = lambda: None
        self.scored_before_release: list[int] = []  # landings told by the time of a release
        self.landed: list[tuple[int, tuple[float, float, float]]] = []
        self._index = -1
        self.place_next = False

    def present(self, index: int, obj: Any) -> Any:
        self._index = index
        return self.plant.spawn_item(obj, STATION)

    def decide(self, index: int, obj: Any, target: Any) -> Decision:
        goal = (float(target.position[0]), float(target.position[1]))
        action = "place" if self.place_next else "throw"
        return Decision(action, 0.05, goal_xy=goal, state=(index, target))

    def pick(self, d: Decision, obj: Any, item: Any) -> None:
        self.plant.step(round(CARRY_S / 2 / self.plant.dt_s))

    def carry(self, d: Decision, obj: Any, item: Any) -> None:
        self.plant.step(round(CARRY_S / 2 / self.plant.dt_s))
        self.on_moved()  # the loop's hook: flights at rest are scored now

    def release(self, d: Decision) -> None:
        index, target = d.state
        self.scored_before_release.append(len(self.landed))
        xy = self.aims.get(index, d.goal_xy)
        goal = np.array([xy[0], xy[1], target.rim_height])
        self.plant.launch(self.plant.items[-1], velocity_to(STATION, goal, FLIGHT_S))

    def finish(self, d: Decision | None) -> None:
        """Nothing is held."""

    def on_landed(self, d: Decision, obj: Any, crossing: Any) -> None:
        self.landed.append((d.state[0], tuple(crossing)))


def run_on_kinematic_plant(
    tmp_path: Path, aims: dict[int, tuple[float, float]], place: bool = False
) -> tuple[Any, Thrower, KinematicPlant]:
    job = parse_job(JOB, str(tmp_path / "job.yaml"))
    plant = KinematicPlant([BinSpec(b.id, b.position, b.size, b.rim_height) for b in job.bins])
    pf = Thrower(plant, aims)
    pf.place_next = place
    loop = ItemLoop(job, pf, plant, on_landed=pf.on_landed)
    pf.on_moved = loop.land  # the hook the loop hands the platform
    return loop.run(), pf, plant


def test_the_loop_scores_each_flight_through_the_hook_and_accounts_pick_to_pick(
    tmp_path: Path,
) -> None:
    summary, pf, plant = run_on_kinematic_plant(tmp_path, aims={})
    rows = [(r.object_id, r.action, r.in_bin, r.failure) for r in summary.results]
    assert rows == [
        ("cube50", "throw", True, ""),
        ("cube50", "throw", True, ""),
        ("cyl50", "throw", True, ""),
        ("cyl50", "throw", True, ""),
    ]
    # item n−1 (0.8 s in the air, 0.5 s each carry) has landed and been scored through
    # the hook by the time item n+1 is released, not after the run
    assert pf.scored_before_release == [0, 0, 1, 2]
    # every landing crossed its bin's rim plane at the goal (the parabola's closed form)
    for (i, cross), r in zip(sorted(pf.landed), summary.results, strict=True):
        assert r.landing_error_m < 1e-6, (i, cross)
        assert cross[2] == pytest.approx(FLIGHT_S, abs=1e-6)
    # cycles run pick to pick; the last one until every flight has come to rest
    cycles = [r.cycle_time_s for r in summary.results]
    assert cycles[:-1] == pytest.approx([CARRY_S] * 3, abs=1e-9)
    assert sum(cycles) == pytest.approx(plant.t, abs=1e-9) == pytest.approx(summary.sim_time_s)
    assert summary.items_per_hour == pytest.approx(4 * 3600.0 / plant.t)


def test_a_throw_that_misses_is_scored_from_its_goal_and_not_counted(tmp_path: Path) -> None:
    off = (1.2, 0.75)  # 0.45 m beyond the near bin's centre, out of its 0.3 m footprint
    summary, pf, plant = run_on_kinematic_plant(tmp_path, aims={1: off})
    r = summary.results[1]
    assert (r.action, r.in_bin, r.failure) == ("throw", False, "missed_bin")
    assert r.landing_error_m == pytest.approx(math.hypot(0.0, 0.45), abs=1e-6)
    assert summary.items_per_hour == pytest.approx(3 * 3600.0 / plant.t)
    assert len(pf.landed) == 4  # every crossing of a rim plane is told, a miss too


def test_a_platform_that_does_not_place_fails_a_place_and_goes_on(tmp_path: Path) -> None:
    summary, _, _ = run_on_kinematic_plant(tmp_path, aims={}, place=True)
    assert all(r.action == "failed" for r in summary.results)
    assert all("does not place" in r.reason for r in summary.results)
