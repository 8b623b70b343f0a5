"""Planning for an arm that turns to face its bin: a plan turned about the vertical
axis still lands where the model says (the model is invariant under the turn)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.catalogue import get_object
from cell.model.params import DEFAULT_EE
from cell.model.throw import predict_landing
from cell.optimize.plan import MISS_TOL, plan_facing, plan_throw


@pytest.mark.parametrize("target", [(-1.5, 0.5, 0.1), (0.3, -2.0, 0.2), (-0.9, -1.2, 0.05)])
def test_a_target_beside_or_behind_is_thrown_from_its_side_and_lands(target):
    obj = get_object("cube40")
    plan = plan_facing(obj, target)
    # released on the target's side of the base, facing it
    assert np.dot([plan.x_m, plan.y_m], target[:2]) > 0
    land = predict_landing(plan.to_batch(obj), DEFAULT_EE)
    miss = math.hypot(land.x[0] - target[0], land.y[0] - target[1])
    assert miss <= MISS_TOL + 1e-6
    assert math.isclose(plan.target_x_m, target[0], abs_tol=1e-9)


def test_a_target_in_front_is_planned_as_before():
    obj = get_object("cube40")
    a, b = plan_facing(obj, (1.6, 0.3, 0.1)), plan_throw(obj, (1.6, 0.3, 0.1))
    assert a == b


@pytest.mark.parametrize(
    ("target", "facing_deg"),
    [((-1.5, 0.5, 0.1), -120.0), ((0.3, -2.0, 0.2), -41.6), ((2.2, 1.0, 0.05), -20.0)],
)
def test_an_arm_facing_a_given_azimuth_releases_along_it_and_lands(target, facing_deg):
    """The release point lies `release_radius` from the base along the azimuth the arm
    faces, at `release_height`; the throw axis turns from there to the target, and the
    model flies the plan onto it. Turning the whole problem about the vertical axis
    turns the plan with it (the model is invariant under the turn)."""
    from dataclasses import replace

    from cell.optimize.bounds import ThrowBounds
    from cell.optimize.plan import rotate_plan

    obj = get_object("cube40")
    f = math.radians(facing_deg)
    b = ThrowBounds(facing_rad=f)
    plan = plan_facing(obj, target, bounds=b)
    r = b.release_radius
    assert math.hypot(plan.x_m - r * math.cos(f), plan.y_m - r * math.sin(f)) < 1e-9
    assert math.isclose(plan.z_m, b.release_height, abs_tol=1e-9)
    toward = math.atan2(target[1] - plan.y_m, target[0] - plan.x_m)
    assert abs(math.remainder(plan.azimuth_rad - toward, 2 * math.pi)) < 0.01
    land = predict_landing(plan.to_batch(obj), DEFAULT_EE)
    assert math.hypot(land.x[0] - target[0], land.y[0] - target[1]) <= MISS_TOL + 1e-6
    # the same throw planned with the arm facing +x and turned back
    c, s = math.cos(-f), math.sin(-f)
    local = (c * target[0] - s * target[1], s * target[0] + c * target[1], target[2])
    turned = rotate_plan(plan_facing(obj, local, bounds=replace(b, facing_rad=0.0)), f)
    assert np.allclose(turned.sigma, plan.sigma, atol=1e-6)
