"""The release IK's damped-least-squares descent (`cell.robot.ik_descent._descend`), iterate
by iterate.

Independent checks: every configuration the descent visits (recorded as those it asks
Pinocchio's kinematics for) is the one the DLS rule gives from the one before, recomputed
here with Pinocchio's forward kinematics (`framesForwardKinematics`), its frame Jacobian by
another route than the descent's (`computeFrameJacobian`), its rotation log (`pin.log3`),
numpy's cross product and `linalg.solve` (to 1e-9 rad); the descent stops where the rule
says (the stop tolerances, the give-up half way, the budget); its best attempt is its
iterate of lowest score; a converged descent's last iterate is within the stop tolerances
by forward kinematics alone. Cases: the Panda and the UR5, the roll fixed (6-D) and free
(5-D), a pose in reach (converges from a nearby seed; again from a farther seed on a budget
of 6 iterations: steps past half of it, without the null-space pull) and one far out of
reach (gives up half way).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

from cell.robot.ik_descent import _descend, _Descent, _Search
from cell.robot.ik_pose import AXIS_TOL_RAD, POSITION_TOL_M, ReleasePose
from cell.robot.model import load_robot

DAMPING, NULL_GAIN = 3e-3, 0.05  # `solve_ik`'s defaults
ITERATIONS = {"reach": 80, "short": 6, "far": 80}  # the budget: `solve_ik`'s, or short


def _reference(robot: Any, d: _Descent, q: np.ndarray, k: int) -> tuple[float, float, np.ndarray]:
    """(position error [m], angle error [rad], the next iterate [rad]) of the DLS rule at
    iterate k, q, from Pinocchio's kinematics and numpy's solve."""
    model, fid = robot.model, robot.tcp_frame
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    p, r = data.oMf[fid].translation.copy(), data.oMf[fid].rotation.copy()
    jac = pin.computeFrameJacobian(model, data, q, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
    e_p = d.pose.position - p
    if d.six:  # the full rotation's error
        w = pin.log3(d.r_des @ r.T)
        ang = float(np.linalg.norm(w))
        jt, err = jac, np.concatenate([e_p, w])
    else:  # the throw axis's turn onto the target's, in the tool's x-y plane
        z, u = r[:, 2], d.pose.axis
        cr = np.cross(z, u)
        ang = math.atan2(float(np.linalg.norm(cr)), float(z @ u))
        w = ang * cr / np.linalg.norm(cr)
        jt = np.vstack([jac[:3], r[:, :2].T @ jac[3:]])
        err = np.concatenate([e_p, r[:, :2].T @ w])
    a = jt @ jt.T + (d.lam2 + 0.01 * float(err @ err)) * np.eye(len(err))
    if k < d.half:  # J⁺e + (I - J⁺J) z
        z0 = d.null_gain * (d.q_cur - q)
        dq = z0 + jt.T @ np.linalg.solve(a, err - jt @ z0)
    else:
        dq = jt.T @ np.linalg.solve(a, err)
    dq *= min(1.0, 0.5 / float(np.max(np.abs(dq))))
    q_next = np.clip(q + dq, robot.limits.lower, robot.limits.upper)
    return float(np.linalg.norm(e_p)), ang, q_next


def _case(name: str, six: bool, kind: str) -> tuple[Any, ReleasePose, np.ndarray, np.ndarray]:
    """(robot, pose, current configuration, seed) [rad]: a pose a random configuration
    reaches, or ("far") moved 1 m out of reach along the base's radius; the seed near that
    configuration (farther for "short")."""
    robot = load_robot(name)
    rng = np.random.default_rng({"panda": 5, "ur5": 6}[name])
    q_goal = robot.random_configuration(rng)[0]
    p, r = robot.tcp_pose(q_goal)
    if kind == "far":
        p = p + np.array([p[0], p[1], 0.0]) / math.hypot(p[0], p[1])
    pose = ReleasePose(p, r[:, 2])
    if six:  # the roll that reproduces r
        r0 = pose.rotation()
        pose = ReleasePose(
            p, r[:, 2], math.atan2(float(r[:, 0] @ r0[:, 1]), float(r[:, 0] @ r0[:, 0]))
        )
    lim = robot.limits
    spread = 0.4 if kind == "short" else 0.3  # [rad] the seed's distance from q_goal
    seed = np.clip(q_goal + rng.normal(0.0, spread, q_goal.shape), lim.lower, lim.upper)
    q_cur = np.clip(q_goal + rng.normal(0.0, 0.3, q_goal.shape), lim.lower, lim.upper)
    return robot, pose, q_cur, seed


@pytest.mark.parametrize("kind", ["reach", "short", "far"])
@pytest.mark.parametrize("six", [True, False], ids=["roll-fixed", "roll-free"])
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_each_iterate_is_the_dls_rule_s_from_the_one_before(
    name: str, six: bool, kind: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    robot, pose, q_cur, seed = _case(name, six, kind)
    budget = ITERATIONS[kind]
    d = _Descent.of(pose, q_cur, POSITION_TOL_M, AXIS_TOL_RAD, budget, DAMPING, NULL_GAIN)
    assert d.six == six
    visited: list[np.ndarray] = []
    kinematics = pin.computeJointJacobians

    def record(model: Any, data: Any, q: np.ndarray) -> Any:
        visited.append(np.array(q))
        return kinematics(model, data, q)

    monkeypatch.setattr(pin, "computeJointJacobians", record)
    s = _Search(best=(math.inf, math.inf, math.inf, q_cur))
    seed_best = _descend(robot, d, seed, s)
    monkeypatch.undo()

    np.testing.assert_array_equal(visited[0], seed)
    scores, stop = [], ""
    for k, q in enumerate(visited):
        ep, ang, q_next = _reference(robot, d, q, k)
        scores.append(ep / d.tol_position_m + ang / d.tol_axis_rad)
        if ep < d.stop_p and ang < d.stop_a:
            stop = "converged"
        elif k == d.half and scores[-1] > 100.0:
            stop = "gave up"
        elif k == budget - 1:
            stop = "budget"
        if stop:
            assert k == len(visited) - 1, (k, stop)  # the descent stopped there, not later
            break
        np.testing.assert_allclose(visited[k + 1], q_next, rtol=0.0, atol=1e-9)
    assert (
        stop in {"reach": ["converged"], "short": ["converged", "budget"], "far": ["gave up"]}[kind]
    )
    if kind == "short":
        assert s.iterations > d.half  # steps without the pull, checked
    assert s.iterations == len(visited) - (stop != "budget")
    # the best attempt: the iterate of lowest score (the search's too: it had none before)
    i = int(np.argmin(scores))
    assert seed_best[1] is visited[i] or np.array_equal(seed_best[1], visited[i])
    assert seed_best[0] == pytest.approx(scores[i], rel=1e-9)
    assert s.best[0] == seed_best[0] and np.array_equal(s.best[3], visited[i])
    ep_i, _, _ = _reference(robot, d, visited[i], i)
    z = robot.tcp_pose(visited[i])[1][:, 2]
    assert s.best[1] == pytest.approx(ep_i, rel=1e-9)
    assert s.best[2] == pytest.approx(math.acos(min(1.0, float(z @ pose.axis))), abs=1e-7)
    if stop == "converged":  # the pose reached, by forward kinematics alone
        p, r = robot.tcp_pose(visited[-1])
        assert np.linalg.norm(p - pose.position) < d.stop_p
        assert math.acos(min(1.0, float(r[:, 2] @ pose.axis))) < d.stop_a + 1e-7
