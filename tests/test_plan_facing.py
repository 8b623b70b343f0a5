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
