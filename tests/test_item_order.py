"""The order a job's items are taken in (`cell run --order`): as the job lists them, or
each bin's items one after another (`Job.expanded_items`, `cell.jobs.ORDERS`).

Independent checks: the orders written out by hand for a small job; in the scene, the
items that land and how far the arm's configuration at one pick is from the last one's
(a pick's IK is solved from where the arm is, the last release)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.errors import InvalidInput
from cell.jobs import ORDERS, parse_job
from cell.orchestrator import Orchestrator
from tests.cli_exit import cell_exit

JOB = """\
cell: {robot: panda}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: left, position_m: [0.20, 1.40], size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: front, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, count: 1, bin: left}
  - {object: cube50, count: 1, bin: front}
  - {object: cube50, count: 1, bin: left}
seed: 0
"""

MIXED = """\
bins:
  - {id: a, position_m: [0.2, 1.4], size_m: [0.3, 0.3], rim_height_m: 0.15}
  - {id: b, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}
  - {id: c, position_m: [1.6, -1.0], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cube50, count: 2, bin: b}
  - {object: cyl50, count: 1, bin: c}
  - {object: sphere40, count: 2, bin: a}
  - {object: cube30, count: 1, bin: b}
  - {object: cyl70, count: 1, bin: c}
"""


def _taken(job, order):
    return [(it.obj.name, it.bin) for it in job.expanded_items(order)]


def test_the_orders_written_out():
    job = parse_job(MIXED, "mixed.yaml")
    listed = [
        ("cube50", "b"),
        ("cube50", "b"),
        ("cyl50", "c"),
        ("sphere40", "a"),
        ("sphere40", "a"),
        ("cube30", "b"),
        ("cyl70", "c"),
    ]
    assert _taken(job, "job") == listed
    # bins as the job first names them (b, c, a), each bin's items in job order
    assert _taken(job, "bins") == [
        ("cube50", "b"),
        ("cube50", "b"),
        ("cube30", "b"),
        ("cyl50", "c"),
        ("cyl70", "c"),
        ("sphere40", "a"),
        ("sphere40", "a"),
    ]
    assert sorted(_taken(job, "bins")) == sorted(listed)  # the same items, none lost


def test_the_cap_keeps_the_jobs_first_items():
    """With limits.max_items, the items run are the job's first ones, whatever the order."""
    job = parse_job(MIXED + "limits: {max_items: 4}\n", "mixed.yaml")
    assert _taken(job, "job") == [
        ("cube50", "b"),
        ("cube50", "b"),
        ("cyl50", "c"),
        ("sphere40", "a"),
    ]
    assert _taken(job, "bins") == [
        ("cube50", "b"),
        ("cube50", "b"),
        ("cyl50", "c"),
        ("sphere40", "a"),
    ]


def test_an_unknown_order_is_refused_with_the_valid_ones():
    job = parse_job(MIXED, "mixed.yaml")
    with pytest.raises(InvalidInput, match=r"item order 'nearest'.*\['job', 'bins'\]"):
        job.expanded_items("nearest")
    with pytest.raises(InvalidInput, match="item order"):
        Orchestrator(job, order="nearest")  # before any scene is built
    assert ORDERS == ("job", "bins")


def _cell(argv, capsys):
    """`cell argv` in this process (`tests.cli_exit`): (exit status, stderr)."""
    capsys.readouterr()
    code = cell_exit(argv)
    return code, capsys.readouterr().err


def test_the_cli_names_the_valid_orders(tmp_path, capsys):
    path = tmp_path / "job.yaml"
    path.write_text(MIXED)
    code, err = _cell(["run", str(path), "--order", "nearest"], capsys)
    assert code == 2
    assert "--order" in err and "'job', 'bins'" in err
    assert "Traceback" not in err


def test_picks_for_one_bin_are_alike_in_the_scene():
    """Three cubes, to two bins 82° apart round the base, in the scene: every one lands in
    its bin in either order. Taken alternately, the picks wander along the Panda's
    redundancy (each solved from the last release, at the other bin: joints 1 and 3 turn
    against each other: 0.75-3.3 rad from one pick to the next when measured); taken bin by
    bin, each pick is within 0.5 rad of the last in every joint. Without the release
    search and the turn (`--no-cycle-search --no-turn-release`): the search, timing each
    release with the approach from where the arm is, keeps even the alternate picks within
    0.3 rad here (measured)."""
    job = parse_job(JOB, "two_bins.yaml")
    gaps: dict[str, list[float]] = {}

    class Recorded(Orchestrator):
        picks: list[np.ndarray]

        def pick(self, d: Any, obj: Any, item: Any) -> None:
            super().pick(d, obj, item)
            self.picks.append(self.q.copy())  # the arm at the pick, the item in the grip

    for order in ORDERS:
        orch = Recorded(
            job, order=order, session=f"order-{order}", cycle_search=False, turn_release=False
        )
        picks: list[np.ndarray] = []
        orch.picks = picks
        try:
            res = orch.run().results
        finally:
            orch.close()
        bins = [r.target_bin for r in res]
        assert bins == (["left", "front", "left"] if order == "job" else ["left"] * 2 + ["front"])
        assert all(r.in_bin for r in res), [(r.target_bin, r.failure) for r in res]
        gaps[order] = [
            float(np.max(np.abs(b - a))) for a, b in zip(picks[:-1], picks[1:], strict=True)
        ]
    assert max(gaps["job"]) > 1.0, gaps
    assert max(gaps["bins"]) < 0.5, gaps


def test_another_platform_refuses_the_bin_order(capsys):
    """The drone's runner takes a job's items as listed: `--order bins` is refused, named."""
    tasks = Path(__file__).resolve().parents[1] / "tasks"
    code, err = _cell(["run", str(tasks / "drone.yaml"), "--order", "bins"], capsys)
    assert code != 0
    assert "--order bins" in err and "'drone'" in err, err
    assert "Traceback" not in err
