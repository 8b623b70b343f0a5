"""Throw planning: plans hit their targets, respect the bounds, and fail loudly.

The landing of every plan is checked twice: with the project's model
(`predict_landing`, ≤ 1 mm) and with an independent implementation of
MODEL.md written below (scipy DOP853 with a crossing event, ≤ 5 mm), which
does not import `cell.model`.
"""

from __future__ import annotations

import itertools
import math
import zlib

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from cell.bench.bench_plan import box_targets, family_targets
from cell.catalogue import catalogue
from cell.errors import InvalidParameter, UnreachableTarget
from cell.model import DEFAULT_EE, ThrowBatch, predict_landing
from cell.optimize import DEFAULT_BOUNDS, MISS_TOL, SIGMA_COLUMNS, ThrowBounds, plan_throw
from cell.optimize.verify import POLISH_TOL, fly, polish

OBJECTS = {k: e.params for k, e in catalogue().items()}

# ---- an independent implementation of MODEL.md (reference defaults copied here) ----
_EE = dict(r_r=0.010, l1=0.030, phi=math.pi / 2, d=0.020, L_t=0.160, L0=0.095, dt=0.012)
_KE = (400.0, 150.0, 114.6, 0.0)  # Ke3, Ke2, Ke1, C
_CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47, "mesh": 1.0}


def _independent_landing(shape: str, mass: float, size, sigma, land_z: float):
    x, y, z, vx, vy, vz, _roll, e, a, stroke = (float(v) for v in sigma)
    w = size[0]
    l2 = math.sqrt(((w - _EE["d"]) / 2) ** 2 + (_EE["L_t"] - stroke) ** 2)
    dl = _EE["l1"] + _EE["r_r"] * _EE["phi"] + _EE["d"] / 2 + l2 - _EE["L0"]
    ke3, ke2, ke1, c = _KE
    f_e = max(ke3 * dl**3 + ke2 * dl**2 + ke1 * dl + c, 0.0) if dl > 0 else 0.0
    f_o = 2 * f_e * math.cos(math.atan2(w - _EE["d"], 2 * (_EE["L_t"] - stroke)))
    sx, sy, sz = size
    if shape == "sphere":
        area = math.pi * sx**2 / 4
    elif shape == "cylinder":
        r = sx / 2
        area = (2 * math.pi * r**2 + 2 * math.pi * r * sz) / 4
    else:
        area = (sx * sy + sy * sz + sz * sx) / 2
    k = 0.5 * 1.225 * _CD[shape] * area / mass
    u = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])

    def rhs(push: float):
        def f(_t, s):
            v = s[3:]
            acc = -k * np.linalg.norm(v) * v + np.array([0.0, 0.0, -9.81]) + push / mass * u
            return np.r_[v, acc]

        return f

    s0 = np.array([x, y, z, vx, vy, vz])
    tol = dict(method="DOP853", rtol=1e-11, atol=1e-12)
    s1 = solve_ivp(rhs(f_o), (0.0, _EE["dt"]), s0, **tol).y[:, -1]

    def crossing(_t, s):
        return s[2] - land_z

    crossing.terminal = True
    crossing.direction = -1
    sol = solve_ivp(rhs(0.0), (_EE["dt"], 30.0), s1, events=crossing, **tol)
    assert sol.t_events[0].size, "never lands"
    p = sol.y_events[0][0]
    return p[0], p[1], sol.t_events[0][0]


# MODEL.md golden rows (object, stroke, release, elevation/azimuth deg, base velocity, land_z,
# landed x, y, flight time), copied here to validate the independent integrator itself
_GOLDEN = [
    ("cube", 0.060, (0.05,) * 3, 0.0625, (0, 0, 0.6), 30, 0, (0, 0, 0), 0.0, 1.2902, 0.0, 0.5290),
    (
        "cube",
        0.020,
        (0.03,) * 3,
        0.08,
        (0, 0, 0.7),
        10,
        -15,
        (0, 0, 0),
        0.0,
        2.6318,
        -0.7052,
        0.5008,
    ),
    (
        "cylinder",
        0.075,
        (0.05, 0.05, 0.07),
        0.06,
        (0, 0, 0.6),
        20,
        5,
        (0.5, 0, 0),
        0.0,
        1.2128,
        0.0869,
        0.4457,
    ),
    (
        "cylinder",
        0.120,
        (0.07, 0.07, 0.06),
        0.1,
        (0, 0, 0.5),
        60,
        -30,
        (0, 0.3, 0.2),
        0.1,
        0.0870,
        0.0585,
        0.3636,
    ),
]


def test_independent_integrator_reproduces_model_md_golden_values():
    for shape, mass, size, stroke, p0, e, a, vb, lz, gx, gy, gt in _GOLDEN:
        sigma = [*p0, *vb, 0.0, math.radians(e), math.radians(a), stroke]
        x, y, t = _independent_landing(shape, mass, size, sigma, lz)
        assert abs(x - gx) < 1e-3 and abs(y - gy) < 1e-3 and abs(t - gt) < 1e-3


def _check_plan(obj, plan, target, bounds=DEFAULT_BOUNDS):
    assert not bounds.violation(plan.sigma, DEFAULT_EE), bounds.violation(plan.sigma, DEFAULT_EE)
    land = predict_landing(plan.to_batch(obj), DEFAULT_EE)
    miss = math.hypot(land.x[0] - target[0], land.y[0] - target[1])
    assert miss <= MISS_TOL
    assert abs(miss - plan.miss_m) < 1e-9
    assert abs(land.t_flight[0] - plan.t_flight_s) < 1e-9
    assert plan.land_z_m == target[2]


@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_plans_hit_random_reachable_targets_for_every_object(name):
    obj = OBJECTS[name]
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    for tgt in family_targets(obj, 3, rng):
        plan = plan_throw(obj, tgt, method="fast")
        assert plan.method == "fast"
        _check_plan(obj, plan, tgt)
    for tgt in box_targets(obj, 2, rng):
        plan = plan_throw(obj, tgt)  # auto: fast if its family reaches, else the NLP
        _check_plan(obj, plan, tgt)
    tgt = box_targets(obj, 1, rng)[0]
    plan = plan_throw(obj, tgt, method="nlp")
    assert plan.method == "nlp"
    _check_plan(obj, plan, tgt)


@pytest.mark.parametrize("name", ["cube50", "sphere40", "cyl70", "o5_tetrapack", "duck"])
def test_independent_model_lands_the_printed_sigma_within_5_mm(name):
    obj = OBJECTS[name]
    rng = np.random.default_rng(7)
    targets = [*family_targets(obj, 2, rng), *box_targets(obj, 1, rng)]
    for i, tgt in enumerate(targets):
        plan = plan_throw(obj, tgt, method="nlp" if i == 2 else "auto")
        # the σ* as printed (JSON floats), by column name
        d = plan.as_dict()
        sigma = [float(d[c]) for c in SIGMA_COLUMNS]
        x, y, t = _independent_landing(obj.shape, obj.mass, obj.size, sigma, d["land_z_m"])
        assert math.hypot(x - tgt[0], y - tgt[1]) < 5e-3
        assert abs(t - plan.t_flight_s) < 5e-3


def test_moving_base_plans_use_bounded_velocities():
    obj = OBJECTS["cube50"]
    bounds = DEFAULT_BOUNDS.with_base_velocity(0.5)
    rng = np.random.default_rng(3)
    for tgt in box_targets(obj, 3, rng):
        plan = plan_throw(obj, tgt, bounds=bounds)
        assert plan.method == "nlp"
        _check_plan(obj, plan, tgt, bounds)
    # least energy uses the base velocity: a far target gets a moving release
    far = plan_throw(obj, (3.0, 0.0, 0.0), bounds=bounds)
    fixed = plan_throw(obj, (3.0, 0.0, 0.0), method="nlp")
    assert far.energy_j < fixed.energy_j
    assert far.vx_mps > 0.4
    # a given (measured) base velocity is honoured
    given = plan_throw(obj, (2.0, 0.5, 0.1), base_velocity=(0.2, -0.1, 0.05))
    assert (given.vx_mps, given.vy_mps, given.vz_mps) == (0.2, -0.1, 0.05)
    _check_plan(obj, given, (2.0, 0.5, 0.1), bounds.with_base_velocity(0.2))


def test_unreachable_targets_raise_with_the_reachable_range():
    obj = OBJECTS["cube50"]
    with pytest.raises(UnreachableTarget) as info:
        plan_throw(obj, (8.0, 0.0, 0.0))
    msg = str(info.value)
    lo, hi = info.value.reach_range
    assert "cube50 reaches" in msg and f"{hi:.2f} m" in msg
    assert 0 < lo < hi < 7.6  # the target lies 7.6 m from the release point
    # the range is the real one: the farthest candidate throw lands at hi
    p0 = DEFAULT_BOUNDS.nominal_release(np.array([8.0, 0.0]))
    elev = DEFAULT_BOUNDS.elevations()
    reach = [
        predict_landing(
            ThrowBatch.single(obj, stroke=0.03, position=p0, elevation=e, azimuth=0.0), DEFAULT_EE
        ).x[0]
        - p0[0]
        for e in elev
    ]
    assert abs(max(reach) - hi) < 1e-9
    # the fast path alone raises too, and so does a target above every trajectory
    with pytest.raises(UnreachableTarget):
        plan_throw(obj, (8.0, 0.0, 0.0), method="fast")
    with pytest.raises(UnreachableTarget, match="never comes down"):
        plan_throw(OBJECTS["o6_bottle"], (1.0, 0.0, 3.0))


def test_fast_path_picks_the_least_energy_elevation():
    """Secondary objective: among the candidate elevations, the longest stroke (least energy)."""
    obj = OBJECTS["cube50"]
    tgt = np.array([1.8, 0.6, 0.15])
    plan = plan_throw(obj, tgt, method="fast")
    p0 = np.array([plan.x_m, plan.y_m, plan.z_m])
    dist = math.hypot(*(tgt[:2] - p0[:2]))
    found = []
    for e in DEFAULT_BOUNDS.elevations():

        def reach(s, e=e):
            b = ThrowBatch.single(obj, stroke=s, position=p0, elevation=e, azimuth=0.0, land_z=0.15)
            return predict_landing(b, DEFAULT_EE).x[0] - p0[0] - dist

        if reach(0.03) > 0 > reach(0.11):
            found.append((brentq(reach, 0.03, 0.11, xtol=1e-12), e))
    assert len(found) >= 3  # several elevations hit: the choice is real
    best_stroke, best_e = max(found)
    assert abs(plan.elevation_rad - best_e) < 1e-12
    assert abs(plan.stroke_m - best_stroke) < 1e-5
    # the NLP over the whole box does at least as well on energy
    nlp = plan_throw(obj, tgt, method="nlp")
    assert nlp.energy_j <= plan.energy_j + 1e-9


@pytest.mark.parametrize(
    ("name", "target"), [("cube50", (1.8, 0.6, 0.15)), ("sphere40", (-2.0, 1.0, 0.0))]
)
def test_nlp_energy_is_no_higher_than_any_fast_plan_from_the_release_box(name, target):
    """Secondary objective of the NLP: least stored energy over the whole release box.

    Fast plans released from a 3×3×3 grid over the box (corners included) are
    hitting plans the NLP could have chosen; none stores less energy."""
    obj = OBJECTS[name]
    nlp = plan_throw(obj, target, method="nlp")
    energies = []
    lo, hi = DEFAULT_BOUNDS.position_min, DEFAULT_BOUNDS.position_max
    for c in itertools.product(*(np.linspace(lo[i], hi[i], 3) for i in range(3))):
        try:
            energies.append(plan_throw(obj, target, current=c, method="fast").energy_j)
        except UnreachableTarget:
            continue
    assert len(energies) > 10
    assert nlp.energy_j <= min(energies) + 1e-6


def test_current_pose_is_the_fast_release_point():
    obj = OBJECTS["sphere55"]
    cur = (0.5, -0.2, 0.7)
    plan = plan_throw(obj, (2.0, -1.0, 0.1), current=cur, method="fast")
    assert (plan.x_m, plan.y_m, plan.z_m) == cur
    # outside the box: moved into it
    plan = plan_throw(obj, (2.0, -1.0, 0.1), current=(1.0, -0.2, 0.7), method="fast")
    assert plan.x_m == DEFAULT_BOUNDS.position_max[0]


def test_custom_bounds_are_honoured():
    obj = OBJECTS["cyl50"]
    bounds = ThrowBounds(
        position_min=(0.3, -0.1, 0.5),
        position_max=(0.5, 0.1, 0.6),
        elevation_min=math.radians(20),
        elevation_max=math.radians(40),
        stroke_min=0.05,
        stroke_max=0.09,
        release_height=0.55,
    )
    rng = np.random.default_rng(11)
    for method in ("fast", "nlp"):
        for tgt in family_targets(obj, 2, rng, bounds=bounds):
            plan = plan_throw(obj, tgt, bounds=bounds, method=method)
            _check_plan(obj, plan, tgt, bounds)


def test_bad_inputs_raise_typed_errors():
    obj = OBJECTS["cube50"]
    with pytest.raises(InvalidParameter):
        plan_throw(obj, (1.0, 2.0))
    with pytest.raises(InvalidParameter):
        plan_throw(obj, (1.0, 2.0, float("nan")))
    with pytest.raises(InvalidParameter):
        plan_throw(obj, (1.0, 2.0, 0.0), method="best")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameter):
        plan_throw(obj, (1.0, 2.0, 0.0), base_velocity=(0.1, 0, 0), method="fast")
    with pytest.raises(InvalidParameter):
        ThrowBounds(position_min=(0.7, 0, 0), position_max=(0.6, 1, 1))
    with pytest.raises(InvalidParameter):
        ThrowBounds(elevation_min=1.0, elevation_max=0.5)
    with pytest.raises(InvalidParameter):
        ThrowBounds(stroke_min=0.05)
    with pytest.raises(InvalidParameter):
        ThrowBounds(stroke_min=0.01, stroke_max=0.05).stroke_range(DEFAULT_EE)


def test_polish_removes_a_residual_miss_on_the_numpy_model():
    obj = OBJECTS["cube50"]
    lo, hi = DEFAULT_BOUNDS.vectors(DEFAULT_EE)
    tgt = np.array([1.7, -0.5, 0.2])
    plan = plan_throw(obj, tgt, method="nlp")
    start = plan.sigma.copy()
    start[9] += 3e-4
    start[8] += 2e-3
    _, _, miss0, _ = polish(obj, start, tgt, DEFAULT_EE, lo, hi)
    assert fly(obj, start, tgt, DEFAULT_EE)[1][0] > 3e-3  # it started well off
    assert miss0 <= POLISH_TOL
    # the stroke on its upper bound: the elevation takes the along-track correction
    on_bound = np.array([0.4, 0.0, 0.8, 0, 0, 0, 0, 0.5, 0.3, hi[9]])
    xy, _, _ = fly(obj, on_bound, np.array([0.0, 0.0, 0.1]), DEFAULT_EE)
    off = np.array([xy[0, 0] + 0.003, xy[0, 1] + 0.002, 0.1])
    sigma, _, miss, _ = polish(obj, on_bound, off, DEFAULT_EE, lo, hi)
    assert miss <= POLISH_TOL
    assert sigma[9] == hi[9] and sigma[7] != on_bound[7]


def test_bounds_from_configuration_mapping():
    b = ThrowBounds.from_dict(
        {
            "position_min": [0.1, -0.2, 0.5],
            "position_max": [0.5, 0.2, 1.0],
            "stroke_max": 0.1,
            "stroke_min": 0.04,
        }
    )
    assert b.position_min == (0.1, -0.2, 0.5) and b.stroke_range(DEFAULT_EE) == (0.04, 0.1)
    with pytest.raises(InvalidParameter, match="valid: position_min"):
        ThrowBounds.from_dict({"box": [0, 0, 0]})
    with pytest.raises(InvalidParameter, match="position_min"):
        ThrowBounds.from_dict({"position_min": [0.1, 0.2]})
