"""The arm's home checked as a pose to start from: the grip's centre (the TCP) above the
floor. A mount file's `home` is checked against the URDF's position limits
(`cell.robot.mount`); a home within them may still hold the grip under the floor (z = 0 in
the world frame W, the URDF's root at the origin), where no arm can start a run."""

from __future__ import annotations

import numpy as np

__all__ = ["home_problem"]


def home_problem(ref: str) -> str:
    """Why the home of the arm `ref` (a name or a mount file's path) is no pose to start
    from, "" where it is one: its TCP under the floor."""
    from cell.robot.model import load_robot
    from cell.robot.mount import load_mount

    spec = load_mount(ref)
    tcp, _ = load_robot(ref).tcp_pose(np.asarray(spec.home, float))
    if tcp[2] >= 0.0:
        return ""
    x, y, z = (float(v) for v in tcp)
    return (
        f"{spec.path}: field 'home': it holds the grip's centre (TCP) at ({x:.3f}, {y:.3f}, "
        f"{z:.3f}) m, under the floor (z = 0 m in the world frame W); choose a home with the "
        "grip above the floor, pointing down in front of the base (docs/arms.md: "
        "`cell reach --at X Y Z --elevation -1.5707` solves one)"
    )
