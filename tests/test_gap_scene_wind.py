"""cell.gap.scene_wind: what a constant-wind fit should find, on the model's own worlds
(no scene): each measurement against a second solver or a world it must give back."""

from __future__ import annotations

import numpy as np

from cell.gap.scene_wind import expected_shift, fitted_wind, weighted_wind, wind_jacobians
from cell.gap.world import throw_records
from cell.log.table import ThrowTable
from cell.model.params import DEFAULT_EE
from cell.model.throw import ThrowBatch


def _batch(n: int = 24, seed: int = 3) -> ThrowBatch:
    recs = throw_records(n, np.random.default_rng(seed))
    return ThrowTable.from_records(
        [{**r, "landed_x_m": 0.0, "landed_y_m": 0.0} for r in recs]
    ).to_batch()


def test_weighted_wind_is_the_linear_least_squares_constant() -> None:
    rng = np.random.default_rng(0)
    jac = rng.normal(size=(30, 2, 2))
    winds = rng.normal([2.0, -1.0], 1.0, (30, 2))
    w, cov, n_eff = weighted_wind(jac, winds)
    # a second solver: the stacked system J_i w = J_i w_i in least squares
    ref = np.linalg.lstsq(
        jac.reshape(-1, 2), np.einsum("nij,nj->ni", jac, winds).ravel(), rcond=None
    )[0]
    assert np.allclose(w, ref, atol=1e-12)
    assert 1.0 < n_eff < 30.0
    # equal sensitivities: the plain mean, its variance 1/n, every throw counts
    same = np.tile(np.array([[0.3, 0.1], [-0.05, 0.2]]), (30, 1, 1))
    w, cov, n_eff = weighted_wind(same, winds)
    assert np.allclose(w, winds.mean(axis=0), atol=1e-12)
    assert np.allclose(cov, np.eye(2) / 30, atol=1e-12)
    assert abs(n_eff - 30.0) < 1e-9


def test_fitted_wind_gives_back_the_wind_through_the_worlds_drag() -> None:
    b = _batch()
    factor = np.where(np.arange(len(b)) % 2 == 0, 0.5, 0.8)  # the world's drag over the model's
    wind = np.array([2.0, -1.0])
    truth = expected_shift(b, DEFAULT_EE, wind, 0.0, nodes=1, factor=factor)
    w, rms = fitted_wind(b, DEFAULT_EE, truth, factor=factor)
    assert np.allclose(w, wind, atol=2e-3) and rms < 1e-4
    # through the model's own drag (twice the world's on half the throws) the wind reads
    # lower, by about the drag ratio (the shift goes with k · w to first order)
    w_model, rms_model = fitted_wind(b, DEFAULT_EE, truth)
    ratio = w_model / wind
    assert np.all((ratio > 0.5) & (ratio < 0.8)) and rms_model > 10 * rms


def test_weighted_wind_predicts_the_fit_of_per_throw_winds() -> None:
    b = _batch()
    rng = np.random.default_rng(7)
    mean = np.array([1.5, 0.5])
    winds = mean + rng.normal(0.0, 0.3, (len(b), 2))
    per_throw = np.zeros((len(b), 2))
    for i in range(len(b)):  # each throw in its own wind
        per_throw[i] = expected_shift(b, DEFAULT_EE, winds[i], 0.0, nodes=1)[i]
    w_fit, _ = fitted_wind(b, DEFAULT_EE, per_throw)
    w_lin, _, _ = weighted_wind(wind_jacobians(b, DEFAULT_EE, mean), winds)
    assert np.allclose(w_fit, w_lin, atol=0.03)
    # and not the plain mean of the draws: the weights matter on this campaign
    assert np.linalg.norm(w_lin - winds.mean(axis=0)) > 0.03
