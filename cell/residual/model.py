"""The trained residual: a tuned pipeline with what it needs to be used later
(feature names, learner, training objects, the model parameters it was
trained against, the scikit-learn version), saved and loaded with skops (no pickle).

The planner commands L_s + ΔL_s (thesis Fig. 5.1): `apply_residual` gives the
corrected stroke, clipped to the end-effector's range with a flag and a warning
when it had to clip.
"""

from __future__ import annotations

import json
import logging
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput, InvalidParameter
from cell.infile import check_input_file
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import Landing, ThrowBatch
from cell.outfile import write_whole
from cell.residual.features import FEATURE_NAMES, GripPose, feature_matrix, table_features
from cell.residual.learners import fit_learner
from cell.residual.target import ResidualTargets, residual_targets

__all__ = [
    "FORMAT",
    "ResidualModel",
    "CorrectedStroke",
    "TrainingData",
    "training_data",
    "train_residual",
    "apply_residual",
    "residual_for_plan",
    "physics_only",
]

log = logging.getLogger(__name__)

FORMAT = "cell-residual/2"  # skops container: {format, meta (JSON), pipeline}
MAX_MODEL_BYTES = 64 * 1024 * 1024  # [B] a random forest of the full grid is ~5 MB
# [B] what its members may unpack to: skops reads each whole into memory
MAX_MODEL_UNPACKED_BYTES = 4 * MAX_MODEL_BYTES
# Types outside scikit-learn's own estimators that the project's learners are built of; skops
# trusts sklearn's estimators by default and lists anything else for the loader to judge.
TRUSTED_TYPES = (
    "cell.residual.learners.RangeClip",
    "sklearn.neural_network._stochastic_optimizers.AdamOptimizer",
    "sklearn.neural_network._stochastic_optimizers.SGDOptimizer",
    "sklearn.tree._tree.Tree",
)


@dataclass(frozen=True)
class ResidualModel:
    """A fitted residual ΔL_s model.

    Attributes:
        learner: "svr", "rf" or "mlp".
        pipeline: the fitted scikit-learn pipeline (features -> ΔL_s [mm]).
        feature_names: the feature order the pipeline expects.
        training_objects: object ids it was trained on.
        ee: the (identified) end-effector parameters the targets were computed with.
        sklearn_version: scikit-learn version it was fitted with.
        best_params: hyper-parameters chosen by inner CV.
        n_train: throws trained on.
        n_excluded: throws excluded (observed reach outside the model's range).
        identified_objects: object ids whose identified η_o (not the logged ones) the
            targets were computed with; a planner adding this residual should plan
            those objects with the same η_o, and every other object with its logged
            (CAD) η_o.
        heldout: how the learner did against the physics model alone on the round-robin's
            held-out throws, and what was saved for it (`cell learn`; empty: not judged).
    """

    learner: str
    pipeline: Any
    feature_names: tuple[str, ...]
    training_objects: tuple[str, ...]
    ee: EndEffectorParams
    sklearn_version: str
    best_params: dict[str, Any] = field(default_factory=dict)
    n_train: int = 0
    n_excluded: int = 0
    identified_objects: tuple[str, ...] = ()
    heldout: dict[str, Any] = field(default_factory=dict)

    def predict_features(self, x: np.ndarray) -> np.ndarray:
        """ΔL_s [m] for feature rows in FEATURE_NAMES order, shape (n,)."""
        x = np.atleast_2d(np.asarray(x, float))
        if x.shape[1] != len(self.feature_names):
            raise InvalidInput(
                f"feature rows have {x.shape[1]} columns; this model expects "
                f"{len(self.feature_names)} ({', '.join(self.feature_names)})"
            )
        return np.asarray(self.pipeline.predict(x), float) / 1000.0

    def delta_strokes(self, objects: list[ObjectParams], poses: list[GripPose]) -> np.ndarray:
        """ΔL_s [m] for objects held in grip poses (the pose carries the model's stroke)."""
        return self.predict_features(feature_matrix(objects, poses, self.ee))

    def delta_stroke(
        self,
        obj: ObjectParams,
        stroke_m: float,
        *,
        elevation_rad: float = 0.0,
        grip_yaw_rad: float = 0.0,
    ) -> float:
        """ΔL_s [m] for one object at the model's planned stroke `stroke_m` [m]."""
        return float(
            self.delta_strokes([obj], [GripPose(stroke_m, elevation_rad, grip_yaw_rad)])[0]
        )

    def save(self, path: str | Path) -> None:
        """Write the model in skops' format (no pickle: loading it runs no code), atomically."""
        import skops.io as sio

        meta = {
            "learner": self.learner,
            "feature_names": list(self.feature_names),
            "training_objects": list(self.training_objects),
            "ee": self.ee.as_dict(),
            "sklearn_version": self.sklearn_version,
            "best_params": {k: _plain(v) for k, v in self.best_params.items()},
            "n_train": self.n_train,
            "n_excluded": self.n_excluded,
            "identified_objects": list(self.identified_objects),
            "heldout": self.heldout,
        }
        doc = {"format": FORMAT, "meta": json.dumps(meta), "pipeline": self.pipeline}
        write_whole(path, lambda p: sio.dump(doc, p))

    @classmethod
    def load(cls, path: str | Path) -> ResidualModel:
        """Read a model written by `save`, trusting only the types its learners are made of.

        The file is untrusted: it is never unpickled. skops lists every type the file would
        build; a file naming any type outside TRUSTED_TYPES (or scikit-learn's own estimators,
        which skops trusts) is refused before anything is built.

        Raises:
            InvalidInput: no such file, too large, not a residual model file, an untrusted
                type in it, or made with another feature set.
        """
        import sklearn
        import skops.io as sio

        p = check_input_file(path, "residual model file", MAX_MODEL_BYTES)
        not_ours = f"{p}: not a residual model file (expected one written by `cell learn`"
        _check_unpacked_size(p)
        try:
            untrusted = set(sio.get_untrusted_types(file=p))
        except Exception as exc:  # a pickle, a zip of something else, garbage: never loaded
            raise InvalidInput(f"{not_ours}, format {FORMAT}; {type(exc).__name__})") from None
        foreign = sorted(untrusted - set(TRUSTED_TYPES))
        if foreign:
            raise InvalidInput(
                f"{p}: refused: it would build types this cell does not trust ({', '.join(foreign)}); "
                f"trusted are scikit-learn's estimators and {', '.join(TRUSTED_TYPES)}"
            )
        try:
            doc = sio.load(p, trusted=sorted(untrusted))
            meta = json.loads(doc["meta"])
            fmt = doc["format"]
            pipeline = doc["pipeline"]
        except Exception as exc:
            raise InvalidInput(f"{not_ours}; {type(exc).__name__}: {exc})") from None
        if fmt != FORMAT:
            raise InvalidInput(f"{p}: residual model format {fmt!r}; this cell reads {FORMAT}")
        try:
            model = cls(
                learner=str(meta["learner"]),
                pipeline=pipeline,
                feature_names=tuple(meta["feature_names"]),
                training_objects=tuple(meta["training_objects"]),
                ee=EndEffectorParams.from_dict(meta["ee"], where=f"{p}: ee"),
                sklearn_version=str(meta["sklearn_version"]),
                best_params=dict(meta["best_params"]),
                n_train=int(meta["n_train"]),
                n_excluded=int(meta["n_excluded"]),
                identified_objects=tuple(meta["identified_objects"]),
                heldout=dict(meta.get("heldout", {})),  # files of before the judgement: none
            )
        except (KeyError, TypeError, ValueError, OverflowError) as exc:
            raise InvalidInput(
                f"{p}: residual model metadata is missing or not valid ({exc}); retrain it "
                "with `cell learn`"
            ) from None
        for key in ("n_train", "n_excluded"):
            v = meta[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise InvalidInput(
                    f"{p}: residual model metadata {key}: {v!r} must be a whole number ≥ 0; "
                    "retrain it with `cell learn`"
                )
        if model.feature_names != FEATURE_NAMES:
            raise InvalidInput(
                f"{p}: made with another feature set ({len(model.feature_names)} features); "
                "retrain it with `cell learn`"
            )
        if model.sklearn_version != sklearn.__version__:
            log.warning(
                "%s was fitted with scikit-learn %s; this is %s",
                p,
                model.sklearn_version,
                sklearn.__version__,
            )
        return model


def _check_unpacked_size(p: Path) -> None:
    """Refuse a model file whose members unpack to more than `MAX_MODEL_UNPACKED_BYTES`
    (a zip bomb: a small file that would fill the memory when skops reads it), by the
    sizes its zip directory declares (Python's zip reader stops at those and refuses a
    member that runs longer). Not a zip: left to skops' own refusal."""
    try:
        with zipfile.ZipFile(p) as z:
            unpacked = sum(info.file_size for info in z.infolist())
    except (zipfile.BadZipFile, OSError, ValueError):
        return
    if unpacked > MAX_MODEL_UNPACKED_BYTES:
        raise InvalidInput(
            f"{p}: unpacks to {unpacked:,} bytes, over the {MAX_MODEL_UNPACKED_BYTES:,} a "
            "residual model file may (a compressed bomb, or not a file `cell learn` wrote)"
        )


def physics_only(model: ResidualModel, heldout: dict[str, Any]) -> ResidualModel:
    """`model` with its residual replaced by none (ΔL_s = 0 for every throw: the planner
    commands the model's own stroke), the learner's name, training record and hyper-
    parameters kept as the record of what was judged, and why in `heldout`."""
    from sklearn.dummy import DummyRegressor
    from sklearn.pipeline import Pipeline

    zero = DummyRegressor(strategy="constant", constant=0.0)
    pipe = Pipeline([("reg", zero)]).fit(np.zeros((1, len(model.feature_names))), [0.0])
    return replace(model, pipeline=pipe, heldout=heldout)


def _plain(v: Any) -> Any:
    """A hyper-parameter value as JSON can hold it (numpy scalars to Python numbers)."""
    return v.item() if isinstance(v, np.generic) else v


@dataclass(frozen=True)
class CorrectedStroke:
    """The stroke to command.

    Attributes:
        stroke_m: L_s + ΔL_s, within the stroke range [m].
        model_stroke_m: the model's L_s [m].
        delta_m: ΔL_s [m] as predicted (before any clipping).
        clipped: True when L_s + ΔL_s left the range and was clipped.
    """

    stroke_m: float
    model_stroke_m: float
    delta_m: float
    clipped: bool


def apply_residual(
    model: ResidualModel,
    obj: ObjectParams,
    stroke_m: float,
    *,
    elevation_rad: float = 0.0,
    grip_yaw_rad: float = 0.0,
    ee: EndEffectorParams | None = None,
) -> CorrectedStroke:
    """The stroke to command for a plan: L_s + ΔL_s, clipped to the stroke range.

    Clipping is never silent: the result says so and a warning is logged.

    Args:
        model: the residual.
        obj: the object thrown.
        stroke_m: the planner's stroke L_s [m].
        elevation_rad: the plan's throw-axis elevation [rad].
        grip_yaw_rad: the object's rotation about the throw axis in the grip [rad].
        ee: the end-effector whose range to clip to (the model's when None).
    """
    rng = ee or model.ee
    delta = model.delta_stroke(
        obj, stroke_m, elevation_rad=elevation_rad, grip_yaw_rad=grip_yaw_rad
    )
    raw = stroke_m + delta
    stroke = float(np.clip(raw, rng.stroke_min, rng.stroke_max))
    clipped = stroke != raw
    if clipped:
        log.warning(
            "L_s + ΔL_s = %.4f + %.4f m is outside the stroke range %.3f … %.3f m; "
            "clipped to %.4f m (the throw will miss)",
            stroke_m,
            delta,
            rng.stroke_min,
            rng.stroke_max,
            stroke,
        )
    return CorrectedStroke(stroke_m=stroke, model_stroke_m=stroke_m, delta_m=delta, clipped=clipped)


def residual_for_plan(
    model: ResidualModel, obj: ObjectParams, plan: Any, *, grip_yaw_rad: float = 0.0
) -> CorrectedStroke:
    """`apply_residual` for a throw plan (anything with `stroke_m` [m] and
    `elevation_rad` [rad], e.g. `cell.optimize.ThrowPlan`): command
    `result.stroke_m` instead of `plan.stroke_m`."""
    return apply_residual(
        model,
        obj,
        float(plan.stroke_m),
        elevation_rad=float(plan.elevation_rad),
        grip_yaw_rad=grip_yaw_rad,
    )


@dataclass(frozen=True)
class TrainingData:
    """A throw log turned into learning data.

    Attributes:
        table: the log.
        batch: its throws for the model (identified η_o applied).
        targets: ΔL_s and the model's strokes.
        features: feature rows, shape (n, k); NaN rows where not usable.
        groups: object id per throw.
        usable: throws to learn from (observed landing within the model's range).
        ee: the end-effector parameters of the model the targets come from.
        identified_objects: ids of the logged objects whose η_o were overridden.
    """

    table: ThrowTable
    batch: ThrowBatch
    targets: ResidualTargets
    features: np.ndarray
    groups: np.ndarray
    usable: np.ndarray
    ee: EndEffectorParams
    identified_objects: tuple[str, ...] = ()


def training_data(
    table: ThrowTable,
    ee: EndEffectorParams,
    *,
    objects: dict[str, ObjectParams] | None = None,
    predict: Callable[[ThrowBatch], Landing] | None = None,
) -> TrainingData:
    """ΔL_s targets and features of a throw log.

    Throws without an observed landing, or whose observed reach the model cannot
    produce, are marked unusable (and counted in a warning by `residual_targets`).

    Args:
        table: the log.
        ee: the (identified) end-effector parameters.
        objects: identified η_o by object id.
        predict: the model, batch -> Landing (default: nominal with `ee`).
    """
    batch = table.to_batch(objects=objects)
    targets = residual_targets(batch, table.landed, ee, predict=predict)
    usable = targets.usable
    stroke_feat = np.where(usable, targets.model_stroke, batch.stroke)
    feats = table_features(table, stroke_feat, ee)
    feats[~usable] = np.nan
    return TrainingData(
        table=table,
        batch=batch,
        targets=targets,
        features=feats,
        groups=np.asarray(table.text("object_id")),
        usable=usable,
        ee=ee,
        identified_objects=tuple(sorted(set(table.text("object_id")) & set(objects or {}))),
    )


def train_residual(
    data: TrainingData,
    *,
    learner: str = "svr",
    grid: str = "full",
    rows: np.ndarray | None = None,
    seed: int = 0,
) -> ResidualModel:
    """Tune and fit a residual on the usable throws (of `rows`, when given).

    Args:
        data: from `training_data`.
        learner: "svr", "rf" or "mlp".
        grid: hyper-parameter grid, "small", "medium" or "full" (`GRIDS`).
        rows: a boolean mask of the throws it may train on (e.g. without held-out objects).
        seed: random state.

    Raises:
        InvalidParameter: no usable throws of at least 2 objects.
    """
    import sklearn

    mask = data.usable.copy()
    if rows is not None:
        mask &= np.asarray(rows, bool)
    if not mask.any():
        raise InvalidParameter("no usable throws to train the residual on")
    fitted = fit_learner(
        learner,
        data.features[mask],
        data.targets.delta_stroke[mask],
        data.groups[mask],
        grid=grid,
        seed=seed,
    )
    return ResidualModel(
        learner=learner,
        pipeline=fitted.pipeline,
        feature_names=FEATURE_NAMES,
        training_objects=tuple(sorted(set(data.groups[mask].tolist()))),
        ee=data.ee,
        sklearn_version=sklearn.__version__,
        best_params=fitted.best_params,
        n_train=int(mask.sum()),
        n_excluded=int(np.sum(~data.usable & (True if rows is None else np.asarray(rows, bool)))),
        identified_objects=data.identified_objects,
    )
