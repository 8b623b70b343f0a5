"""The diagnosis problem: observed throws, the configured model, and the held-out folds.

A `GapProblem` predicts the landing points of any subset of the throws with
the configured model plus a set of effects, and holds the two held-out
schemes the diagnosis scores on: leave-objects-out folds and random folds.
Errors are 2-D landing misses [m] on each throw's landing plane.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np

from cell.errors import InvalidInput, plural
from cell.log.table import ThrowTable
from cell.model.effects import Effect, TrackingScale
from cell.model.effects_apply import flight_accel, predict_with_effects
from cell.model.flight3d import acceleration
from cell.model.params import EndEffectorParams
from cell.model.throw import Landing, ThrowBatch, drag_constant
from cell.params import Validation

__all__ = ["GapProblem", "BandStiffness", "build_problem", "rmse"]

log = logging.getLogger(__name__)

MISS_PENALTY_M = 3.0  # [m] residual used for a prediction that never lands
FOLDS = 5


@dataclass(frozen=True)
class BandStiffness(Effect):
    """The nominal band law re-identified (`--identify`): Ke3, Ke2, Ke1 and C scaled by one
    factor. Not an effect of the vocabulary: it is the configured model refitted."""

    name: ClassVar[str] = "band_stiffness"
    phase: ClassVar[str] = "launch"
    bounds: ClassVar[tuple[tuple[float, float], ...]] = ((0.3, 3.0),)
    scale: ClassVar[tuple[float, ...]] = (0.02,)
    factor: float = 1.0  # [-]

    def apply(self, ee: EndEffectorParams) -> EndEffectorParams:
        """The end-effector with its band law scaled."""
        f = self.factor
        return replace(ee, Ke3=ee.Ke3 * f, Ke2=ee.Ke2 * f, Ke1=ee.Ke1 * f, C=ee.C * f)


def rmse(residual: np.ndarray) -> float:
    """Root mean square of 2-D misses [m]; residual shape (n, 2)."""
    r = np.asarray(residual, float)
    if r.size == 0:
        return float("nan")
    return float(np.sqrt(np.mean(np.sum(r * r, axis=-1))))


@dataclass
class GapProblem:
    """Observed throws and the configured model.

    Attributes:
        table: the throw log (only the rows diagnosed).
        batch: the throws as a model batch (rows without stroke carry a placeholder
            stroke; their launch comes from `launch`).
        ee: end-effector parameters of the configured model.
        base_effects: effects the configured model already has (parameter file).
        observed: logged landing points [m, W], shape (n, 2).
        rotor_rpm: rotor speed per throw [rpm], shape (n,).
        launch: observed launch states from tracks (position, velocity, time, bias
            coefficients c0 of `cell.gap.tracks.TrackFit`), or None.
        has_stroke: True for throws of this end-effector (stroke logged), shape (n,).
        groups: object index per throw, shape (n,).
        step: 3-D integrator step [s].
        seed: seed of every random choice (folds, permutations, bootstrap).
        validated_m: per throw, the configured model's held-out misfit for its object
            [m] (the parameter file's validation section; NaN for an object it does not
            list), or None without one: the part of the noise floor repeats cannot see.
    """

    table: ThrowTable
    batch: ThrowBatch
    ee: EndEffectorParams
    base_effects: tuple[Effect, ...]
    observed: np.ndarray
    rotor_rpm: np.ndarray
    launch: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None
    has_stroke: np.ndarray
    groups: np.ndarray
    step: float = 0.02
    seed: int = 0
    folds: dict[str, list[tuple[np.ndarray, np.ndarray]]] = field(default_factory=dict)
    validated_m: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.observed.shape[0])

    def landing(
        self,
        idx: np.ndarray,
        effects: list[Effect] | tuple[Effect, ...] = (),
        *,
        permute: bool = False,
        ee: EndEffectorParams | None = None,
    ) -> Landing:
        """Predicted landings of throws idx (observed scale)."""
        idx = np.asarray(idx)
        sub = self.batch.take(idx)
        ee_used = ee or self.ee
        rest = []
        for e in effects:
            if isinstance(e, BandStiffness):
                ee_used = e.apply(ee_used)
            else:
                rest.append(e)
        all_eff = list(self.base_effects) + rest
        launch = None
        if self.launch is not None:
            launch = self._launch(idx, sub, all_eff)
        perm = None
        if permute:
            perm = np.random.default_rng(self.seed + 7919 * len(idx)).permutation(len(idx))
        land = predict_with_effects(
            sub,
            ee_used,
            all_eff,
            rotor_rpm=self.rotor_rpm[idx],
            launch=launch,
            permutation=perm,
            step=self.step,
        )
        return land

    def _launch(
        self, idx: np.ndarray, sub: ThrowBatch, effects: list[Effect]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Observed launch states of throws idx, corrected for the acceleration the
        effects add over the first samples (the track fit assumed the nominal one)."""
        assert self.launch is not None
        p, v, t, c = (a[idx] for a in self.launch)
        given = np.isfinite(t)
        if not given.any() or not effects:
            return p, v, t
        s = next((e.scale_factor for e in effects if isinstance(e, TrackingScale)), 1.0)
        g = np.flatnonzero(given)
        part = sub.take(g)
        k = drag_constant(part.shape, part.mass, part.size)
        acc = flight_accel(part, effects, self.rotor_rpm[idx][g])
        a_true = acceleration(p[g] / s, v[g] / s, k, acc) * s
        a_nom = acceleration(p[g], v[g], k, None)
        da = a_true - a_nom
        p, v = p.copy(), v.copy()
        p[g] -= c[g, :1] * da
        v[g] -= c[g, 1:] * da
        return p, v, t

    def residual(
        self,
        idx: np.ndarray,
        effects: list[Effect] | tuple[Effect, ...] = (),
        *,
        permute: bool = False,
        ee: EndEffectorParams | None = None,
    ) -> np.ndarray:
        """Observed minus predicted landing [m], shape (m, 2); a miss counts MISS_PENALTY_M."""
        r = self.observed[idx] - self.landing(idx, effects, permute=permute, ee=ee).xy
        return np.where(np.isfinite(r), r, MISS_PENALTY_M)

    def subset(self, mask: np.ndarray) -> GapProblem:
        """The problem restricted to some throws (folds are rebuilt)."""
        idx = np.flatnonzero(mask)
        launch = None
        if self.launch is not None:
            p0, v0, t0, c0 = self.launch
            launch = (p0[idx], v0[idx], t0[idx], c0[idx])
        out = replace(
            self,
            table=self.table.take(idx),
            batch=self.batch.take(idx),
            observed=self.observed[idx],
            rotor_rpm=self.rotor_rpm[idx],
            launch=launch,
            has_stroke=self.has_stroke[idx],
            groups=self.groups[idx],
            folds={},
            validated_m=None if self.validated_m is None else self.validated_m[idx],
        )
        out.make_folds()
        return out

    def make_folds(self) -> None:
        """Leave-objects-out folds (when there are ≥ 3 objects) and random folds."""
        n = len(self)
        rng = np.random.default_rng(self.seed)
        folds: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
        objs = np.unique(self.groups)
        if objs.size >= 3:
            k = min(FOLDS, objs.size)
            order = rng.permutation(objs)
            obj_fold = {o: i % k for i, o in enumerate(order)}
            fid = np.array([obj_fold[g] for g in self.groups])
            folds["object"] = [
                (np.flatnonzero(fid != i), np.flatnonzero(fid == i)) for i in range(k)
            ]
        fid = rng.permutation(n) % FOLDS
        folds["random"] = [
            (np.flatnonzero(fid != i), np.flatnonzero(fid == i)) for i in range(FOLDS)
        ]
        self.folds = folds


def build_problem(
    table: ThrowTable,
    ee: EndEffectorParams,
    *,
    base_effects: tuple[Effect, ...] = (),
    objects: dict | None = None,
    launch: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
    seed: int = 0,
    step: float = 0.02,
    validation: Validation | None = None,
) -> GapProblem:
    """The problem of a throw log.

    Throws without a stroke (another launcher) are kept only when `launch` gives
    their observed launch state (from tracks); throws without a logged landing
    are dropped. `validation` (the parameter file's) gives each throw its object's
    held-out misfit (`GapProblem.validated_m`).

    Raises:
        InvalidInput: no throw left to diagnose.
    """
    n = len(table)
    stroke = table.num("stroke_m")
    has_stroke = np.isfinite(stroke)
    landed = np.all(np.isfinite(table.landed), axis=1)
    usable = landed.copy()
    if launch is not None:
        given = np.isfinite(launch[2])
        usable &= has_stroke | given
    else:
        usable &= has_stroke
    dropped = int(n - usable.sum())
    if dropped:
        no_land = int((~landed).sum())
        no_launch = int((landed & ~usable).sum())  # no stroke, and no launch from a track
        why = [f"{no_land} with no landing logged"] if no_land else []
        if no_launch:
            why.append(
                f"{no_launch} with no stroke (another launcher's) and "
                + (
                    "no usable track (the report's tracks.unusable says why)"
                    if launch is not None
                    else "no track given (--tracks)"
                )
            )
        log.warning("%s dropped: %s", plural(dropped, "throw"), "; ".join(why))
    if usable.sum() < 10:
        raise InvalidInput(
            f"{table.path or 'throw log'}: only {plural(int(usable.sum()), 'throw')} can be diagnosed "
            "(need ≥ 10 with a logged landing and either a stroke or a track)"
        )
    idx = np.flatnonzero(usable)
    tab = table.take(idx)
    filled = np.where(np.isfinite(tab.num("stroke_m")), tab.num("stroke_m"), ee.stroke_min)
    batch = tab.with_columns({"stroke_m": filled}).to_batch(objects=objects)
    oid = tab.text("object_id")
    names = {o: i for i, o in enumerate(dict.fromkeys(oid))}
    lau = None
    if launch is not None:
        p0, v0, t0, c0 = (a[idx] for a in launch)
        lau = (p0, v0, np.where(np.isfinite(tab.num("stroke_m")), np.nan, t0), c0)
    prob = GapProblem(
        table=tab,
        batch=batch,
        ee=ee,
        base_effects=tuple(base_effects),
        observed=tab.landed,
        rotor_rpm=tab.num("rotor_rpm"),
        launch=lau,
        has_stroke=np.isfinite(tab.num("stroke_m")),
        groups=np.array([names[o] for o in oid]),
        step=step,
        seed=seed,
        validated_m=None if validation is None else np.array(validation.misfit_m(oid), float),
    )
    prob.make_folds()
    return prob
