"""A throw's carry turns the grip about one axis as far as it can (`Orchestrator._swing`).

The twist-free swing's waypoints are solved in the frame the release swings up from, but
the grip pointing down over the pick is solved at azimuth 0 (a vertical axis has none).
To a bin behind the arm the swing then turned the grip up to 80° off the one rotation
between its ends, and the wrist 3.4-3.9 rad; the spline between the ends alone turns it
less, and a sphere's carry takes that one where it is sooner (a sphere is the same
turned about the throw axis).

Independent checks: the twist of a joint path measured here with scipy's rotations from
the arm's forward kinematics (a move of the last joint alone is a rotation about one axis:
no twist), and the scene's physics (the spheres at rest in their bin)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from cell.arm.joints import twist
from cell.arm.tuning import TUNING
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from tests.job_rows import job_rows

# random layout 4 (Panda): a 35 g, 43 mm sphere into a bin behind the arm, 1.66 m out
JOB = """\
cell: {robot: panda, ee: pybullet}
bins:
  - {id: bin_0, position_m: [-1.263, -1.079], size_m: [0.317, 0.259], rim_height_m: 0.051}
  - {id: bin_4, position_m: [2.111, -0.101], size_m: [0.264, 0.255], rim_height_m: 0.053}
items:
  - {shape: sphere, mass_kg: 0.035, size_m: [0.0431, 0.0431, 0.0431], count: 2, bin: bin_0}
policy: auto
seed: 4
"""


def twist_deg(robot, qs: np.ndarray) -> float:
    """The most the grip turns [°] off the one rotation between the first and last
    configurations of `qs`."""
    rots = Rotation.from_matrix([robot.tcp_pose(q)[1] for q in qs])
    turn = rots[-1] * rots[0].inv()
    rv = turn.as_rotvec()
    k = rv / np.linalg.norm(rv) if np.linalg.norm(rv) > 1e-9 else rots[0].as_matrix()[:, 2]
    v = rots[0].inv().apply(k)
    return max(math.degrees(math.acos(np.clip(r.apply(v) @ k, -1, 1))) for r in rots)


def test_twist_is_zero_about_one_axis_and_found_off_it(tmp_path: Path) -> None:
    job = parse_job(JOB, str(tmp_path / "job.yaml"))
    o = Orchestrator(job, session="twist")
    try:
        rb = o.robot
        q0 = np.asarray(rb.home, float)
        q1 = q0.copy()
        q1[-1] += 1.2  # the flange about its own axis
        assert twist(o.robot, [q0, q1], TUNING.swing_check_samples) == pytest.approx(0.0, abs=1e-6)
        mid = (q0 + q1) / 2
        mid[-2] += 0.6  # out of that rotation and back
        line = [q0 + f * (q1 - q0) for f in np.linspace(0, 1, 5)]
        assert math.degrees(twist(o.robot, [q0, mid, q1], TUNING.swing_check_samples)) > 20.0
        assert twist_deg(rb, np.asarray(line)) == pytest.approx(0.0, abs=1e-4)
    finally:
        o.close()


def test_a_carry_behind_the_arm_turns_the_grip_about_one_axis(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    carries: list[float] = []

    class Watched(Orchestrator):
        def follow(self, traj, q_end, settle_s):  # type: ignore[no-untyped-def]
            if self.ee.item is not None:
                ts = np.linspace(0.0, traj.duration, 80)
                carries.append(twist_deg(self.robot, np.asarray(traj.sample_many(ts)[0])))
            return super().follow(traj, q_end, settle_s)

    # the bin's rim (0.051 m) is low: its throws are planned at steeply first
    # (`ArmTuning.steep_rim_m`, on as by default); the steep plan, whose carry turned the
    # grip 52° and 132°, falls through to the ordinary bounds (`cell.arm.steep`)
    rows = job_rows(JOB, tmp_path, "twist", Watched)
    assert rows == [("throw", "", True)] * 2, rows
    assert carries and max(carries) < 45.0, carries  # [°]; 74-80° along the swing
