"""Physical checks of the nominal model against independent truths."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from cell.catalogue import catalogue, get_object
from cell.errors import InvalidParameter, NoLanding
from cell.model import (
    DEFAULT_EE,
    EndEffectorParams,
    G,
    ObjectParams,
    ThrowBatch,
    band_force,
    band_state,
    launch_state,
    predict_landing,
    push_force,
    reference_landing,
    stored_energy,
)
from cell.model.rigid import quat_to_matrix, simulate_rigid
from tests import mdl_reference as ref

NO_DRAG_EE = DEFAULT_EE


def _batch(obj: ObjectParams, n: int, **kw) -> ThrowBatch:
    args = dict(stroke=0.06, position=(0.0, 0.0, 0.6), elevation=0.5, azimuth=0.0)
    args.update(kw)
    return ThrowBatch.build(shape=obj.code, mass=obj.mass, size=obj.size, **args)


def test_drag_free_landing_matches_closed_form():
    # A dense tiny object has negligible drag: the landing is the ballistic closed form
    # from the launch state after the push, which is itself closed form (constant force).
    obj = ObjectParams("sphere", mass=50.0, size=(0.001, 0.001, 0.001))
    ee = EndEffectorParams(Ke1=114.6 * 500, Ke2=150 * 500, Ke3=400 * 500)
    e, a, z0, stroke = 0.6, 0.3, 0.7, 0.05
    land = predict_landing(
        _batch(obj, 1, stroke=stroke, elevation=e, azimuth=a, position=(0.1, -0.2, z0)), ee
    )
    f_o = float(push_force(stroke, obj.width, ee))
    u = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    acc = f_o / obj.mass * u + np.array([0, 0, -G])
    v1 = acc * ee.dt
    p1 = np.array([0.1, -0.2, z0]) + 0.5 * acc * ee.dt**2
    t = (v1[2] + math.sqrt(v1[2] ** 2 + 2 * G * p1[2])) / G
    expected = p1[:2] + v1[:2] * t
    assert np.linalg.norm(land.xy[0] - expected) < 2e-5
    assert land.t_flight[0] == pytest.approx(ee.dt + t, abs=1e-6)


def test_reach_falls_monotonically_with_stroke():
    strokes = np.linspace(DEFAULT_EE.stroke_min, DEFAULT_EE.stroke_max, 60)
    for name in ("cube30", "cube50", "cuboid_c", "cyl70", "sphere40"):
        obj = get_object(name)
        land = predict_landing(_batch(obj, 60, stroke=strokes), DEFAULT_EE)
        assert np.all(np.diff(land.x) < 0), name


def test_push_impulse_equals_force_times_duration():
    # With gravity and drag in the push, the momentum change is f_o Δt + m g Δt + drag
    # impulse; remove the two known terms, the drag term is tiny: the remainder is f_o Δt u.
    obj = get_object("cube50")
    b = _batch(obj, 1, stroke=0.05, elevation=0.4, azimuth=0.2)
    p1, v1 = launch_state(b, DEFAULT_EE, steps=400)
    f_o = float(push_force(0.05, obj.width, DEFAULT_EE))
    impulse = obj.mass * v1[0] - obj.mass * np.array([0, 0, -G]) * DEFAULT_EE.dt
    u = np.array([math.cos(0.4) * math.cos(0.2), math.cos(0.4) * math.sin(0.2), math.sin(0.4)])
    assert np.linalg.norm(impulse - f_o * DEFAULT_EE.dt * u) < 1e-3 * f_o * DEFAULT_EE.dt


def test_batched_equals_one_at_a_time():
    rng = np.random.default_rng(3)
    objs = [e.params for e in catalogue().values()]
    n = 40
    picks = [objs[i] for i in rng.integers(0, len(objs), n)]
    kw = dict(
        stroke=rng.uniform(0.03, 0.11, n),
        position=np.c_[rng.uniform(-0.2, 0.2, (n, 2)), rng.uniform(0.4, 1.2, n)],
        elevation=rng.uniform(-0.1, 1.1, n),
        azimuth=rng.uniform(-3, 3, n),
        base_velocity=rng.uniform(-0.4, 0.4, (n, 3)),
    )
    batch = ThrowBatch.build(
        shape=[o.code for o in picks],
        mass=[o.mass for o in picks],
        size=[o.size for o in picks],
        **kw,
    )
    all_at_once = predict_landing(batch, DEFAULT_EE)
    for i in range(n):
        one = predict_landing(batch.take(np.array([i])), DEFAULT_EE)
        assert one.x[0] == pytest.approx(all_at_once.x[i], abs=1e-9)
        assert one.y[0] == pytest.approx(all_at_once.y[i], abs=1e-9)


def test_fast_path_agrees_with_scipy_reference():
    rng = np.random.default_rng(7)
    objs = [e.params for e in catalogue().values()]
    for _ in range(25):
        o = objs[rng.integers(len(objs))]
        s, e, a = rng.uniform(0.03, 0.11), rng.uniform(-0.1, 1.1), rng.uniform(-3, 3)
        p0 = (rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(0.4, 1.4))
        vb = tuple(rng.uniform(-0.4, 0.4, 3))
        lz = rng.uniform(0, 0.3)
        fast = predict_landing(
            ThrowBatch.single(
                o, stroke=s, position=p0, elevation=e, azimuth=a, base_velocity=vb, land_z=lz
            ),
            DEFAULT_EE,
        )
        x, y, t = ref.land(o.shape, o.mass, o.size, s, p0, e, a, vb, lz)
        assert math.hypot(fast.x[0] - x, fast.y[0] - y) < 1e-3
        assert fast.t_flight[0] == pytest.approx(t, abs=1e-3)


def test_reference_integration_agrees_with_fast_path_on_varied_batch():
    from cell.bench.bench_predict import varied_batch

    b = varied_batch(400, seed=11)
    fast = predict_landing(b, DEFAULT_EE, strict=False)
    slow = reference_landing(b, DEFAULT_EE)
    assert np.array_equal(fast.landed, slow.landed)
    ok = fast.landed
    assert np.max(np.linalg.norm(fast.xy[ok] - slow.xy[ok], axis=1)) < 1e-3


def test_rigid_body_keeps_quaternion_norm_and_angular_momentum():
    obj = get_object("cuboid_c")
    tr = simulate_rigid(
        obj,
        DEFAULT_EE,
        stroke=0.05,
        position=(0, 0, 0.8),
        elevation=0.6,
        azimuth=0.3,
        roll=0.4,
        omega0=(6.0, 0.3, 2.0),
    )
    assert np.max(np.abs(np.linalg.norm(tr.quaternion, axis=1) - 1)) < 1e-10
    inertia = obj.inertia
    l_world = np.array(
        [quat_to_matrix(q) @ (inertia * w) for q, w in zip(tr.quaternion, tr.omega, strict=True)]
    )
    assert np.max(np.ptp(l_world, axis=0)) < 1e-6 * np.linalg.norm(l_world[0])
    energy = 0.5 * np.sum(inertia * tr.omega**2, axis=1)
    assert np.ptp(energy) < 1e-6 * energy[0]


def test_rigid_body_without_spin_lands_where_the_fast_path_says():
    obj = get_object("cyl50")
    tr = simulate_rigid(
        obj,
        DEFAULT_EE,
        stroke=0.06,
        position=(0, 0, 0.6),
        elevation=0.35,
        azimuth=0.1,
        base_velocity=(0.5, 0, 0),
    )
    fast = predict_landing(
        ThrowBatch.single(
            obj,
            stroke=0.06,
            position=(0, 0, 0.6),
            elevation=0.35,
            azimuth=0.1,
            base_velocity=(0.5, 0, 0),
        ),
        DEFAULT_EE,
    )
    assert np.linalg.norm(tr.landing[:2] - fast.xy[0]) < 1e-3
    assert np.allclose(tr.omega, 0)


def test_stored_energy_is_the_integral_of_the_band_force():
    for ee in (DEFAULT_EE, EndEffectorParams(C=-2.0), EndEffectorParams(C=1.5)):
        for dl in (0.0, 0.01, 0.05, 0.09):
            numeric = (
                quad(lambda x, ee=ee: float(band_force(x, ee)), 0, dl, limit=200)[0] if dl else 0.0
            )
            assert float(stored_energy(dl, ee)) == pytest.approx(numeric, abs=1e-7)


def test_grip_force_rises_as_stroke_shortens():
    strokes = np.linspace(0.03, 0.11, 30)
    band = band_state(strokes, 0.05, DEFAULT_EE)
    assert np.all(np.diff(band.grip) < 0)
    assert np.all(np.diff(band.energy) < 0)


def test_slack_band_gives_no_force():
    ee = EndEffectorParams(L0=0.3)
    assert float(band_state(0.1, 0.05, ee).push) == 0.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(mass=-0.1), "mass"),
        (dict(size=(0.05, 0.0, 0.05)), "size"),
    ],
)
def test_bad_object_raises(kwargs, match):
    base = dict(shape="cube", mass=0.05, size=(0.05, 0.05, 0.05))
    base.update(kwargs)
    with pytest.raises(InvalidParameter, match=match):
        ObjectParams(**base)


def test_unknown_shape_lists_valid_ones():
    with pytest.raises(InvalidParameter, match="cube, cuboid, cylinder, sphere, mesh"):
        ObjectParams(shape="pyramid", mass=0.05, size=(0.05, 0.05, 0.05))


def test_stroke_outside_range_raises():
    with pytest.raises(InvalidParameter, match="0.030 … 0.110"):
        predict_landing(_batch(get_object("cube50"), 1, stroke=0.2), DEFAULT_EE)


def test_negative_mass_in_batch_raises():
    with pytest.raises(InvalidParameter, match="mass"):
        ThrowBatch.build(
            stroke=0.05,
            position=(0, 0, 1),
            elevation=0.3,
            azimuth=0,
            shape=0,
            mass=-1.0,
            size=(0.05, 0.05, 0.05),
        )


def test_throw_that_never_reaches_its_plane_raises():
    b = _batch(get_object("cube50"), 1, position=(0, 0, 0.5), land_z=5.0)
    with pytest.raises(NoLanding, match="never crosses"):
        predict_landing(b, DEFAULT_EE)
    assert not predict_landing(b, DEFAULT_EE, strict=False).landed[0]


def test_bad_end_effector_parameters_raise():
    with pytest.raises(InvalidParameter, match="stroke range"):
        EndEffectorParams(stroke_min=0.2, stroke_max=0.1)
    with pytest.raises(InvalidParameter, match="unknown end-effector parameter"):
        EndEffectorParams.from_dict({"Ke9": 1.0})


@pytest.mark.parametrize(
    "field, value", [("Ke1", -100.0), ("Ke1", 0.0), ("Ke2", -1.0), ("Ke3", -400.0)]
)
def test_a_band_that_would_store_negative_energy_is_refused(field: str, value: float) -> None:
    """Stored energy ∫f dx over a stretch must be positive; the bounds make it so."""
    from dataclasses import replace

    from cell.errors import InvalidParameter
    from cell.model.params import DEFAULT_EE

    with pytest.raises(InvalidParameter, match=field):
        replace(DEFAULT_EE, **{field: value})
