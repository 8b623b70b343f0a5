"""The arm: descriptions, kinematics, inverse kinematics and motion.

- `composite_urdf(robot)`: the arm + throwing end-effector URDF (for Pinocchio and PyBullet).
- `load_robot(robot)`: the Pinocchio model reduced to the arm joints, limits, home.
- `solve_ik(robot, ReleasePose(...), q_current)`: the release configuration (IKFailed if none).
- `plan_path`, `plan_move`, `plan_stop`, `release_joint_velocity`: trajectories.
"""

from cell.robot.composite import composite_urdf, end_effector_urdf
from cell.robot.ik import IKNoSolution, IKResult, ReleasePose, pose_error, solve_ik
from cell.robot.limits import JointLimits
from cell.robot.model import EE_JOINTS, TCP_FRAME, Robot, axis_frame, load_robot
from cell.robot.motion import (
    Trajectory,
    check_limits,
    move_time,
    plan_move,
    plan_path,
    plan_stop,
    release_joint_velocity,
)
from cell.robot.mount import MountSpec, load_mount, robot_names
from cell.robot.paths import example_robot_data_dir, robots_dir

__all__ = [
    "EE_JOINTS",
    "MountSpec",
    "TCP_FRAME",
    "IKNoSolution",
    "IKResult",
    "JointLimits",
    "ReleasePose",
    "Robot",
    "Trajectory",
    "axis_frame",
    "check_limits",
    "composite_urdf",
    "end_effector_urdf",
    "example_robot_data_dir",
    "load_mount",
    "load_robot",
    "move_time",
    "plan_move",
    "plan_path",
    "plan_stop",
    "pose_error",
    "release_joint_velocity",
    "robot_names",
    "robots_dir",
    "solve_ik",
]
