"""`leave_time_s` remembered (`cell.robot.moving_landing._leave_time_s`): the same time as
the steps worked out afresh, for every item and launch asked again, and a physical check
of those steps: a heavier item leaves later, and a steeper throw (more of gravity against
the push) too."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from cell.catalogue import get_object
from cell.model.params import DEFAULT_EE, EndEffectorParams
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


def test_the_leave_time_steps_the_models_push_bit_for_bit() -> None:
    """The same time, to the bit, as the steps worked out here with the model's own push
    (`cell.model.band.push_force` on NumPy scalars, as the loop asked it before it was
    written in Python floats), for items narrower and wider than the pads, rising and
    falling throws, and an end-effector whose item leaves at L_e."""
    from cell.model.band import push_force
    from cell.model.params import G
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    def stepped(
        mass: float, width: float, stroke: float, elevation: float, ee: EndEffectorParams
    ) -> float:
        end = ee.L_e if ee.L_e > 0 else DEFAULT_GEOMETRY.end_stop_m
        m = mass + DEFAULT_GEOMETRY.moving_mass_kg
        w = max(float(width), ee.d)
        s, v, t, h = stroke, 0.0, 0.0, 1e-5
        while s < end and t < 0.5:
            f = float(push_force(np.float64(s), w, ee))
            v += (f / m - G * math.sin(elevation)) * h
            s += v * h
            t += h
        return t

    rng = np.random.default_rng(11)
    left_at = dataclasses.replace(DEFAULT_EE, L_e=0.1)
    for name in ("cube30", "cube50", "sphere40", "duck"):
        obj = get_object(name)
        for stroke, elevation in zip(
            rng.uniform(0.04, 0.09, 2), rng.uniform(-0.3, 1.3, 2), strict=True
        ):
            for ee in (DEFAULT_EE, left_at):
                args = (obj.mass, obj.width, float(stroke), float(elevation), ee)
                assert ml._leave_time_s.__wrapped__(*args) == stepped(*args)
