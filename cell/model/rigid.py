"""The full rigid-body state of a thrown object (eq. 3.10 with Euler's equations).

State: position p [m, W], unit quaternion q (w, x, y, z) rotating the object
frame O into W, linear velocity v [m/s, W], angular velocity ω [rad/s, O].
Translation: push f_o u for t < Δt, gravity, quadratic drag. Rotation:
torque-free Euler equations I ω̇ + ω × I ω = 0; the quaternion is advanced on
the rotation group (q ← q ⊗ exp(ω h / 2)), so its norm is kept by
construction rather than by renormalising.

This is the slow, complete path (time series of the whole state); landing
points in bulk come from `cell.model.throw.predict_landing`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import NoLanding
from cell.frames import (
    axis_frame,
    matrix_from_quat_wxyz,
    quat_exp_wxyz,
    quat_mul_wxyz,
    quat_wxyz_from_matrix,
)
from cell.model.band import push_force
from cell.model.integrate import plane_crossing, rk4_step
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams, G, aero_factor_kg_per_m
from cell.model.throw import ride, throw_axis

__all__ = ["RigidTrajectory", "release_orientation", "simulate_rigid", "quat_to_matrix"]


quat_to_matrix = matrix_from_quat_wxyz
"""Rotation matrix of a unit quaternion (w, x, y, z) (`cell.frames.matrix_from_quat_wxyz`)."""


def release_orientation(elevation: float, azimuth: float, roll: float) -> np.ndarray:
    """Quaternion (w, x, y, z) of the object frame O at release.

    O is the throw-axis frame of `cell.frames.axis_frame` (the cell's one roll
    convention): z along the throw axis u; with zero roll, x (across the band) in the
    vertical plane of the throw; roll turns x and y about u.
    """
    return quat_wxyz_from_matrix(axis_frame(elevation, azimuth, roll))


@dataclass(frozen=True)
class RigidTrajectory:
    """Sampled full state of one throw, from the start of the push to the landing.

    Attributes:
        t: times [s], shape (k,).
        position: centre of mass [m, W], shape (k, 3).
        quaternion: orientation O→W (w, x, y, z), shape (k, 4).
        velocity: [m/s, W], shape (k, 3).
        omega: angular velocity [rad/s, O], shape (k, 3).
        landing: landing point on the plane [m, W], shape (3,).
        t_flight: time of the plane crossing [s].
    """

    t: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    landing: np.ndarray
    t_flight: float


def _trajectory(hist: list[Any], landing: np.ndarray, t_flight: float) -> RigidTrajectory:
    """The trajectory of the steps `hist` ((t, position, quaternion, velocity, spin) each)
    that crossed the landing plane at `landing` [m, W], `t_flight` [s] after the release."""
    ts, ps, qs, vs, ws = zip(*hist, strict=True)
    return RigidTrajectory(
        t=np.array(ts),
        position=np.array(ps),
        quaternion=np.array(qs),
        velocity=np.array(vs),
        omega=np.array(ws),
        landing=landing,
        t_flight=t_flight,
    )


def simulate_rigid(
    obj: ObjectParams,
    ee: EndEffectorParams,
    *,
    stroke: float,
    position: tuple[float, float, float] | np.ndarray,
    elevation: float,
    azimuth: float,
    roll: float = 0.0,
    base_velocity: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
    omega0: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
    land_z: float = 0.0,
    step: float = 5e-4,
    t_max: float = 30.0,
) -> RigidTrajectory:
    """Integrate one throw's full rigid-body state until it lands.

    Args:
        obj: the object.
        ee: end-effector parameters.
        stroke: L_s [m].
        position: release grip centre [m, W].
        elevation, azimuth, roll: throw axis and roll about it [rad].
        base_velocity: end-effector velocity at release [m/s, W].
        omega0: initial angular velocity [rad/s, O] (the nominal model has none).
        land_z: landing plane height [m].
        step: integration step [s]; the push end falls on a step boundary.
        t_max: give up after this flight time [s].

    Raises:
        NoLanding: the object never crosses the landing plane while descending.
    """
    u = throw_axis(np.array(elevation), np.array(azimuth)).reshape(3)
    f_push = float(push_force(stroke, obj.width, ee)) * u
    k = aero_factor_kg_per_m(obj.cd, obj.area) / obj.mass
    inertia = obj.inertia
    n_push = max(1, math.ceil(ee.dt / step))
    h_push = ee.dt / n_push
    g = np.array([0.0, 0.0, -G])

    def acc(v: np.ndarray, pushing: bool) -> np.ndarray:
        a = g - k * np.linalg.norm(v) * v
        return a + f_push / obj.mass if pushing else a

    def alpha(w: np.ndarray) -> np.ndarray:
        return -np.cross(w, inertia * w) / inertia

    p = np.asarray(position, float).copy()
    v = np.asarray(base_velocity, float).copy()
    w = np.asarray(omega0, float).copy()
    q = release_orientation(elevation, azimuth, roll)
    hist = [(0.0, p, q, v, w)]  # (t, position, quaternion, velocity, spin) of each step
    t = 0.0
    i = 0
    while t < t_max:
        pushing = i < n_push
        h = h_push if pushing else step

        def rates(_p: object, vs: list[np.ndarray], push: bool = pushing) -> list[np.ndarray]:
            return [acc(vs[0], push), alpha(vs[1])]  # the spin: a state with no position

        (p_new,), (v_new, w_new) = rk4_step(rates, [p], [v, w], h)
        q_new = quat_mul_wxyz(q, quat_exp_wxyz(0.5 * (w + w_new), h))
        t_new = t + h
        if not pushing and p[2] > land_z >= p_new[2]:
            sa, pos, _ = plane_crossing(p[None], p_new[None], v[None], v_new[None], h, land_z)
            hist.append((t_new, p_new, q_new, v_new, w_new))
            return _trajectory(hist, pos[0], t + float(sa[0]) * h)
        if not pushing and p_new[2] <= land_z and v_new[2] < 0:
            break
        p, v, w, q, t = p_new, v_new, w_new, q_new, t_new
        i += 1
        if i == n_push and ee.L_e > 0:  # the ride on the carriage to L_e, as launch_state
            travel = float((p - np.asarray(position, float)) @ u)
            (p,), (v,) = ride(p[None], v[None], u[None], np.array([stroke + travel]), ee.L_e)
        hist.append((t, p, q, v, w))
    raise NoLanding(
        f"the throw never crosses its landing plane z = {land_z:.3f} m while descending "
        f"(released at z = {float(np.asarray(position)[2]):.3f} m)"
    )
