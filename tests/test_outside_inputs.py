"""Inputs written by hand, as a new user writes them from the docs, that the generators
(`cell job random`, `cell synth`) never make: each was found to pass the parser and fail
later without naming its file and field, or to give silent nonsense. Each is now refused
up front, naming file, line or row, field and what would be valid."""

from __future__ import annotations

import pytest

from cell.errors import JobError
from cell.jobcell import BASE_SPEED_MAX_MPS
from cell.jobs import BIN_WALL_M, parse_job
from cell.platforms.mobile import BaseLimits
from cell.sim.bins import BinSpec

BINS = """\
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: flat, position_m: [1.50, -0.80], size_m: [0.40, 0.40], rim_height_m: RIM}
items:
  - {object: cube50, bin: flat}
"""


def test_the_parsers_bin_wall_is_the_scenes() -> None:
    """The bound the parser holds a rim to is the wall the scene builds (checked against
    the scene's own default, not a copy of the number)."""
    assert BinSpec("b", (1.0, 0.0), (0.3, 0.3), 0.2).wall == BIN_WALL_M


def test_a_rim_no_higher_than_the_bins_floor_plate_is_refused_with_its_line() -> None:
    """A 1 cm rim passed the parser and was refused by the scene, after the reach checks,
    as `bin flat: rim_height 0.01 m must exceed the wall thickness 0.01 m`: no file, no
    line, no field."""
    with pytest.raises(JobError) as e:
        parse_job(BINS.replace("RIM", "0.01"), "flat.yaml", check_reach=False)
    msg = str(e.value)
    assert "flat.yaml, line 3, bins[1].rim_height_m" in msg
    assert f"higher than {BIN_WALL_M} m" in msg
    job = parse_job(BINS.replace("RIM", "0.02"), "flat.yaml", check_reach=False)
    assert job.bins[1].rim_height == 0.02
    # the scene builds the bin the parser accepts
    BinSpec("flat", (1.5, -0.8), (0.4, 0.4), job.bins[1].rim_height)


MOBILE = """\
cell: {platform: mobile, mobile: {speed_mps: SPEED}}
bins:
  - {id: a, position_m: [-2.0, 0.0], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, bin: a}
"""


def test_the_parsers_base_speed_bound_is_the_bases_limit() -> None:
    assert BaseLimits().velocity_mps == BASE_SPEED_MAX_MPS


def test_a_base_speed_over_the_bases_limit_is_refused_with_its_line() -> None:
    """`speed_mps: 2.0` was documented valid (`[0, 2]`) and refused only when the base
    planned, as `speed_mps=2.0: must be in [0, 1.5] m/s`, naming no file or line."""
    with pytest.raises(JobError) as e:
        parse_job(MOBILE.replace("SPEED", "2.0"), "mobile.yaml", check_reach=False)
    msg = str(e.value)
    assert "mobile.yaml, line 1, cell.mobile.speed_mps" in msg
    assert str(BASE_SPEED_MAX_MPS) in msg
    job = parse_job(MOBILE.replace("SPEED", "1.5"), "mobile.yaml", check_reach=False)
    assert job.base_speed_mps == 1.5
