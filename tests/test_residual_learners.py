"""The learner pipelines: grouped tuning, the null candidates, the range clip."""

from __future__ import annotations

import numpy as np
import pytest

from cell.errors import InvalidParameter
from cell.residual.learners import RangeClip, fit_learner, make_pipeline


def _data(signal: bool, n_groups: int = 8, per: int = 15, seed: int = 0):
    rng = np.random.default_rng(seed)
    g = np.repeat(np.arange(n_groups), per)
    width = np.repeat(rng.uniform(0.03, 0.07, n_groups), per)
    x = np.c_[width, rng.uniform(0.04, 0.1, g.size), np.ones(g.size)]  # last column constant
    y = (0.1 * width if signal else 0.0) + rng.normal(0, 5e-5, g.size)  # [m]
    return x, y, g.astype(str)


def test_a_learnable_residual_is_learned():
    x, y, g = _data(True)
    f = fit_learner("svr", x, y, g, grid="small")
    assert "null" not in f.best_params
    assert np.sqrt(np.mean((f.predict_m(x) - 0.1 * x[:, 0]) ** 2)) < 3e-4


def test_noise_alone_gives_a_null_residual():
    x, y, g = _data(False)
    f = fit_learner("svr", x, y, g, grid="small")
    assert f.best_params["null"] in ("zero", "mean")
    pred = f.predict_m(x)
    assert np.ptp(pred) == 0 and abs(pred[0]) < 1e-4


def test_range_clip_holds_unseen_features_to_the_training_range():
    c = RangeClip().fit(np.array([[0.0, 1.0], [2.0, 3.0]]))
    np.testing.assert_array_equal(
        c.transform(np.array([[-5.0, 2.0], [9.0, 9.0]])), [[0, 2], [2, 3]]
    )
    pipe = make_pipeline("mlp", grid="small")
    assert [name for name, _ in pipe.steps] == ["drop", "clip", "scale", "reg"]


def test_bad_learner_input_is_rejected():
    x, y, g = _data(True)
    with pytest.raises(InvalidParameter, match="valid: svr, rf, mlp"):
        fit_learner("gp", x, y, g)
    with pytest.raises(InvalidParameter, match="at least 2 objects"):
        fit_learner("svr", x, y, np.zeros(len(y)))
    with pytest.raises(InvalidParameter, match="finite"):
        fit_learner("svr", x, np.full(len(y), np.nan), g)


def test_the_medium_grid_is_the_full_one_with_fewer_candidates_and_the_same_estimators():
    """`cell learn`'s default grid searches a subset of the full grid's hyper-parameters
    with the full grid's estimators, so a choice the full search makes from that subset
    is the same model (docs/HISTORY.md: the example's unseen-object figures are)."""
    from cell.residual.learners import GRIDS, LEARNERS

    for name in LEARNERS:
        medium, full = GRIDS[name]["medium"], GRIDS[name]["full"]
        assert set(medium) == set(full), name
        assert all(set(medium[k]) <= set(full[k]) for k in medium), name
        n_medium = int(np.prod([len(v) for v in medium.values()]))
        assert n_medium < int(np.prod([len(v) for v in full.values()])), name
        same = make_pipeline(name, grid="full").get_params()["reg"].get_params()
        assert make_pipeline(name, grid="medium").get_params()["reg"].get_params() == same
    with pytest.raises(InvalidParameter, match="valid: small, medium, full"):
        make_pipeline("svr", grid="large")


def test_cell_learn_searches_the_medium_grid_by_default():
    from cell.cli import build_parser

    args = build_parser().parse_args(["learn", "throws.csv", "-o", "r.skops"])
    assert args.grid == "medium"
