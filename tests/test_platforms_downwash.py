"""The downwash law and throws through it, against closed forms, invariants and a second solver."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cell.catalogue import get_object
from cell.errors import InvalidParameter, NoLanding
from cell.model import DEFAULT_EE, RHO_AIR, ThrowBatch, predict_landing
from cell.model.throw import drag_constant, launch_state
from cell.platforms import DownwashLaw, air_velocity, predict_drone_landing

CUBE = get_object("cube50")
LAW = DownwashLaw(induced_mps_per_krpm=0.7)
RPMS = np.array([0.0, 5000.0, 8900.0, 13900.0, 14860.0])
ROTOR = np.array([0.0, 0.0, 3.48])


def _batch(n, stroke=0.0436, z=3.207, elevation=0.0, land_z=0.0):
    return ThrowBatch.build(
        stroke=[stroke] * n,
        position=[(0.0, 0.0, z)] * n,
        elevation=elevation,
        azimuth=0.0,
        shape=CUBE.code,
        mass=CUBE.mass,
        size=CUBE.size,
        land_z=land_z,
    )


def _axis_speed(s, v_i, r0, decay):
    """Closed form on the axis: actuator disc (v_i → 2 v_i) times the jet decay."""
    return v_i * (1 + s / math.sqrt(s * s + r0 * r0)) / (1 + s / decay)


def test_air_velocity_on_the_axis_is_the_actuator_disc_law():
    rpm = 12000.0
    v_i = 0.7 * rpm / 1000
    for s in (1e-4, 0.1, 0.5, 2.0):
        w = air_velocity(np.array([[0.0, 0.0, 3.0 - s]]), [0, 0, 3.0], rpm, LAW)
        assert w[0, :2] == pytest.approx([0.0, 0.0])
        assert -w[0, 2] == pytest.approx(_axis_speed(s, v_i, LAW.wake_radius_m, LAW.decay_m), 1e-6)
    # at the disc v_i, far below (without decay) twice v_i: momentum theory
    ideal = LAW.with_params(decay_m=100.0)
    far = air_velocity(np.array([[0.0, 0.0, -27.0]]), [0, 0, 3.0], rpm, ideal)
    assert -far[0, 2] / (1 / (1 + 30 / 100.0)) == pytest.approx(2 * v_i, rel=1e-3)


def test_no_downwash_above_the_rotors_outside_the_column_or_at_zero_rpm():
    pts = np.array([[0.0, 0.0, 3.2], [0.0, 0.0, 3.5], [1.0, 0.0, 3.0], [0.0, 0.0, 0.5]])
    w = air_velocity(pts, ROTOR, 14000.0, LAW)
    assert np.all(w[1] == 0.0)  # above the disc
    assert abs(w[2, 2]) < 1e-6  # 1 m off the axis, well outside the ~0.2 m column
    assert w[0, 2] < -5.0 and w[3, 2] < 0.0  # inside, down
    assert not air_velocity(pts, ROTOR, 0.0, LAW).any()
    assert not air_velocity(pts, ROTOR, 14000.0, DownwashLaw()).any()  # c = 0
    thr = LAW.with_params(threshold_rpm=9000.0)
    assert not air_velocity(pts, ROTOR, 8900.0, thr).any()


def _flux(law, depth, power):
    """∫ w^power dA over a horizontal cross-section at a depth below the disc."""
    r = np.linspace(0.0, 1.0, 20001)
    pts = np.c_[r, np.zeros_like(r), np.full_like(r, 3.0 - depth)]
    w = -air_velocity(pts, [0, 0, 3.0], 10000.0, law)[:, 2]
    return np.trapezoid(w**power * 2 * np.pi * r, r)


def test_slipstream_conserves_mass_then_momentum():
    # ideal slipstream (no mixing, sharp edge): mass flux v_i·A at every depth
    ideal = DownwashLaw(induced_mps_per_krpm=0.7, edge_m=1e-3, decay_m=100.0)
    v_i = 7.0
    q0 = v_i * math.pi * ideal.wake_radius_m**2
    for depth in (0.05, 0.3, 1.0):
        f = 1 / (1 + depth / 100.0)  # the tiny decay left
        assert _flux(ideal, depth, 1) / f**-1 == pytest.approx(q0, rel=0.02)
    # mixing slows and widens the jet but keeps its momentum flux ∫w² dA (a turbulent
    # round jet): the same as the unmixed slipstream's at every depth
    mixing = ideal.with_params(decay_m=0.5)
    for depth in (0.5, 2.0):
        assert _flux(mixing, depth, 2) == pytest.approx(_flux(ideal, depth, 2), rel=0.02)
    assert _flux(mixing, 2.0, 1) > 2 * _flux(ideal, 2.0, 1)  # it entrains still air


def test_zero_rpm_is_the_nominal_model():
    b = _batch(3)
    nominal = predict_landing(b, DEFAULT_EE)
    for rpm, law in ((0.0, LAW), (14000.0, DownwashLaw())):
        land = predict_drone_landing(b, DEFAULT_EE, rpm, ROTOR, law)
        assert np.max(np.abs(land.xy - nominal.xy)) < 1e-3
        assert np.max(np.abs(land.t_flight - nominal.t_flight)) < 1e-3


def test_downwash_shortens_the_reach_more_with_rpm():
    land = predict_drone_landing(_batch(len(RPMS)), DEFAULT_EE, RPMS, ROTOR, LAW)
    reach = land.x
    assert np.all(np.diff(reach) < 0)
    assert reach[0] - reach[-1] > 0.1  # a clear effect at full speed
    assert np.all(np.abs(land.y) < 1e-9)  # the column is axisymmetric: no side push
    # the item leaves the column sinking faster than without the downwash
    assert land.impact_velocity[-1, 2] < land.impact_velocity[0, 2]


def test_drone_elsewhere_changes_nothing():
    b = _batch(1)
    far = predict_drone_landing(b, DEFAULT_EE, 14860.0, [10.0, -10.0, 3.48], LAW)
    assert far.x[0] == pytest.approx(float(predict_landing(b, DEFAULT_EE).x[0]), abs=1e-3)


def test_a_throw_straight_down_the_axis_against_a_second_solver():
    # elevation -90°: the cube falls down the column's axis, where the air
    # speed has the closed form; integrate the 1-D equation with scipy
    b = _batch(1, z=2.0, elevation=-math.pi / 2)
    rpm = 12000.0
    rotor_z = 2.3
    land = predict_drone_landing(b, DEFAULT_EE, rpm, [0, 0, rotor_z], LAW, step=0.001)
    p1, v1 = launch_state(b, DEFAULT_EE)
    k = float(drag_constant(b.shape, b.mass, b.size)[0])
    v_i = 0.7 * rpm / 1000

    def rhs(t, y):
        z, vz = y
        w = -_axis_speed(rotor_z - z, v_i, LAW.wake_radius_m, LAW.decay_m)
        rel = vz - w
        return [vz, -9.81 - k * abs(rel) * rel]

    def ground(t, y):
        return y[0]

    ground.terminal = True
    sol = solve_ivp(rhs, (0, 5), [p1[0, 2], v1[0, 2]], events=ground, rtol=1e-10, atol=1e-12)
    t_ground = float(sol.t_events[0][0]) + DEFAULT_EE.dt
    assert land.t_flight[0] == pytest.approx(t_ground, abs=1e-4)
    assert land.impact_velocity[0, 2] == pytest.approx(float(sol.y_events[0][0][1]), abs=1e-3)
    still = predict_drone_landing(b, DEFAULT_EE, 0.0, [0, 0, rotor_z], LAW, step=0.001)
    assert land.t_flight[0] < still.t_flight[0]  # the downwash pushes it down faster


def test_exit_distance_delays_the_downwash():
    b = _batch(2)
    early, late = (
        predict_drone_landing(
            b.take(np.array([0])), DEFAULT_EE, 14860.0, ROTOR, LAW, exit_distance_m=e
        )
        for e in (0.0, 0.13)
    )
    still = predict_drone_landing(b.take(np.array([0])), DEFAULT_EE, 0.0, ROTOR, LAW)
    assert early.x[0] < late.x[0] < still.x[0]


def test_law_physics_helpers():
    # momentum theory: T = 2 ρ A v_i², and C_T = (π/2)(v_i/(nD))²
    law = DownwashLaw(induced_mps_per_krpm=0.7)
    v_i = 0.7 * 12.0
    area = math.pi * law.wake_radius_m**2
    assert law.thrust_n(12000.0) == pytest.approx(2 * RHO_AIR * area * v_i**2)
    n = 12000.0 / 60
    assert law.thrust_coefficient() == pytest.approx(math.pi / 2 * (v_i / (n * 0.256)) ** 2)


def test_bad_inputs_raise():
    with pytest.raises(InvalidParameter, match="induced_mps_per_krpm"):
        DownwashLaw(induced_mps_per_krpm=-1.0)
    with pytest.raises(InvalidParameter, match="rotor_rpm"):
        predict_drone_landing(_batch(1), DEFAULT_EE, -5.0, ROTOR, LAW)
    with pytest.raises(InvalidParameter, match="drone_pose"):
        predict_drone_landing(_batch(2), DEFAULT_EE, 0.0, [[0, 0, 1]] * 3, LAW)
    with pytest.raises(NoLanding):
        predict_drone_landing(_batch(1, land_z=5.0), DEFAULT_EE, 0.0, ROTOR, LAW)


def test_a_batch_lands_each_throw_where_it_lands_alone():
    # throws of one batch under drones of their own: spun and not, gated and not, the
    # third thrown up through its drone's rotor plane (air only below it) while the
    # others fly below theirs, the last dropped down its drone's column from 8 m, the
    # longest flight. They land one by one, so the rows integrated shrink, at the end to
    # the last one alone, still in its column. Each lands where it lands flown alone: a
    # row's air is its own drone's, at its own place, whatever else the batch holds
    b = ThrowBatch.build(
        stroke=[0.08, 0.06, 0.05, 0.09],
        position=[(0.1, 0.0, 2.0), (0.0, 0.1, 1.2), (0.0, 0.0, 1.0), (0.0, 0.0, 8.0)],
        elevation=np.array([0.2, -0.3, 0.9, -1.5]),
        azimuth=np.array([0.5, -0.4, 0.0, 1.0]),
        shape=CUBE.code,
        mass=CUBE.mass,
        size=CUBE.size,
    )
    rpm = np.array([0.0, 12000.0, 14860.0, 8900.0])
    pose = np.array([[0.1, 0.0, 2.3], [0.05, 0.1, 1.5], [0.0, 0.0, 1.1], [0.0, 0.0, 8.3]])
    exit_m = np.array([0.0, 0.05, 0.0, 0.0])
    law = LAW.with_params(threshold_rpm=1000.0)
    both = predict_drone_landing(b, DEFAULT_EE, rpm, pose, law, exit_distance_m=exit_m)
    assert np.all(np.diff(both.t_flight[[1, 0, 2, 3]]) > 0.05)  # the rows leave one by one
    for i in range(4):
        one = predict_drone_landing(
            b.take(np.array([i])), DEFAULT_EE, rpm[i], pose[i], law, exit_distance_m=exit_m[i]
        )
        got = (both.x[i], both.y[i], both.t_flight[i])
        assert got == pytest.approx((one.x[0], one.y[0], one.t_flight[0]), abs=1e-12), i
    # the third leaves below its rotor plane rising fast enough to pass it (its apex
    # without drag 0.1 m or more above it; a cube's drag takes a few mm off it)
    p1, v1 = launch_state(b.take(np.array([2])), DEFAULT_EE)
    assert p1[0, 2] < 1.1 < p1[0, 2] + v1[0, 2] ** 2 / (2 * 9.81) - 0.1
    # the last one's downwash pushes it down sooner than still air would
    still = predict_drone_landing(b.take(np.array([3])), DEFAULT_EE, 0.0, pose[3], law)
    assert both.t_flight[3] < still.t_flight[0] - 0.05
