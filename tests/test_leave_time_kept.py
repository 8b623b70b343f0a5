"""`leave_time_s` remembered (`cell.robot.moving_landing._leave_time_s`): the same time as
the steps worked out afresh, for every item and launch asked again, and a physical check
of those steps: a heavier item leaves later, and a steeper throw (more of gravity against
the push) too."""

from __future__ import annotations

import dataclasses

import numpy as np

from cell.catalogue import get_object
from cell.model.params import DEFAULT_EE
from cell.robot import moving_landing as ml


def test_the_remembered_leave_time_is_the_one_stepped_afresh() -> None:
    rng = np.random.default_rng(5)
    ml._leave_time_s.cache_clear()
    for name in ("cube50", "cyl50", "sphere40", "cuboid_b", "duck"):
        obj = get_object(name)
        for stroke, elevation in zip(
            rng.uniform(0.04, 0.09, 4), rng.uniform(0.2, 1.2, 4), strict=True
        ):
            first = ml.leave_time_s(obj, np.float64(stroke), float(elevation), DEFAULT_EE)
            again = ml.leave_time_s(obj, float(stroke), np.float64(elevation), DEFAULT_EE)
            fresh = ml._leave_time_s.__wrapped__(
                obj.mass, obj.width, float(stroke), float(elevation), DEFAULT_EE
            )
            assert first == again == fresh
            assert 0.0 < first < 0.5
    info = ml._leave_time_s.cache_info()
    assert info.hits == 20 and info.misses == 20


def test_the_leave_time_follows_the_push() -> None:
    cube = get_object("cube50")
    t = ml.leave_time_s(cube, 0.07, 0.5, DEFAULT_EE)
    heavier = ml.leave_time_s(dataclasses.replace(cube, mass=4 * cube.mass), 0.07, 0.5, DEFAULT_EE)
    steeper = ml.leave_time_s(cube, 0.07, 1.2, DEFAULT_EE)
    assert heavier > t and steeper > t
