"""The model's inverse in the stroke and the ΔL_s targets (cell.residual.target)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from cell.model import DEFAULT_EE, ThrowBatch, predict_landing
from cell.residual.target import (
    NO_LANDING,
    NO_OBSERVATION,
    OK,
    TOO_FAR,
    TOO_NEAR,
    reach_along_azimuth,
    residual_targets,
    stroke_for_reach,
)


def _batch(n: int, seed: int = 0, stroke: tuple[float, float] = (0.035, 0.105)) -> ThrowBatch:
    rng = np.random.default_rng(seed)
    w = rng.uniform(0.03, 0.07, n)
    return ThrowBatch.build(
        stroke=rng.uniform(*stroke, n),
        position=np.c_[
            rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n), rng.uniform(0.4, 0.9, n)
        ],
        elevation=rng.uniform(0.2, 0.9, n),
        azimuth=rng.uniform(-3.0, 3.0, n),
        shape=rng.integers(0, 4, n),
        mass=rng.uniform(0.02, 0.12, n),
        size=np.c_[w, w, rng.uniform(0.03, 0.08, n)],
    )


def test_inverse_recovers_the_stroke_of_the_forward_model():
    b = _batch(500)
    land = predict_landing(b, DEFAULT_EE)
    sol = stroke_for_reach(b, reach_along_azimuth(b, land.xy), DEFAULT_EE)
    assert np.all(sol.status == OK)
    np.testing.assert_allclose(sol.stroke, b.stroke, atol=1e-8)
    assert np.max(np.abs(sol.miss)) < 1e-6
    assert sol.iterations < 40  # the secant steps converge far faster than bisection's 27+


def test_reach_falls_with_stroke_so_the_bracket_is_valid():
    b = _batch(50)
    strokes = np.linspace(DEFAULT_EE.stroke_min, DEFAULT_EE.stroke_max, 9)
    reach = []
    for s in strokes:
        bb = ThrowBatch(
            **{**{k: getattr(b, k) for k in b.__dataclass_fields__}, "stroke": np.full(50, s)}
        )
        reach.append(reach_along_azimuth(bb, predict_landing(bb, DEFAULT_EE).xy))
    assert np.all(np.diff(np.array(reach), axis=0) < 0)


def test_unreachable_reaches_are_flagged_not_clipped():
    b = _batch(6)
    land = predict_landing(b, DEFAULT_EE)
    r = reach_along_azimuth(b, land.xy)
    r[0] += 10.0  # farther than stroke_min throws
    r[1] = 0.01  # nearer than stroke_max throws
    sol = stroke_for_reach(b, r, DEFAULT_EE)
    assert sol.status[0] == TOO_FAR and sol.stroke[0] == DEFAULT_EE.stroke_min
    assert sol.status[1] == TOO_NEAR and sol.stroke[1] == DEFAULT_EE.stroke_max
    assert sol.miss[0] < 0 < sol.miss[1]
    assert np.all(sol.status[2:] == OK)


def test_a_throw_that_never_lands_is_flagged():
    b = ThrowBatch.build(
        stroke=[0.06],
        position=[(0, 0, 0.5)],
        elevation=[0.5],
        azimuth=[0.0],
        shape=[0],
        mass=[0.05],
        size=[(0.05, 0.05, 0.05)],
        land_z=[5.0],
    )
    sol = stroke_for_reach(b, np.array([1.0]), DEFAULT_EE)
    assert sol.status[0] == NO_LANDING


def test_targets_of_a_stroke_offset_world_are_minus_the_offset_and_correct_the_plan(caplog):
    """A world whose true stroke is the commanded one plus δ: the model's inverse of its
    landings is L_used + δ, so ΔL_s = -δ, and commanding L_model + ΔL_s lands on target."""
    delta = 0.004
    b = _batch(200, seed=3, stroke=(0.04, 0.10))

    def shifted(batch: ThrowBatch) -> np.ndarray:
        bb = ThrowBatch(
            **{
                **{k: getattr(batch, k) for k in batch.__dataclass_fields__},
                "stroke": batch.stroke + delta,
            }
        )
        return predict_landing(bb, DEFAULT_EE, check_stroke=False).xy

    observed = shifted(b)
    observed[0] += 20.0 * np.array([np.cos(b.azimuth[0]), np.sin(b.azimuth[0])])  # out of reach
    observed[1] = np.nan  # not observed
    with caplog.at_level(logging.WARNING, logger="cell.residual.target"):
        t = residual_targets(b, observed, DEFAULT_EE)
    assert not t.usable[0] and np.isnan(t.delta_stroke[0])
    assert t.excluded_counts()["beyond the model's reach at stroke_min"] == 1
    assert t.status[1] == NO_OBSERVATION and np.isnan(t.delta_stroke[1])
    assert t.excluded_counts()["no observed landing"] == 1
    assert "2 of 200 throws excluded" in caplog.text
    np.testing.assert_allclose(t.delta_stroke[2:], -delta, atol=1e-7)
    # plan: the model's stroke for a target, plus ΔL_s, thrown in the shifted world
    target = predict_landing(b, DEFAULT_EE).xy
    sol = stroke_for_reach(b, reach_along_azimuth(b, target), DEFAULT_EE)
    cmd = ThrowBatch(
        **{**{k: getattr(b, k) for k in b.__dataclass_fields__}, "stroke": sol.stroke - delta}
    )
    np.testing.assert_allclose(shifted(cmd), target, atol=1e-5)


@pytest.mark.parametrize("n", [1, 3])
def test_small_batches(n):
    b = _batch(n, seed=7)
    land = predict_landing(b, DEFAULT_EE)
    sol = stroke_for_reach(b, reach_along_azimuth(b, land.xy), DEFAULT_EE)
    np.testing.assert_allclose(sol.stroke, b.stroke, atol=1e-8)
