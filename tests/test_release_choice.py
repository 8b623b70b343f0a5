"""With `cycle_search` (on by default), the release a throw is carried to: the
one the decision chose and timed, in the release bounds whose cycle is the sooner
(`Orchestrator._release_costs`, `_release_branch`, `_plan_facing`). Run without the turn
toward the station (`turn_release=False`), as these were measured: turned, the carries
of this job go elsewhere and its second item's is no longer one IK solves apart.

Random layout 2's geometry (Panda). Without the search the carry solves the release's IK again
from the pick, and on this job's second item (a 67 mm cube) that lands 3.13 rad away in a
wrist joint from the configuration the decision timed: its carry took 2.11 s in the scene
against the 1.06 s timed. And without it the plan is made in the cell's release bounds,
the lower ones (TUNING.release_fallbacks) only where IK finds nothing there.
Two of the layout's three 165 g cubes: four static throws, and the chosen bounds 1.5 s
sooner over the first three cycles (7.37 s against 8.87 s); the third cube added 5 CPU-s.

Independent checks: where the arm is when the latch opens, the scene's clock against the
time `_static_carry` gave the carry before it, and the same job run in the scene with the
release bounds chosen and with the cell's bounds only; the scene's physics says where
each item came to rest.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.arm.joints import joint_gap
from cell.arm.tuning import TUNING
from cell.decision import Decision
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_0, position_m: [-0.432, -1.044], size_m: [0.263, 0.392], rim_height_m: 0.05}
  - {id: bin_2, position_m: [1.706, 1.434], size_m: [0.314, 0.377], rim_height_m: 0.123}
  - {id: bin_3, position_m: [0.066, 2.162], size_m: [0.313, 0.305], rim_height_m: 0.11}
items:
  - {object: unseen_cube45, count: 1, bin: bin_2}
  - {shape: cube, mass_kg: 0.0519, size_m: [0.0668, 0.0668, 0.0668], count: 1, bin: bin_3}
  - {shape: cube, mass_kg: 0.1655, size_m: [0.0568, 0.0568, 0.0568], count: 2, bin: bin_0}
seed: 2
"""


def _orchestrator(tmp_path: Path, session: str) -> Orchestrator:
    # bin_0's rim (0.05 m) is low: by default its throws are planned in the steep bounds
    # first (`ArmTuning.steep_rim_m`), which leaves out the lower ones compared here;
    # with that rule on, one of the 165 g cubes thrown steeply lands on the first and
    # leaves the bin (tune layout 2, docs/HISTORY.md, branch grip8). Without the release
    # IK's warm start (`ArmTuning.ik_warm`), as measured: with it, each of these four
    # releases is the one IK finds again from the pick, and the carry to a release IK
    # lands apart from, which this file checks, does not happen on this job
    return Orchestrator(
        parse_job(JOB, str(tmp_path / f"{session}.yaml")),
        session=session,
        cycle_search=True,
        turn_release=False,
        tuning=replace(TUNING, steep_rim_m=0.0, ik_warm=None),
    )


def _watch_carries(o: Orchestrator) -> list[tuple[float, float, float, float]]:
    """Watch each static throw's carry: (how far the arm is from the release chosen when
    the carry ends [rad], how far IK from the pick lands from it [rad], how long the carry
    took in the scene [s], the time `_static_carry` gave it before [s]), one row a throw."""
    rows: list[tuple[float, float, float, float]] = []
    carry = o.carry

    def watched(d: Decision, obj: Any, item: Any) -> None:
        if d.action != "throw" or d.moving or o._grip_stroke != d.stroke_m:
            carry(d, obj, item)
            return
        plan, chosen = d.plan, d.state.q_release
        e, a = plan.elevation_rad, plan.azimuth_rad
        centre = np.array([plan.x_m, plan.y_m, plan.z_m])
        tcp = o._tcp_for_item_centre(centre, e, a, d.stroke_m, obj)
        resolved = o._ik_gripped(tcp, e, a)  # IK from the pick, where the arm is
        at = (o.q, o.scene.item_position(item), obj, d.stroke_m)
        _, timed = o._static_carry(at, d.state.q_lift, chosen, plan)
        t0 = o.scene.t
        carry(d, obj, item)
        rows.append((joint_gap(o.q, chosen), joint_gap(resolved, chosen), o.scene.t - t0, timed))

    o.carry = watched  # type: ignore[method-assign]
    return rows


Runs = tuple[Any, Any, list[float], list[tuple[float, float, float, float]]]


def _run(tmp_path: Path, session: str, first_only: bool) -> tuple[Any, list[float], list[Any]]:
    """The job run in the scene; the release heights [m] of the bounds each plan was
    kept in; and each static throw's carry (`_watch_carries`; not watched with
    `first_only`). `first_only`: the plan in
    the first release bounds reached is kept, as before the bounds competed."""
    o = _orchestrator(tmp_path, session)
    heights: list[float] = []
    soonest = o._soonest_release
    carries = [] if first_only else _watch_carries(o)

    def watched(obj: Any, found: list[Any]) -> Any:
        r = found[0] if first_only else soonest(obj, found)
        heights.append(float(r.bounds.release_height))
        return r

    o._soonest_release = watched  # type: ignore[method-assign]
    try:
        return o.run(), heights, carries
    finally:
        o.close()


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Runs:
    """The job run with the release bounds chosen (its carries watched) and with the
    first bounds reached: each run once for the file's tests."""
    tmp = tmp_path_factory.mktemp("release_choice")
    chosen, heights, carries = _run(tmp, "bounds", first_only=False)
    first, _, _ = _run(tmp, "first", first_only=True)
    return chosen, first, heights, carries


def test_each_carry_ends_at_the_release_chosen_in_the_time_timed(runs: Runs) -> None:
    summary, _, _, rows = runs
    assert len(rows) >= 4, rows  # the static throws
    for at_release, _, took, timed in rows:
        assert at_release < 1e-3, rows  # [rad]: the arm is at the release chosen
        assert abs(took - timed) < 0.02, rows  # [s]: and took the time it was chosen by
    # the chosen release is not the one IK finds from the pick on every item
    assert max(r[1] for r in rows) > 1.0, rows
    assert summary.in_bin == len(summary.results)


def test_the_release_bounds_chosen_are_sooner_in_the_scene(runs: Runs) -> None:
    chosen, first, heights, _ = runs
    # a lower release was taken for at least one item, over the cell's own bounds
    assert min(heights) < max(heights), heights
    # pick to pick: every cycle but the last (which waits for the throws to come to rest)
    took_chosen = sum(r.cycle_time_s for r in chosen.results[:-1])
    took_first = sum(r.cycle_time_s for r in first.results[:-1])
    assert took_chosen < took_first, (took_chosen, took_first)
    assert chosen.in_bin == len(chosen.results)  # and no item lost for it
