"""`cell.robot.toppra_bulk`: toppra's gridpoints and its constant-acceleration states,
computed over whole arrays, are toppra's own to the last bit (the planner's speed-up must
not change a single plan)."""

from __future__ import annotations

import numpy as np
import pytest
import toppra.algorithm as algo
import toppra.constraint as constraint
from toppra.interpolator import propose_gridpoints as toppra_gridpoints

from cell.robot.model import load_robot
from cell.robot.path_plan import plan_path
from cell.robot.spline import spline_path
from cell.robot.toppra_bulk import const_accel_states, propose_gridpoints


def _paths(n: int, seed: int = 0) -> list[object]:
    rng = np.random.default_rng(seed)
    return [
        spline_path(list(rng.uniform(-2.0, 2.0, (int(rng.integers(2, 6)), 7)))) for _ in range(n)
    ]


@pytest.mark.parametrize(("threshold", "least"), [(1e-3, 100), (1e-4, 100), (1e-3, 5)])
def test_gridpoints_are_toppras(threshold: float, least: int) -> None:
    for path in _paths(15):
        ours = propose_gridpoints(path, max_err_threshold=threshold, min_nb_points=least)
        theirs = np.array(toppra_gridpoints(path, max_err_threshold=threshold, min_nb_points=least))
        assert ours.shape == theirs.shape
        assert np.array_equal(ours, theirs)


def test_gridpoints_fail_as_toppras() -> None:
    path = _paths(1, seed=3)[0]
    with pytest.raises(ValueError):
        toppra_gridpoints(path, max_err_threshold=1e-12, max_iteration=3)
    with pytest.raises(ValueError):
        propose_gridpoints(path, max_err_threshold=1e-12, max_iteration=3)


def test_states_are_toppras() -> None:
    vmax, amax = np.full(7, 2.0), np.full(7, 5.0)
    rng = np.random.default_rng(1)
    for path in _paths(8, seed=1):
        raw = algo.TOPPRA(
            [
                constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
                constraint.JointAccelerationConstraint(
                    np.c_[-amax, amax],
                    discretization_scheme=constraint.DiscretizationType.Interpolation,
                ),
            ],
            path,
            parametrizer="ParametrizeConstAccel",
        ).compute_trajectory(0.0, 0.0)
        d = raw.duration
        ts = np.r_[np.linspace(0.0, d, 501), rng.uniform(0.0, d, 40), d, 0.0]
        for ours, order in zip(const_accel_states(raw, ts), (0, 1, 2), strict=True):
            assert np.array_equal(ours, raw(ts, order))


def test_plan_path_is_toppras_default() -> None:
    """`plan_path`, given the gridpoints and sampled in bulk, is the trajectory toppra plans
    with its own gridpoints, sampled point by point."""
    rb = load_robot("panda")
    rng = np.random.default_rng(2)
    lo, hi = rb.limits.lower, rb.limits.upper
    for _ in range(4):
        way = [lo + (hi - lo) * rng.uniform(0.2, 0.8, rb.dof) for _ in range(3)]
        ours = plan_path(way, rb, velocity_scale=0.9, acceleration_scale=0.7)
        path = spline_path(way, lo, hi)
        v, a = rb.limits.velocity * 0.9 * 0.98, rb.limits.acceleration * 0.7 * 0.98
        raw = algo.TOPPRA(
            [
                constraint.JointVelocityConstraint(np.c_[-v, v]),
                constraint.JointAccelerationConstraint(
                    np.c_[-a, a], discretization_scheme=constraint.DiscretizationType.Interpolation
                ),
            ],
            path,
            parametrizer="ParametrizeConstAccel",
            gridpt_min_nb_points=100,
        ).compute_trajectory(0.0, 0.0)
        assert ours.duration == float(raw.duration)
        ts = np.linspace(0.0, ours.duration, 301)
        for mine, order in zip(ours.sample_many(ts), (0, 1, 2), strict=True):
            assert np.array_equal(mine, raw(ts, order))
