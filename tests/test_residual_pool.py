"""`cell learn`'s fits in joblib's processes give the serial run's table and model to the
bit: the round-robin's units and the saved learner's fit, started longest first beside
each other, and each learner refitted only when it beats the null candidates."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model import DEFAULT_EE
from cell.residual.campaign import shape_stretch_hook
from cell.residual.evaluate import (
    FitUnit,
    SaveUnit,
    round_robin,
    round_robin_and_save,
    round_robin_folds,
    unit_cost,
)
from cell.residual.learners import fit_learner, make_pipeline
from cell.residual.model import train_residual, training_data
from cell.synth import Campaign, NoiseModel, World, draw_campaign

NOISE = NoiseModel(along_rel=0.005, across_rel=0.0025, floor_m=0.003)
HOLD_OUT = 4  # objects held out a fold in the pool test


@pytest.fixture(scope="module")
def data():
    world = World(ee=DEFAULT_EE, noise=NOISE, predict=shape_stretch_hook(0.1))
    return training_data(
        draw_campaign(world, Campaign(n=140, stroke_m=(0.04, 0.10)), seed=4), DEFAULT_EE
    )


def test_the_pool_gives_the_serial_table_and_saved_model(data):
    """Two at a time in joblib's processes, started in `unit_cost`'s order (not the
    units'), against one after the other in this process: every fold's model, the table
    and the saved learner (the seeded forest: a seed not handed on would change it).
    Four objects held out a fold: 3 folds (4, 4 and 6 of the 14 objects), 7 units on the 2
    processes, each process running several one after another as with the thesis' 7 folds
    of 2 (15 units); the pool's bookkeeping is the same whatever a fold holds out."""
    learners = ("svr", "rf")
    serial = round_robin(data, learners=learners, hold_out=HOLD_OUT, grid="small", seed=3)
    saved_serial = train_residual(data, learner="rf", grid="small", seed=3)
    pooled, saved = round_robin_and_save(
        data, save="rf", learners=learners, hold_out=HOLD_OUT, grid="small", seed=3, jobs=2
    )
    # the order the pool starts them in is not the units' (or this checks no reordering)
    folds = round_robin_folds(sorted(set(data.groups[data.usable])), hold_out=HOLD_OUT, seed=3)
    assert len(folds) == 3
    units = [FitUnit(data, n, f, "small", 3) for n in learners for f in folds]
    costs = [unit_cost(u) for u in [*units, SaveUnit(data, "rf", "small", 3)]]
    assert sorted(range(len(costs)), key=lambda i: -costs[i]) != list(range(len(costs)))
    probe = data.features[data.usable]
    for name in learners:
        assert serial[name].as_dict() == pooled[name].as_dict()
        for a, b in zip(serial[name].folds, pooled[name].folds, strict=True):
            assert a.fold == b.fold
            np.testing.assert_array_equal(
                a.model.predict_features(probe), b.model.predict_features(probe)
            )
    assert "null" not in saved.best_params  # the forest itself, not a constant
    assert saved.best_params == saved_serial.best_params
    assert saved.training_objects == saved_serial.training_objects
    np.testing.assert_array_equal(
        saved.predict_features(probe), saved_serial.predict_features(probe)
    )


def test_the_refit_is_grid_search_cv_s_own(data):
    """A learner that beats the null candidates is refitted as GridSearchCV(refit=True)
    refits its choice: the same predictions to the bit."""
    from sklearn.model_selection import GridSearchCV, GroupKFold

    from cell.residual.learners import GRIDS

    m = data.usable
    x, y, g = data.features[m], data.targets.delta_stroke[m], data.groups[m]
    for name in ("svr", "mlp"):
        fitted = fit_learner(name, x, y, g, grid="small", seed=2)
        assert "null" not in fitted.best_params, name
        search = GridSearchCV(
            make_pipeline(name, grid="small", seed=2),
            GRIDS[name]["small"],
            cv=GroupKFold(n_splits=4),
            scoring="neg_mean_squared_error",
            refit=True,
        ).fit(x, y * 1000.0, groups=g)
        assert fitted.best_params == search.best_params_, name
        np.testing.assert_array_equal(fitted.pipeline.predict(x), search.predict(x))
