"""Sort jobs on the drone and moving-base platforms, and the shipped task files."""

from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest

from cell.errors import InvalidInput
from cell.jobs import load_job, parse_job
from cell.log.store import ThrowStore
from cell.orchestrator import RunSummary
from cell.platforms.runner import PlatformRunner
from cell.sim.settle import crossing

TASKS = Path(__file__).resolve().parents[1] / "tasks"

JOB = """
cell: {{platform: {platform}, {extra}}}
pick_station: {{position_m: [-1.0, -1.0, 0.1]}}
bins:
  - {{id: a, position_m: [1.6, 0.5], size_m: [0.4, 0.4], rim_height_m: 0.15}}
  - {{id: b, position_m: [0.5, -1.9], size_m: [0.4, 0.4], rim_height_m: 0.15}}
items:
  - {{object: cube50, count: 1, bin: a}}
  - {{object: sphere40, count: 1, bin: b}}
policy: throw
"""


@pytest.mark.parametrize(
    "platform, extra",
    [
        ("drone", "drone: {hover_height_m: 2.2, rotor_rpm: 13900}"),
        ("mobile", "mobile: {speed_mps: 0.6}"),
    ],
)
def test_platform_job_runs_with_the_arm_summary_and_logs_its_platform(platform, extra, tmp_path):
    job = parse_job(JOB.format(platform=platform, extra=extra), str(tmp_path / "job.yaml"))
    store = ThrowStore(tmp_path / "log.sqlite")
    runner = PlatformRunner(job, store=store, session="t")
    try:
        summary = runner.run()
    finally:
        runner.close()
    assert isinstance(summary, RunSummary)
    d = summary.as_dict()
    assert set(d) == {f.name for f in fields(RunSummary)}
    assert summary.items == 2 and summary.thrown == 2 and summary.failed == 0
    assert summary.in_bin == 2, [r.reason or r.bin_id for r in summary.results]
    table = store.table(session="t")
    tracks = store.tracks()
    store.close()
    assert len(table.text("platform")) == 2
    # every throw carries its flight track, from the release to where it came to rest: it
    # starts at the logged release point and crosses the rim plane at the logged landing
    ids = table.text("throw_id")
    assert sorted(tracks) == sorted(ids)
    for i, tid in enumerate(ids):
        tr = tracks[tid]
        assert tr.shape[1] == 4 and len(tr) > 50 and np.all(np.diff(tr[:, 0]) > 0)
        release = [table.num(k)[i] for k in ("x_m", "y_m", "z_m")]
        assert np.linalg.norm(tr[0, 1:] - release) < 0.02  # one step of flight at most
        x, y, _ = crossing(tr, table.num("land_z_m")[i])
        assert (x, y) == pytest.approx(
            (table.num("landed_x_m")[i], table.num("landed_y_m")[i]), abs=1e-9
        )
    assert set(table.text("platform")) == {platform}
    rpm = table.num("rotor_rpm")
    speed = np.hypot(table.num("vx_mps"), table.num("vy_mps"))
    if platform == "drone":
        assert np.all(rpm == 13900.0) and np.all(speed == 0.0)
        # released under the drone: 0.25 m below its base frame
        assert table.num("z_m") == pytest.approx([2.2 - 0.25] * 2, abs=0.01)
    else:
        assert np.all(rpm == 0.0) and speed == pytest.approx([0.6, 0.6])


def test_shipped_task_files_validate_as_their_platforms():
    drone = load_job(TASKS / "drone.yaml")
    assert drone.platform == "drone" and drone.rotor_rpm > 0 and drone.hover_height_m > 1.0
    mobile = load_job(TASKS / "mobile.yaml")
    assert mobile.platform == "mobile" and mobile.base_speed_mps > 0
    assert drone.policy == mobile.policy == "throw"


def test_runner_refuses_the_arm_job():
    job = load_job(TASKS / "bins.yaml")
    with pytest.raises(InvalidInput, match="drone or mobile"):
        PlatformRunner(job)
