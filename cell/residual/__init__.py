"""Residual learning of the stroke correction ΔL_s (thesis chapter 5).

The identified model misses on unseen, oddly shaped objects; a learned
residual ΔL_s, predicted from the object's parameters, the shape descriptors
of the composite grip cloud and the throw's pose, corrects the planned stroke:
the cell commands L_s + ΔL_s.

* `target`: ΔL_s of logged throws by the model's own inverse in the stroke.
* `cloud`, `features`: the composite point cloud and the feature vectors.
* `learners`: SVR, random forest and MLP pipelines tuned by grouped inner CV.
* `model`: the saved `ResidualModel` and `apply_residual` for the planner.
* `evaluate`: the round-robin of thesis Table 5.1.
* `campaign`: a world with a shape-dependent stretch, and throws at set targets.
* `plot`: figures.
"""

from cell.residual.campaign import shape_stretch_hook, targeted_throws, unseen_ids
from cell.residual.evaluate import round_robin, round_robin_folds
from cell.residual.features import FEATURE_NAMES, GripPose
from cell.residual.learners import LEARNERS
from cell.residual.model import (
    CorrectedStroke,
    ResidualModel,
    apply_residual,
    residual_for_plan,
    train_residual,
    training_data,
)
from cell.residual.target import residual_targets, stroke_for_reach

__all__ = [
    "FEATURE_NAMES",
    "LEARNERS",
    "CorrectedStroke",
    "GripPose",
    "ResidualModel",
    "apply_residual",
    "residual_for_plan",
    "residual_targets",
    "round_robin",
    "round_robin_folds",
    "shape_stretch_hook",
    "stroke_for_reach",
    "targeted_throws",
    "train_residual",
    "training_data",
    "unseen_ids",
]
