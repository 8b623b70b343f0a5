"""04 — the arm: IK to a release pose, then a time-optimal path and a jerk-limited move
that arrives moving (a release while moving adds the arm's velocity to the throw).

Run: .venv/bin/python examples/04_reach_and_move.py
"""

import numpy as np

from cell.robot.ik import ReleasePose, solve_ik
from cell.robot.model import load_robot
from cell.robot.motion import plan_move, plan_path

robot = load_robot("panda")
pose = ReleasePose.from_angles((0.5, 0.1, 0.7), elevation=0.5, azimuth=0.2)
sol = solve_ik(robot, pose)
print(f"IK: q = {np.round(sol.q, 3)}, position error {sol.position_error_m * 1000:.3f} mm")
home = robot.home
path = plan_path([np.asarray(home), sol.q], robot)
print(f"toppra path from home: {path.duration:.3f} s")
dq = np.zeros(robot.dof)
dq[0] = 0.5  # [rad/s] arrive with the base joint turning
move = plan_move(np.asarray(home), None, sol.q, dq, robot)
q_end, dq_end, _ = move.end_state()
print(
    f"ruckig move arriving with joint velocity {np.round(dq_end, 3)} rad/s in {move.duration:.3f} s"
)
