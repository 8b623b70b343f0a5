"""`cell reach` and the robot benchmark's figures."""

import json
import math

import numpy as np

from cell.cli import main
from cell.model import throw_axis
from cell.robot.model import load_robot
from cell.robot.motion import move_time


def test_reach_json_gives_a_solution_that_fk_confirms(capsys):
    at, e, a = (0.6, 0.05, 0.45), 0.4, 0.1
    assert (
        main(
            [
                "reach",
                "--robot",
                "panda",
                "--at",
                *map(str, at),
                "--elevation",
                str(e),
                "--azimuth",
                str(a),
                "--json",
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert {"q", "position_error_m", "axis_error_rad", "move_time_s"} <= set(out)
    robot = load_robot("panda")
    q = np.array(out["q"])
    p, r = robot.tcp_pose(q)
    assert np.linalg.norm(p - np.array(at)) <= 1e-3
    u = np.ravel(throw_axis(e, a))
    assert math.acos(min(1.0, float(r[:, 2] @ u))) <= math.radians(0.5)
    assert out["position_error_m"] <= 1e-3 and out["axis_error_rad"] <= math.radians(0.5)
    assert out["move_time_s"] == move_time(robot.home, q, robot)
    assert out["move_time_s"] > 0


def test_reach_text_output_for_the_ur5(capsys):
    assert main(["reach", "--robot", "ur5", "--at", "0.4", "0.2", "0.4"]) == 0
    text = capsys.readouterr().out
    assert "position error" in text and "move time" in text


def test_reach_out_of_range_is_a_clean_error(capsys):
    assert main(["reach", "--robot", "panda", "--at", "2", "0", "0.5"]) == 2
    err = capsys.readouterr().err
    assert "IK failed" in err and "best residual" in err
