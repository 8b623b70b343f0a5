"""`cell learn`'s fits: each learner refitted only when it beats the null candidates, as
GridSearchCV refits its choice."""

from __future__ import annotations

import numpy as np
import pytest

from cell.model import DEFAULT_EE
from cell.residual.campaign import shape_stretch_hook
from cell.residual.learners import fit_learner, make_pipeline
from cell.residual.model import training_data
from cell.synth import Campaign, NoiseModel, World, draw_campaign

NOISE = NoiseModel(along_rel=0.005, across_rel=0.0025, floor_m=0.003)


@pytest.fixture(scope="module")
def data():
    world = World(ee=DEFAULT_EE, noise=NOISE, predict=shape_stretch_hook(0.1))
    return training_data(
        draw_campaign(world, Campaign(n=140, stroke_m=(0.04, 0.10)), seed=4), DEFAULT_EE
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
