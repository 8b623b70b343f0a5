"""The effect augmentations: neutral = nominal, closed forms, physical directions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.errors import InvalidParameter
from cell.model import DEFAULT_EE, G, ThrowBatch, predict_landing, reference_landing
from cell.model.band import push_force
from cell.model.effects import (
    EFFECTS,
    BandDamping,
    BandMass,
    Bounce,
    Downwash,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    TrackingScale,
    Wind,
    effects_from_mapping,
    effects_to_mapping,
)
from cell.model.effects_apply import predict_with_effects
from cell.model.flight3d import fly
from cell.model.objects import ObjectParams
from cell.model.throw import drag_constant, launch_state

CUBE50 = ObjectParams("cube", 0.060, (0.05, 0.05, 0.05), "cube50")
SPHERE40 = ObjectParams("sphere", 0.030, (0.04, 0.04, 0.04), "sphere40")


def _batch(n: int = 200, seed: int = 3) -> ThrowBatch:
    rng = np.random.default_rng(seed)
    return ThrowBatch.build(
        stroke=rng.uniform(0.03, 0.11, n),
        position=np.c_[
            rng.uniform(-0.3, 0.3, n), rng.uniform(-0.3, 0.3, n), rng.uniform(0.5, 1.5, n)
        ],
        elevation=rng.uniform(0.0, 1.0, n),
        azimuth=rng.uniform(-np.pi, np.pi, n),
        shape=rng.integers(0, 5, n),
        mass=rng.uniform(0.02, 0.2, n),
        size=rng.uniform(0.03, 0.07, (n, 3)),
        base_velocity=rng.uniform(-0.3, 0.3, (n, 3)),
        land_z=rng.uniform(0.0, 0.3, n),
    )


def test_neutral_effects_are_the_nominal_model() -> None:
    b = _batch()
    nominal = predict_landing(b, DEFAULT_EE, strict=False)
    for cls in EFFECTS.values():
        got = predict_with_effects(b, DEFAULT_EE, [cls.neutral()])
        d = np.hypot(got.x - nominal.x, got.y - nominal.y)
        # launch/landing effects run the fast path itself; flight effects the 3-D integrator
        assert np.nanmax(d) < 1e-4, cls.name


def test_3d_integrator_matches_reference_and_golden_value() -> None:
    b = _batch(60)
    ref = reference_landing(b, DEFAULT_EE, step=2e-4)
    p1, v1 = launch_state(b, DEFAULT_EE)
    res = fly(p1, v1, drag_constant(b.shape, b.mass, b.size), b.land_z, step=0.01)
    assert np.nanmax(np.linalg.norm(res.position[:, :2] - ref.xy, axis=1)) < 1e-3
    # MODEL.md golden row: cube50, stroke 0.0625, (0, 0, 0.6), 30°, 0° -> (1.2902, 0), 0.5290 s
    g = ThrowBatch.single(CUBE50, stroke=0.0625, position=(0, 0, 0.6), elevation=math.radians(30),
                          azimuth=0.0)  # fmt: skip
    land = predict_with_effects(g, DEFAULT_EE, [Wind()])
    assert abs(land.x[0] - 1.2902) < 1e-3 and abs(land.y[0]) < 1e-6
    assert abs(land.t_flight[0] - 0.5290) < 1e-3


def test_stroke_offset_and_release_pitch_are_shifted_inputs() -> None:
    b = _batch()
    shifted = ThrowBatch(**{**b.__dict__, "stroke": b.stroke + 0.004})
    a = predict_with_effects(b, DEFAULT_EE, [StrokeOffset(0.004)])
    e = predict_landing(shifted, DEFAULT_EE, strict=False, check_stroke=False)
    assert np.allclose(a.xy, e.xy, equal_nan=True)
    pitched = ThrowBatch(**{**b.__dict__, "elevation": b.elevation - 0.05})
    a = predict_with_effects(b, DEFAULT_EE, [ReleasePitch(-0.05)])
    e = predict_landing(pitched, DEFAULT_EE, strict=False)
    assert np.allclose(a.xy, e.xy, equal_nan=True)


def test_band_mass_and_damping_scale_the_launch_impulse() -> None:
    b = ThrowBatch.single(SPHERE40, stroke=0.05, position=(0, 0, 1.0), elevation=0.0, azimuth=0.0)
    f = float(push_force(b.stroke, b.size[:, 0], DEFAULT_EE)[0])
    m = SPHERE40.mass
    for mb in (0.0, 0.01, 0.03):
        v = predict_with_effects(b, DEFAULT_EE, [BandMass(mb)]).launch_velocity[0]
        # impulse f Δt drives m + m_b (drag over 12 ms changes it by < 1 %)
        assert v[0] == pytest.approx(f * DEFAULT_EE.dt / (m + mb), rel=0.01)
        assert v[2] == pytest.approx(-G * DEFAULT_EE.dt, rel=0.02)
    from cell.model.band import band_stretch

    dl = float(band_stretch(b.stroke, b.size[:, 0], DEFAULT_EE)[0])
    v = predict_with_effects(b, DEFAULT_EE, [BandDamping(2.0)]).launch_velocity[0]
    assert v[0] == pytest.approx(f * (1 - 2.0 * dl) * DEFAULT_EE.dt / m, rel=0.01)


def test_shape_stretch_acts_on_curved_objects_only() -> None:
    cube = ThrowBatch.single(CUBE50, stroke=0.06, position=(0, 0, 1), elevation=0.3, azimuth=0)
    sph = ThrowBatch.single(SPHERE40, stroke=0.06, position=(0, 0, 1), elevation=0.3, azimuth=0)
    eff = [ShapeStretch(0.2)]
    assert predict_with_effects(cube, DEFAULT_EE, eff).x[0] == pytest.approx(
        predict_landing(cube, DEFAULT_EE).x[0], abs=1e-12
    )
    # more stretch, more push: the sphere flies farther
    assert predict_with_effects(sph, DEFAULT_EE, eff).x[0] > predict_landing(sph, DEFAULT_EE).x[0]


def test_tracking_scale_and_bounce_closed_forms() -> None:
    b = _batch()
    nominal = predict_landing(b, DEFAULT_EE, strict=False)
    a = predict_with_effects(b, DEFAULT_EE, [TrackingScale(1.05)])
    assert np.allclose(a.xy, 1.05 * nominal.xy, equal_nan=True)
    a = predict_with_effects(b, DEFAULT_EE, [Bounce(0.5)])  # μ = 2
    vh = nominal.impact_velocity[:, :2]
    slide = np.linalg.norm(a.xy - nominal.xy, axis=1)
    assert np.allclose(slide, np.sum(vh**2, axis=1) / (2 * 2.0 * G), equal_nan=True)
    # along the horizontal velocity
    cos = np.sum((a.xy - nominal.xy) * vh, axis=1) / (slide * np.linalg.norm(vh, axis=1))
    assert np.nanmin(cos) > 1 - 1e-9


def test_wind_directions() -> None:
    b = ThrowBatch.single(CUBE50, stroke=0.05, position=(0, 0, 1), elevation=0.5, azimuth=0.0)
    x0 = predict_landing(b, DEFAULT_EE).x[0]
    assert predict_with_effects(b, DEFAULT_EE, [Wind(5, 0, 0)]).x[0] > x0  # tailwind
    assert predict_with_effects(b, DEFAULT_EE, [Wind(-5, 0, 0)]).x[0] < x0  # headwind
    assert predict_with_effects(b, DEFAULT_EE, [Wind(0, 4, 0)]).y[0] > 0.01  # crosswind drift


def test_downwash_absent_at_zero_rpm_and_confined_below_rotors() -> None:
    b = ThrowBatch.build(
        stroke=[0.05, 0.05], position=[(0, 0, 2.0), (0, 0, 2.0)], elevation=[0.2, 0.2],
        azimuth=[0.0, 0.0], shape=[0, 0], mass=[0.06, 0.06], size=[(0.05,) * 3] * 2,
    )  # fmt: skip
    nominal = predict_landing(b, DEFAULT_EE)
    dw = [Downwash(8.0, 0.5, 1.0)]
    off = predict_with_effects(b, DEFAULT_EE, dw, rotor_rpm=np.array([0.0, 0.0]))
    assert np.allclose(off.xy, nominal.xy, atol=1e-6)
    on = predict_with_effects(b, DEFAULT_EE, dw, rotor_rpm=np.array([4000.0, 8000.0]))
    assert on.x[1] < on.x[0] < nominal.x[0]  # pushed down: shorter, more with more rpm
    # a column too narrow to hold the object for long does less
    thin = predict_with_effects(b, DEFAULT_EE, [Downwash(8.0, 0.05, 1.0)],
                                rotor_rpm=np.array([8000.0, 8000.0]))  # fmt: skip
    assert on.x[1] < thin.x[1] < nominal.x[1]


def test_spin_lift_sign_and_saturation() -> None:
    b = ThrowBatch.single(SPHERE40, stroke=0.05, position=(0, 0, 1), elevation=0.3, azimuth=0.0)
    x0 = predict_landing(b, DEFAULT_EE).x[0]
    back = predict_with_effects(b, DEFAULT_EE, [Spin(200.0, 0.3)]).x[0]
    top = predict_with_effects(b, DEFAULT_EE, [Spin(-200.0, 0.3)]).x[0]
    assert top < x0 < back
    # the lift saturates: a tenfold spin cannot give more than lift_max allows
    huge = predict_with_effects(b, DEFAULT_EE, [Spin(600.0, 0.3)]).x[0]
    sat = predict_with_effects(b, DEFAULT_EE, [Spin(600.0, 0.05)]).x[0]
    assert back < huge and sat < huge


def test_effects_mapping_round_trip_and_errors() -> None:
    effs = [BandMass(0.01), Wind(1.0, -2.0, 0.0)]
    again = effects_from_mapping(effects_to_mapping(effs))
    assert again == effs
    with pytest.raises(InvalidParameter, match="unknown effect"):
        effects_from_mapping({"gremlins": {}})
    with pytest.raises(InvalidParameter, match="unknown parameter"):
        effects_from_mapping({"band_mass": {"kg": 1.0}})
    with pytest.raises(InvalidParameter, match="outside its range"):
        effects_from_mapping({"band_mass": {"mass_kg": -1.0}})
    b = _batch(20)
    a = predict_with_effects(b, DEFAULT_EE, {"tracking_scale": {"scale_factor": 0.9}})
    assert np.allclose(a.xy, 0.9 * predict_landing(b, DEFAULT_EE, strict=False).xy, equal_nan=True)
