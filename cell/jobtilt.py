"""An arm that cannot turn its throw axis up to level, refused when its job throws.

A throw from the arm leaves with the throw axis (the grip's +z, `Robot.throw_axis`) level
or pointing up: the release search's elevations run from `ThrowBounds.elevation_min`, 0 rad,
and its flat fallback for a slow launch keeps that floor (`cell.arm.launch`). An arm whose
tool only ever points down (a SCARA: two joints turning about the vertical, a quill, a roll
about the quill) places, but every throw it is given fails `ik` one item after another,
after the job has loaded. So the job check (`cell.jobcheck.job_problems`) looks at the
highest elevation the axis takes over random configurations of the arm's joints, and where
it stays `TILT_MARGIN_RAD` under level, refuses a job that throws into any bin (those beyond
`limits.place_reach_m` under `auto`, those `auto` throws into as the arm cannot place into
them, every bin under `policy: throw`), naming the bins.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

__all__ = ["AXIS_SAMPLES", "TILT_MARGIN_RAD", "highest_axis_rad", "tilt_problems"]

AXIS_SAMPLES = 2000  # random configurations the axis' highest elevation is taken over
TILT_MARGIN_RAD = math.radians(45.0)  # refused only when the axis stays this far under level


@lru_cache(maxsize=16)
def highest_axis_rad(robot: Any) -> float:
    """The highest elevation [rad] of the arm's throw axis over `AXIS_SAMPLES` random
    configurations within its joints' limits (seeded): +π/2 pointing straight up, −π/2
    straight down."""
    qs = robot.random_configuration(np.random.default_rng(0), AXIS_SAMPLES)
    up = max(float(robot.throw_axis(q)[2]) for q in qs)
    return math.asin(min(max(up, -1.0), 1.0))


def tilt_problems(
    robot: Any, bins: Sequence[Any], thrown: Collection[int], where: dict[str, str]
) -> list[str]:
    """One error when the job throws into some bins (indices `thrown`) and the arm
    (`cell.robot.model.Robot`) cannot turn its throw axis up to level; none otherwise.

    Args:
        robot: the arm.
        bins: the job's BinSpecs.
        thrown: the indices of the bins the job throws into.
        where: "cell" / "bins[i]" -> "file, line N".
    """
    if not thrown:
        return []
    high = highest_axis_rad(robot)
    if high > -TILT_MARGIN_RAD:
        return []
    named = "; ".join(f"{bins[i].id!r} ({where.get(f'bins[{i}]', '?')})" for i in sorted(thrown))
    return [
        f"{where.get('cell', '?')}, cell: the {robot.name} arm cannot throw: its throw axis "
        f"(the grip's +z) points at most {math.degrees(high):.0f}° from level over "
        f"{AXIS_SAMPLES} random configurations of its joints, and a throw leaves with the "
        "axis level or pointing up; the job throws into "
        f"{len(thrown)} bin{'s' if len(thrown) > 1 else ''}: {named}. Have their items "
        "placed (bins within limits.place_reach_m the arm reaches, under policy auto or "
        "place), or choose an arm that tilts its tool"
    ]
