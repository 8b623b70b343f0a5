"""`cell reach`: the joint solution for a release pose, and the time to get there."""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterator
from typing import Any

import numpy as np

from cell.cli.common import add_axis_args, add_json_arg, add_vector_arg, report


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "reach", help="inverse kinematics to a release pose, and the move time from home"
    )
    p.add_argument(
        "--robot",
        default="panda",
        help="arm: a name under robots/ (docs/arms.md) or a mount.yaml path (panda)",
    )
    add_vector_arg(p, "--at", "grip centre in the arm's base frame [m]", required=True)
    add_axis_args(p)
    p.add_argument(
        "--roll",
        type=float,
        default=None,
        metavar="RAD",
        help="fix the roll about the throw axis [rad] (default: free)",
    )
    p.add_argument(
        "--from",
        dest="q_from",
        type=float,
        nargs="+",
        metavar="Q",
        help="current configuration [rad] (default: home)",
    )
    add_json_arg(p, "the solution")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cell.robot.ik import ReleasePose, solve_ik
    from cell.robot.model import load_robot
    from cell.robot.motion import move_time

    robot = load_robot(args.robot)
    q0 = robot.home if args.q_from is None else np.asarray(args.q_from, dtype=float)
    if len(q0) != len(robot.home):
        from cell.errors import InvalidInput

        raise InvalidInput(
            f"--from: {len(q0)} joint values given; the {args.robot} has {len(robot.home)} "
            "joints: give one angle [rad] for each"
        )
    pose = ReleasePose.from_angles(tuple(args.at), args.elevation, args.azimuth, args.roll)
    res = solve_ik(robot, pose, q0)
    t_move = move_time(q0, res.q, robot)
    out = {
        "robot": args.robot,
        "q": res.q,
        "position_error_m": res.position_error_m,
        "axis_error_rad": res.axis_error_rad,
        "roll_error_rad": res.roll_error_rad if args.roll is not None else None,
        "move_time_s": t_move,
        "from_q": q0,
    }
    return report(args, out, _text(args, res, t_move))


def _text(args: argparse.Namespace, res: Any, t_move: float) -> Iterator[str]:
    """The solution as a person reads it, line by line."""
    yield f"robot           {args.robot}"
    yield "q [rad]         " + " ".join(f"{v:+.4f}" for v in res.q)
    yield f"position error  {res.position_error_m * 1e3:.3f} mm"
    yield f"axis error      {math.degrees(res.axis_error_rad):.3f}°"
    if args.roll is not None:
        yield f"roll error      {math.degrees(res.roll_error_rad):.3f}°"
    yield (
        f"move time       {t_move:.3f} s (jerk-limited, from {'home' if args.q_from is None else 'the given q'})"
    )
