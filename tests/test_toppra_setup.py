"""`plan_path`'s toppra (`cell.robot.path_plan._toppra_class`) is toppra's own TOPPRA to the
last bit: the same controllable sets, velocities, times and states on random paths, with
the joint limits alone and with the grip as a constraint (feasible or not); and the spline
and gridpoints `plan_path` keeps by its waypoints' and limits' bytes are those it would
make afresh (a speed-up of the planner must not change a single plan)."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
import toppra.algorithm as algo
import toppra.constraint as constraint

from cell.errors import TrajectoryError
from cell.robot import path_plan
from cell.robot.carry_plan import _Dilated, _TimeScaled
from cell.robot.grip_constraint import grip_constraint
from cell.robot.grip_hold import GripHold, sampled_motion
from cell.robot.model import load_robot
from cell.robot.path_plan import _path_and_grid, _toppra_class, plan_path
from cell.robot.spline import spline_path
from cell.robot.toppra_bulk import propose_gridpoints

# a tall cylinder held by its faces (tests/test_carry.py's), and a grip too weak for it
HOLD = GripHold(
    force_n=0.9489852874519011,
    torque_nm=0.029163938102180383,
    mass_kg=0.06,
    inertia_xx=2.909375e-05,
    offset_tcp_m=(0.0, 0.0, -0.03),
    lever_m=0.02,
    base_half_m=0.0175,
)


def _limits(vmax: np.ndarray, amax: np.ndarray) -> list[object]:
    return [
        constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
        constraint.JointAccelerationConstraint(
            np.c_[-amax, amax], discretization_scheme=constraint.DiscretizationType.Interpolation
        ),
    ]


def _same(ours: object, theirs: object) -> None:
    """Both None, or the same parameterisation bit for bit."""
    assert (ours is None) == (theirs is None)
    if ours is None:
        return
    for name in ("_ss", "_velocities", "_xs", "_ts", "_us"):
        a, b = getattr(ours, name), getattr(theirs, name)
        assert a.shape == b.shape and a.tobytes() == b.tobytes(), name
    ts = np.linspace(0.0, theirs.duration, 97)  # type: ignore[attr-defined]
    for order in (0, 1, 2):
        assert ours(ts, order).tobytes() == theirs(ts, order).tobytes()  # type: ignore[operator]


def _cases(rb: object, n: int, seed: int) -> list[tuple[object, np.ndarray]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        k = int(rng.integers(2, 6))
        way = [rb.home + rng.uniform(-0.6, 0.6, rb.dof) for _ in range(k)]  # type: ignore[attr-defined]
        path = spline_path(way)
        if len(out) % 2:  # uneven steps: each grid point's own
            grid = np.r_[0.0, np.sort(rng.uniform(0.0, 1.0, 120)), 1.0]
        else:
            grid = propose_gridpoints(path, max_err_threshold=1e-3, min_nb_points=100)
        out.append((path, grid))
    return out


@pytest.mark.parametrize("robot", ["panda", "ur5"])
def test_toppra_at_the_joint_limits_is_toppras(robot: str) -> None:
    rb = load_robot(robot)
    for i, (path, grid) in enumerate(_cases(rb, 12, seed=len(robot))):
        scale = (1.0, 0.5, 0.05)[i % 3]
        cons = _limits(rb.limits.velocity * np.sqrt(scale), rb.limits.acceleration * scale)
        ours = _toppra_class()(cons, path, grid)
        theirs = algo.TOPPRA(
            cons,
            path,
            gridpoints=grid,
            solver_wrapper="seidel",
            parametrizer="ParametrizeConstAccel",
        )
        k_ours, k_theirs = (
            ours.compute_controllable_sets(0.0, 0.0),
            theirs.compute_controllable_sets(0.0, 0.0),
        )
        assert k_ours.tobytes() == k_theirs.tobytes()
        _same(ours.compute_trajectory(0.0, 0.0), theirs.compute_trajectory(0.0, 0.0))


def test_toppra_with_the_grip_is_toppras_held_or_not() -> None:
    """With the grip as a constraint: where toppra finds a parameterisation and where the
    bound is under what the weight alone asks (none: the controllable sets' NaN where
    toppra's stop)."""
    rb = load_robot("panda")
    weight = HOLD.mass_kg * 9.81 / HOLD.force_n
    found = {True: 0, False: 0}
    for i, (path, grid) in enumerate(_cases(rb, 8, seed=5)):
        for bound in (1.0, 0.8 * weight if i % 2 else 1.2 * weight):
            cons = [*_limits(rb.limits.velocity, rb.limits.acceleration)]
            cons.append(grip_constraint(rb, HOLD, bound))
            ours = _toppra_class()(cons, path, grid)
            theirs = algo.TOPPRA(
                cons,
                path,
                gridpoints=grid,
                solver_wrapper="seidel",
                parametrizer="ParametrizeConstAccel",
            )
            k_ours = ours.compute_controllable_sets(0.0, 0.0)
            k_theirs = theirs.compute_controllable_sets(0.0, 0.0)
            assert np.array_equal(k_ours, k_theirs, equal_nan=True)
            raw = theirs.compute_trajectory(0.0, 0.0)
            _same(ours.compute_trajectory(0.0, 0.0), raw)
            found[raw is not None] += 1
    assert found[True] > 0 and found[False] > 0  # both kinds were compared


def test_the_kept_spline_is_the_one_made_afresh_for_those_waypoints_and_limits() -> None:
    """`_path_and_grid` answers the same waypoints and limits with what it made for them,
    and anything else (a waypoint one ulp away, the same waypoints under other limits)
    with what `_spline_within` and the gridpoints give afresh."""
    rb = load_robot("panda")
    path_plan._PATHS.clear()
    rng = np.random.default_rng(2)
    a = [rb.home + rng.uniform(-0.5, 0.5, 7) for _ in range(3)]
    b = [w.copy() for w in a]
    b[1][3] = np.nextafter(b[1][3], np.inf)
    kept_a = _path_and_grid(rb, a)
    assert _path_and_grid(rb, [w.copy() for w in a]) is kept_a
    kept_b = _path_and_grid(rb, b)
    assert kept_b is not kept_a
    fresh_b = path_plan._spline_within(rb, b)
    assert kept_b[0](kept_b[1]).tobytes() == fresh_b(kept_b[1]).tobytes()
    assert kept_b[1].tobytes() == propose_gridpoints(fresh_b, 1e-3, min_nb_points=100).tobytes()
    assert not kept_b[1].flags.writeable  # shared: nothing may write into it

    # the same waypoints, joint 1's upper limit just over them: the cubic overshoots it
    # (to 0.38 rad) where the joint turns back, the shape-preserving one does not
    tight = copy.copy(rb)
    way = [rb.home, rb.home + np.r_[0.3, [0.1] * 6], rb.home + np.r_[0.05, [0.5] * 6]]
    upper = rb.limits.upper.copy()
    upper[0] = float(way[1][0]) + 1e-3
    tight.limits = dataclasses.replace(rb.limits, upper=upper)
    loose_path = _path_and_grid(rb, way)[0]
    tight_path = _path_and_grid(tight, way)[0]
    assert tight_path is not loose_path
    s = np.linspace(0.0, 1.0, 50)
    assert tight_path(s).tobytes() == path_plan._spline_within(tight, way)(s).tobytes()
    assert tight_path(s).tobytes() != loose_path(s).tobytes()


def test_a_spline_leaving_the_limits_is_refused_each_time_it_is_asked() -> None:
    rb = load_robot("panda")
    path_plan._PATHS.clear()
    # a carry of the demo's (item 17): joint 6 turns back near its limit, 3.158 rad
    way = [
        np.array([1.2137, -0.6078, -1.6454, -1.734, -0.6168, 1.7471, -2.6804]),
        np.array([1.0801, -1.4811, -0.9398, -1.8689, -0.8416, 1.6155, -2.8973]),
        np.array([1.0795, -1.7628, -0.7894, -2.1492, -0.705, 2.1794, -2.7591]),
        np.array([1.2212, -1.6589, -0.7695, -2.3701, -0.4671, 3.158, -2.8881]),
    ]
    with pytest.raises(TrajectoryError) as first:
        plan_path(way, rb)
    with pytest.raises(TrajectoryError) as again:
        plan_path(way, rb)
    assert str(again.value) == str(first.value)
    assert "leaves the joint limits" in str(first.value)


def test_each_scale_keeps_its_own_plans_motion_and_the_dilation_reads_full_speeds() -> None:
    """`_TimeScaled.motion(s)` is the samples of the path planned at s (not another
    scale's), and `_Dilated` from them is `_Dilated` from the path itself."""
    rb = load_robot("panda")
    way = [rb.home, rb.home + np.array([0.8, -0.4, 0.3, 0.5, -0.9, 0.4, 0.6])]
    for margin in (None, 1.5):
        scaled = _TimeScaled(way, rb, HOLD, 1.0, 1.0, 6, margin)
        for s in (0.3, 1.0):
            motion = scaled.motion(s)
            fresh = sampled_motion(scaled.attempt(s)[0], rb, HOLD)
            assert all(m.tobytes() == f.tobytes() for m, f in zip(motion, fresh, strict=True))
        shared = _Dilated(
            scaled.attempt(1.0)[0], rb, HOLD, margin=margin, motion=scaled.motion(1.0)
        )
        own = _Dilated(scaled.attempt(1.0)[0], rb, HOLD, margin=margin)
        for s in (0.02, 0.4, 1.0):
            assert shared.use(s) == own.use(s)
        assert shared.use(1.0) == scaled.attempt(1.0)[1]


def test_a_planned_path_pickles_to_the_same_trajectory() -> None:
    """A forked planning branch sends its planned carries back pickled (`cell.arm.fork`):
    `plan_path`'s trajectory, unpickled, has the same parameterisation and states bit for
    bit (its class is made in `_toppra_class`: it pickles by its state)."""
    import pickle

    rb = load_robot("panda")
    rng = np.random.default_rng(5)
    way = [rb.home + rng.uniform(-0.5, 0.5, 7) for _ in range(3)]
    traj = plan_path(way, rb)
    back = pickle.loads(pickle.dumps(traj, protocol=pickle.HIGHEST_PROTOCOL))
    assert type(back._traj) is type(traj._traj) and back.duration == traj.duration
    _same(back._traj, traj._traj)
    ts = np.linspace(0.0, traj.duration, 61)
    for a, b in zip(back.sample_many(ts), traj.sample_many(ts), strict=True):
        assert a.tobytes() == b.tobytes()
