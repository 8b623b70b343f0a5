"""One frame convention: the throw axis and its roll, for the arm, the scene and the model."""

import math

import numpy as np

from cell.catalogue import get_object
from cell.frames import axis_frame, matrix_from_quat_wxyz, quat_from_matrix, quat_wxyz_from_matrix
from cell.model import DEFAULT_EE, throw_axis
from cell.model.rigid import simulate_rigid
from cell.robot.model import axis_frame as robot_axis_frame
from cell.sim.frames import release_orientation as scene_orientation

RNG = np.random.default_rng(3)
ANGLES = [
    (RNG.uniform(-1.2, 1.4), RNG.uniform(-math.pi, math.pi), RNG.uniform(-math.pi, math.pi))
    for _ in range(50)
]


def test_the_frame_is_a_rotation_whose_z_is_the_models_throw_axis():
    for e, a, r in ANGLES:
        m = axis_frame(e, a, r)
        assert np.allclose(m.T @ m, np.eye(3), atol=1e-12) and np.linalg.det(m) > 0
        assert np.allclose(m[:, 2], throw_axis(np.array([e]), np.array([a]))[0], atol=1e-12)


def test_roll_zero_puts_x_in_the_vertical_plane_of_the_throw_pointing_down():
    for e, a, _ in ANGLES:
        x = axis_frame(e, a, 0.0)[:, 0]
        normal = np.array([-math.sin(a), math.cos(a), 0.0])  # of the throw's vertical plane
        assert abs(x @ normal) < 1e-12
        assert x[2] == np.float64(-math.cos(e)) or abs(x[2] + math.cos(e)) < 1e-12


def test_roll_turns_x_about_the_axis_by_the_angle():
    for e, a, r in ANGLES:
        x0, x = axis_frame(e, a, 0.0)[:, 0], axis_frame(e, a, r)[:, 0]
        u = axis_frame(e, a, 0.0)[:, 2]
        assert math.isclose(math.atan2(np.cross(x0, x) @ u, x0 @ x), r, abs_tol=1e-9)


def test_the_arm_the_scene_and_the_rigid_model_share_the_convention():
    obj = get_object("cube50")
    for e, a, r in ANGLES[:3]:
        m = axis_frame(e, a, r)
        assert np.array_equal(robot_axis_frame(e, a, r), m)
        assert np.array_equal(scene_orientation(e, a, r), m)
        tr = simulate_rigid(
            obj, DEFAULT_EE, stroke=0.05, position=(0, 0, 0.8), elevation=e, azimuth=a, roll=r,
        )  # fmt: skip
        assert np.allclose(matrix_from_quat_wxyz(tr.quaternion[0]), m, atol=1e-12)


def test_both_quaternion_orders_describe_the_same_rotation():
    from scipy.spatial.transform import Rotation

    for e, a, r in ANGLES:
        m = axis_frame(e, a, r)
        xyzw = np.array(quat_from_matrix(m))
        wxyz = quat_wxyz_from_matrix(m)
        assert np.allclose(Rotation.from_quat(xyzw).as_matrix(), m, atol=1e-12)
        assert np.allclose(matrix_from_quat_wxyz(wxyz), m, atol=1e-12)
        assert (
            min(np.abs(np.roll(wxyz, -1) - xyzw).max(), np.abs(np.roll(wxyz, -1) + xyzw).max())
            < 1e-12
        )
