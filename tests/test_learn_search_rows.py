"""A large log's hyper-parameter search on a draw of its rows (`cell.residual.learners.
SEARCH_ROWS`): each object keeps its share, the choice is what scikit-learn's own grid
search makes on those rows, and the chosen learner is fitted on every row; a log within the
bound is searched whole."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.model_selection import GridSearchCV, GroupKFold

from cell.residual import learners
from cell.residual.learners import GRIDS, fit_learner, make_pipeline


def _log(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n rows of 3 features, ΔL_s [m] a smooth function of them plus noise, 5 objects of
    unequal shares."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, (n, 3))
    y = 0.004 * np.sin(2 * x[:, 0]) + 0.002 * x[:, 1] ** 2 + 0.0003 * rng.standard_normal(n)
    groups = rng.choice(np.array(["a", "b", "c", "d", "e"]), n, p=[0.4, 0.3, 0.15, 0.1, 0.05])
    return x, y, groups


def test_a_log_within_the_bound_is_searched_whole() -> None:
    x, y, g = _log(120)
    xs, ys, gs = learners._search_rows(x, y, g, seed=0)
    assert xs is x and ys is y and gs is g


def test_a_larger_log_is_searched_on_a_draw_and_fitted_on_every_row(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(learners, "SEARCH_ROWS", 150)
    x, y, g = _log(600)
    xs, ys, gs = learners._search_rows(x, y, g, seed=0)
    assert abs(len(xs) - 150) <= 3  # each object's share rounded
    for obj in "abcde":  # every object, in its share of the rows
        assert np.mean(gs == obj) == pytest.approx(np.mean(g == obj), abs=0.02)
    rows = {tuple(r) for r in x}
    assert all(tuple(r) in rows for r in xs)  # rows of the log, each once
    assert len({tuple(r) for r in xs}) == len(xs)
    # the choice: scikit-learn's own search on the same rows and folds
    fit = fit_learner("svr", x, y, g, grid="small", seed=0)
    ref = GridSearchCV(
        make_pipeline("svr", grid="small"),
        GRIDS["svr"]["small"],
        cv=GroupKFold(n_splits=4),
        scoring="neg_mean_squared_error",
    ).fit(xs, ys * 1000.0, groups=gs)
    assert fit.best_params == ref.best_params_
    assert fit.inner_cv_mse_mm2 == pytest.approx(-ref.best_score_, rel=1e-12)
    assert fit.pipeline.named_steps["scale"].n_samples_seen_ == 600  # refitted on every row
