"""The three learners of thesis Table 5.1 as scikit-learn pipelines, tuned by
inner cross-validation grouped by object.

Every pipeline drops the features that do not vary in its training set (an
object class never seen in training then cannot move a prediction), clips the
rest to the range they spanned in training (no wild extrapolation to an unseen
object's descriptors), scales them, and regresses ΔL_s in millimetres (SVR's ε
and the MLP's loss are then on a sensible scale). Hyper-parameters are chosen
by `GridSearchCV` over `GroupKFold` splits of the *training* objects only:
whatever objects an evaluation holds out never reach `fit_learner`.

Two null candidates take part in the choice: ΔL_s = 0 (the model alone) and a
constant ΔL_s (a stroke offset). When the tuned learner does not beat the better
of them in the same inner CV, that null is fitted instead: a learner that cannot predict
the residual better than that would only add its own noise to the plan.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.errors import InvalidParameter

__all__ = ["LEARNERS", "GRIDS", "RangeClip", "make_pipeline", "fit_learner", "FittedLearner"]

LEARNERS = ("svr", "rf", "mlp")

# name -> grid size -> parameter grid of the pipeline step "reg". "medium" is "full" without
# the candidates the inner CV never chose on 865-throw campaigns and that cost the most
# (SVR's γ 0.03 and "scale", ε 0.02; the forest's 5-throw leaves; the network's α 0.1):
# docs/HISTORY.md
GRIDS: dict[str, dict[str, dict[str, list[Any]]]] = {
    "svr": {
        "small": {"reg__C": [10.0, 100.0], "reg__epsilon": [0.05], "reg__gamma": [0.003, 0.01]},
        "medium": {
            "reg__C": [1.0, 10.0, 100.0, 1000.0],
            "reg__epsilon": [0.05, 0.1],
            "reg__gamma": [0.001, 0.003, 0.01],
        },
        "full": {
            "reg__C": [1.0, 10.0, 100.0, 1000.0],
            "reg__epsilon": [0.02, 0.05, 0.1],
            "reg__gamma": [0.001, 0.003, 0.01, 0.03, "scale"],
        },
    },
    "rf": {
        "small": {"reg__min_samples_leaf": [3, 10]},
        "medium": {"reg__min_samples_leaf": [1, 20], "reg__max_features": [1.0, 0.3]},
        "full": {"reg__min_samples_leaf": [1, 5, 20], "reg__max_features": [1.0, 0.3]},
    },
    "mlp": {
        "small": {"reg__alpha": [1e-3, 1e-1]},
        "medium": {"reg__alpha": [1e-3, 1.0]},
        "full": {"reg__alpha": [1e-3, 1e-1, 1.0]},
    },
}


class RangeClip:
    """A scikit-learn transformer that clips each feature to the range it spanned in
    training. An unseen object whose descriptor lies far outside what the training
    objects showed is then treated like the nearest training case instead of
    being extrapolated (an RBF kernel would forget it, a network would run away).
    """

    def fit(self, x: np.ndarray, y: Any = None) -> RangeClip:
        """Store the per-feature minimum and maximum of x (n, k)."""
        x = np.asarray(x, float)
        self.min_ = x.min(axis=0)
        self.max_ = x.max(axis=0)
        return self

    def transform(self, x: np.ndarray) -> np.ndarray:
        """x clipped to the training range, shape (n, k)."""
        return np.clip(np.asarray(x, float), self.min_, self.max_)

    def fit_transform(self, x: np.ndarray, y: Any = None) -> np.ndarray:
        """fit, then transform."""
        return self.fit(x, y).transform(x)

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """No parameters (scikit-learn estimator protocol)."""
        return {}

    def set_params(self, **params: Any) -> RangeClip:
        """No parameters (scikit-learn estimator protocol)."""
        return self


def make_pipeline(name: str, *, grid: str = "full", seed: int = 0) -> Any:
    """An unfitted pipeline: VarianceThreshold → RangeClip → StandardScaler → regressor.

    Args:
        name: one of LEARNERS.
        grid: "small" (fast, for tests; smaller estimators too), "medium" or "full" (the
            full-size estimators; medium searches fewer hyper-parameters, docs/HISTORY.md).
        seed: random state of the forest and the network.

    Raises:
        InvalidParameter: an unknown learner or grid.
    """
    from sklearn.ensemble import RandomForestRegressor
    from sklearn.feature_selection import VarianceThreshold
    from sklearn.neural_network import MLPRegressor
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVR

    if name not in LEARNERS:
        raise InvalidParameter(f"unknown learner {name!r}; valid: {', '.join(LEARNERS)}")
    if grid not in GRIDS[name]:
        raise InvalidParameter(f"unknown grid {grid!r}; valid: {', '.join(GRIDS[name])}")
    small = grid == "small"
    reg: Any
    if name == "svr":
        reg = SVR(kernel="rbf", C=100.0, epsilon=0.05, gamma=0.003)
    elif name == "rf":
        reg = RandomForestRegressor(
            n_estimators=60 if small else 200, min_samples_leaf=3, random_state=seed, n_jobs=1
        )
    else:
        reg = MLPRegressor(
            hidden_layer_sizes=(32, 32) if small else (64, 64, 64),  # three layers (thesis)
            alpha=1e-2,
            learning_rate_init=3e-3,
            max_iter=300 if small else 1000,
            early_stopping=False,
            random_state=seed,
        )
    return Pipeline(
        [
            ("drop", VarianceThreshold(1e-12)),
            ("clip", RangeClip()),
            ("scale", StandardScaler()),
            ("reg", reg),
        ]
    )


@dataclass(frozen=True)
class FittedLearner:
    """A tuned, fitted pipeline.

    Attributes:
        name: learner name.
        pipeline: the fitted pipeline (predicts ΔL_s in mm).
        best_params: the hyper-parameters the inner CV chose.
        inner_cv_mse_mm2: the inner CV's mean squared error of the choice [mm²].
    """

    name: str
    pipeline: Any
    best_params: dict[str, Any]
    inner_cv_mse_mm2: float

    def predict_m(self, x: np.ndarray) -> np.ndarray:
        """ΔL_s [m] for feature rows x, shape (n,)."""
        return np.asarray(self.pipeline.predict(np.asarray(x, float)), float) / 1000.0


def _null_mse(splits: list[Any], y_mm: np.ndarray) -> dict[str, float]:
    """The inner CV's mean squared error [mm²] of the null candidates over `splits`
    ((train, test) index pairs): "zero" (no residual) and "mean" (a constant offset)."""
    null_mse = {"zero": 0.0, "mean": 0.0}
    for train, test in splits:
        null_mse["zero"] += float(np.mean(y_mm[test] ** 2)) / len(splits)
        null_mse["mean"] += float(np.mean((y_mm[test] - y_mm[train].mean()) ** 2)) / len(splits)
    return null_mse


# Rows the inner CV's hyper-parameter search runs on at most: a log larger than this is
# searched on a draw of this many, each object's share kept, and the choice refitted on all
# of it. An SVR's fit grows with the square of the rows or faster: `cell learn` took 84 s on
# 2,000 rows and 194 s on 5,000, and 20,000 had not ended after 30 min (docs/HISTORY.md);
# the campaigns the figures are made of (865 throws) are searched whole, as before.
SEARCH_ROWS = 2000


def _search_rows(
    x: np.ndarray, y: np.ndarray, groups: np.ndarray, seed: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows the inner CV searches: all of them up to `SEARCH_ROWS`, else a draw of
    `SEARCH_ROWS` (seeded) taking each object's share of the rows, at least one each, in
    their order."""
    n = x.shape[0]
    if n <= SEARCH_ROWS:
        return x, y, groups
    rng = np.random.default_rng(seed)
    keep: list[np.ndarray] = []
    for g in np.unique(groups):
        rows = np.flatnonzero(groups == g)
        k = max(1, round(SEARCH_ROWS * rows.size / n))
        keep.append(rng.choice(rows, min(k, rows.size), replace=False))
    idx = np.sort(np.concatenate(keep))
    return x[idx], y[idx], groups[idx]


def fit_learner(
    name: str,
    x: np.ndarray,
    delta_m: np.ndarray,
    groups: np.ndarray,
    *,
    grid: str = "full",
    inner_splits: int = 4,
    seed: int = 0,
) -> FittedLearner:
    """Tune a learner by grouped inner CV on (x, ΔL_s) (on a draw of `SEARCH_ROWS` rows
    where there are more, `_search_rows`) and refit its choice on all of it,
    when it beats the null candidates (no residual, a constant one) in that CV; else the
    better null, fitted on all of it (the learner is then not refitted: nothing would read it).

    Args:
        name: one of LEARNERS.
        x: features, shape (n, k).
        delta_m: ΔL_s [m], shape (n,).
        groups: object id of each row, shape (n,): inner folds never split an object.
        grid: "small", "medium" or "full" hyper-parameter grid.
        inner_splits: GroupKFold splits (capped at the number of objects).
        seed: random state.

    Raises:
        InvalidParameter: fewer than 2 objects, or mismatched shapes.
    """
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.model_selection import GridSearchCV, GroupKFold

    x = np.asarray(x, float)
    y_mm = np.asarray(delta_m, float) * 1000.0
    groups = np.asarray(groups)
    if x.shape[0] != y_mm.shape[0] or groups.shape[0] != y_mm.shape[0]:
        raise InvalidParameter(
            f"features ({x.shape[0]} rows), targets ({y_mm.shape[0]}) and groups "
            f"({groups.shape[0]}) must have one row per throw"
        )
    if not np.all(np.isfinite(x)) or not np.all(np.isfinite(y_mm)):
        raise InvalidParameter("features and targets must be finite (drop unusable throws first)")
    n_groups = len(np.unique(groups))
    if n_groups < 2:
        raise InvalidParameter(f"need throws of at least 2 objects to tune by CV; got {n_groups}")
    cv = GroupKFold(n_splits=min(inner_splits, n_groups))
    xs, ys, gs = _search_rows(x, y_mm, groups, seed)
    search = GridSearchCV(
        make_pipeline(name, grid=grid, seed=seed),
        GRIDS[name][grid],
        cv=cv,
        scoring="neg_mean_squared_error",
        n_jobs=None,  # 1, or the caller's joblib.parallel_config (cell learn: one per core)
        refit=False,  # below, and only when the learner beats the null candidates
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        search.fit(xs, ys, groups=gs)
    best_mse = float(-search.best_score_)
    # The null candidates: no residual at all, and a constant offset. A learner that
    # cannot beat them in the inner CV would only add its noise to the plan.
    null_mse = _null_mse(list(cv.split(xs, ys, gs)), ys)
    null = min(null_mse, key=lambda k: null_mse[k])
    if null_mse[null] <= best_mse:  # the learner's own refit would be thrown away: none
        from sklearn.dummy import DummyRegressor
        from sklearn.pipeline import Pipeline

        strategy = {"zero": {"strategy": "constant", "constant": 0.0}, "mean": {"strategy": "mean"}}
        pipe = Pipeline([("reg", DummyRegressor(**strategy[null]))]).fit(x, y_mm)  # type: ignore[arg-type]
        return FittedLearner(
            name=name,
            pipeline=pipe,
            best_params={"null": null, "learner_cv_mse_mm2": best_mse, **search.best_params_},
            inner_cv_mse_mm2=null_mse[null],
        )
    # GridSearchCV's refit=True, done here: its choice, cloned, fitted on all of (x, y)
    from sklearn.base import clone

    pipe = clone(search.estimator).set_params(**clone(search.best_params_, safe=False))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        pipe.fit(x, y_mm)
    return FittedLearner(
        name=name,
        pipeline=pipe,
        best_params=dict(search.best_params_),
        inner_cv_mse_mm2=best_mse,
    )
