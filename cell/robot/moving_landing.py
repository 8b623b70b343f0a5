"""Where an item thrown from a moving grip lands: its leave time and landing point."""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams


def leave_time_s(
    obj: ObjectParams, stroke_m: float, elevation_rad: float, ee: EndEffectorParams
) -> float:
    """The time [s] from the latch opening until the item leaves the carriage at L_e: the
    band's push (`push_force`, the grip's width) drives the carriage and the item
    (`moving_mass_kg` + the item's mass) from rest at L_s against gravity's component
    along the axis (semi-implicit Euler, 10 µs steps).

    The model's launch state is where and how the item leaves in the end-effector's
    frame; the model's push lasts ee.dt (a fitted constant, ~9 ms) and its ride to L_e
    takes no time, while the plant's item stays in the end-effector for this whole time
    (~35 ms: measured 37 ms in the scene for cube50 at L_s = 85 mm). Released on the
    move, the item is carried v_rel × this time before it flies.

    Remembered (`_leave_time_s`, the last LEAVE_TIMES_KEPT): the ~3,000 steps take ~8 ms,
    and a release on the move's polish asks again for the same stroke and elevation
    (its Jacobian's azimuth column; the same launch tried at other speeds): 112 calls,
    54 distinct, in the demo's first 10 items. The same arguments, the same steps.
    """
    return _leave_time_s(obj.mass, obj.width, float(stroke_m), elevation_rad, ee)


LEAVE_TIMES_KEPT = 4096


@functools.lru_cache(maxsize=LEAVE_TIMES_KEPT)
def _leave_time_s(
    obj_mass: float, obj_width: float, stroke_m: float, elevation_rad: float, ee: EndEffectorParams
) -> float:
    """`leave_time_s` of an item of mass [kg] and width [m] `obj_mass`, `obj_width`.

    The push at each step is `push_force(np.float64(stroke), width, ee)` [N] in Python
    floats: the same operations in the same order (the square by `pow`, as NumPy's scalar
    `**`; sqrt, cos and atan2 from libm, which this NumPy's float64 loops equal bit for
    bit), the terms that do not depend on the stroke computed once, gravity's component
    along the axis too (tests/test_leave_time_kept.py steps `push_force` itself and gets
    the same time)."""
    from cell.model.params import G
    from cell.sim.mechanism import DEFAULT_GEOMETRY

    end = ee.L_e if ee.L_e > 0 else DEFAULT_GEOMETRY.end_stop_m
    mass = obj_mass + DEFAULT_GEOMETRY.moving_mass_kg
    width = max(float(obj_width), ee.d)
    half_gap_sq = ((width - ee.d) / 2) ** 2
    base = ee.l1 + ee.r_r * ee.phi + ee.d / 2
    gap = width - ee.d
    k3, k2, k1, c = ee.Ke3, ee.Ke2, ee.Ke1, ee.C
    l_t, l_0 = ee.L_t, ee.L0
    along = G * math.sin(elevation_rad)
    sqrt, cos, atan2 = math.sqrt, math.cos, math.atan2
    s, v, t, h = float(stroke_m), 0.0, 0.0, 1e-5
    while s < end and t < 0.5:
        out = l_t - s
        stretch = base + sqrt(half_gap_sq + out**2) - l_0
        if stretch > 0:
            f_e = ((k3 * stretch + k2) * stretch + k1) * stretch + c
            if f_e < 0.0:  # np.fmax(f_e, 0.0): -0.0 kept as it is
                f_e = 0.0
        else:
            f_e = 0.0 * stretch
        v += (2 * f_e * cos(atan2(gap, 2 * out)) / mass - along) * h
        s += v * h
        t += h
    return t


def predict_moving_landing(obj: ObjectParams, plan: Any, ee: EndEffectorParams) -> np.ndarray:
    """The landing (x, y) [m, W] of a plan released with the grip moving at its base
    velocity v_b, the launch taken in the end-effector's frame (inertial, moving at v_b):
    the model's launch state for the plan made static (push and ride), plus v_b to the
    velocity and v_b × `leave_time_s` to the position; then the model's flight.

    `predict_landing` adds v_b before the push instead, so the item is carried only the
    push's fitted ee.dt along: for cube50 at 0.75 m/s that lands 18 mm short of where the
    scene's item lands (whose moving launch is the static one plus v_b within 1 %).
    With v_b = 0 this is `predict_landing`'s landing.
    """
    from cell.model.planar import flight_planar_one
    from cell.model.throw import _FLIGHT_STEP, drag_constant, launch_state
    from cell.optimize.verify import sigma_batch

    vb = np.array([plan.vx_mps, plan.vy_mps, plan.vz_mps])
    sig = plan.sigma.copy()
    sig[3:6] = 0.0
    batch = sigma_batch(obj, sig, plan.land_z_m)
    p1, v1 = (x[0] for x in launch_state(batch, ee))
    if vb.any():
        p1 = p1 + vb * leave_time_s(obj, plan.stroke_m, plan.elevation_rad, ee)
        v1 = v1 + vb
    k = float(drag_constant(batch.shape, batch.mass, batch.size)[0])
    vh = math.hypot(v1[0], v1[1])
    dist = flight_planar_one(float(p1[2]), vh, float(v1[2]), k, float(plan.land_z_m), _FLIGHT_STEP)[
        0
    ]
    return np.asarray(p1[:2] + dist * np.array([v1[0], v1[1]]) / vh, float)
