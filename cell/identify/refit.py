"""Refit the objects' η_o from observed throws, η_ee held fixed (stage 2 of Algorithm 1).

`cell run --learn` calls this between runs: the throws a store holds of a job's
objects move each object's effective mass and extents toward what its landings
showed, from where the parameter file puts them (`ModelParams.model_object`:
the identified η_o when the file names the object, else the mass rule's), with
the priors and bounds identification uses (`IdentifyOptions`: factors within
1 ± object_bound of the start, a Gaussian prior toward it, residuals weighed by the
documented landing noise). No cross-validated selection here: a job's few throws
of an object are too few to split. The end-effector's
η_ee is the file's: a few throws of a few objects cannot say more about the band
than the campaign the file was identified from, and holding it keeps an object's
refit from moving every other object's plan.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from cell.errors import InvalidInput, plural
from cell.identify.algorithm import IdentifyOptions, _stage2
from cell.identify.problem import ThrowData
from cell.log.table import REQUIRED_COLUMNS, ThrowTable
from cell.model.objects import ObjectParams
from cell.params import ModelParams

__all__ = ["ObjectRefit", "RefitReport", "concat_tables", "refit_objects", "table_objects"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ObjectRefit:
    """How one object's refit went.

    Attributes:
        object_id: the object.
        throws: usable throws of it in the table (stroke and landing logged).
        refitted: True when it had at least min_throws and its η_o was refitted;
            False: it keeps its start values (the after figures equal the before).
        rmse_before_m: landing RMSE of its throws with the start η_o [m].
        rmse_after_m: the same with the refitted η_o [m].
        mass_before_kg: the start effective mass [kg].
        mass_after_kg: the refitted effective mass [kg].
    """

    object_id: str
    throws: int
    refitted: bool
    rmse_before_m: float
    rmse_after_m: float
    mass_before_kg: float
    mass_after_kg: float

    def line(self) -> str:
        """One line for a person: throws, RMSE before -> after, effective mass."""
        if not self.refitted:
            return f"{self.object_id}: {plural(self.throws, 'throw')}, too few to refit; kept"
        return (
            f"{self.object_id}: {self.throws} throws, landing RMSE {self.rmse_before_m:.3f} m "
            f"-> {self.rmse_after_m:.3f} m, effective mass {self.mass_before_kg * 1000:.1f} g "
            f"-> {self.mass_after_kg * 1000:.1f} g"
        )


@dataclass(frozen=True)
class RefitReport:
    """What `refit_objects` did: one entry per object of the table, sorted by id."""

    objects: list[ObjectRefit]

    @property
    def refitted(self) -> list[ObjectRefit]:
        """The objects whose η_o was refitted."""
        return [o for o in self.objects if o.refitted]


def table_objects(table: ThrowTable) -> dict[str, ObjectParams]:
    """Each object id's η_o as its first row logs it (shape, mass, extents)."""
    out: dict[str, ObjectParams] = {}
    ids, shape, mass = table.text("object_id"), table.text("shape"), table.num("mass_kg")
    size = np.stack([table.num("size_x_m"), table.num("size_y_m"), table.num("size_z_m")], -1)
    for i, oid in enumerate(ids):
        if oid not in out:
            out[oid] = ObjectParams(
                shape=shape[i],  # type: ignore[arg-type]
                mass=float(mass[i]),
                size=tuple(float(s) for s in size[i]),  # type: ignore[arg-type]
                name=oid,
            )
    return out


def concat_tables(tables: list[ThrowTable], path: str = "") -> ThrowTable:
    """The rows of several tables with the same columns, in order, as one table.

    Raises:
        InvalidInput: the tables' columns differ.
    """
    if not tables:
        raise InvalidInput("concat_tables: no table given")
    cols = list(tables[0].columns)
    for t in tables[1:]:
        if list(t.columns) != cols:
            raise InvalidInput(f"{t.path or path}: its columns differ from {tables[0].path}")
    data: dict[str, object] = {}
    for c in cols:
        first = tables[0].data[c]
        if isinstance(first, np.ndarray):
            data[c] = np.concatenate([np.asarray(t.data[c], float) for t in tables])
        else:
            data[c] = [v for t in tables for v in t.data[c]]
    return ThrowTable(columns=cols, data=data, path=path or tables[0].path)


def _rmse(res: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(res**2, axis=1)))) if len(res) else math.nan


def refit_objects(
    table: ThrowTable,
    params: ModelParams,
    *,
    min_throws: int = 2,
    options: IdentifyOptions | None = None,
) -> tuple[ModelParams, RefitReport]:
    """Refit η_o of every object with at least `min_throws` throws in `table`.

    Each object starts from `params.model_object(obj)` (obj as its first row logs it):
    the file's identified η_o, else the mass rule's effective mass with its own extents
    (its own mass when the file has no rule). Stage 2 of identification
    (`cell.identify.algorithm._stage2`, the same Gaussian prior toward the start and
    the same bounds, 1 ± `options.object_bound`) is solved with `params.ee` fixed,
    again from its own result until no factor changes by more than `options.tol`
    (at most `options.max_iter` solves).

    Args:
        table: the throws (rows without stroke or landing are left out).
        params: the parameter file's η_ee, identified η_o and mass rule.
        min_throws: the fewest usable throws an object needs to be refitted; one with
            fewer keeps its values (and is not added to the result's objects).
        options: identification's options (priors, bounds, solver settings); their
            fit_objects is ignored (this is the object fit).

    Returns:
        `params` with the refitted objects added to (or replaced in) its objects, and a
        report per object of the table.

    Raises:
        InvalidInput: min_throws < 1, or no throw in the table has a stroke and a landing.
    """
    if min_throws < 1:
        raise InvalidInput(f"min_throws={min_throws}: give at least 1")
    opt = options or IdentifyOptions()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # optional: only a speed matter (see identify)
        return _refit(table, params, min_throws, opt)
    with threadpool_limits(limits=1, user_api="blas"):
        return _refit(table, params, min_throws, opt)


def _refit(
    table: ThrowTable, params: ModelParams, min_throws: int, opt: IdentifyOptions
) -> tuple[ModelParams, RefitReport]:
    stroke, landed = table.num("stroke_m"), table.landed
    usable = np.isfinite(stroke) & np.all(np.isfinite(landed), axis=1)
    if not usable.any():
        raise InvalidInput(
            f"{table.path or 'throw log'}: no throw has both stroke_m and landed_x_m/"
            "landed_y_m; a refit needs the stroke and the observed landing"
        )
    table = table.take(np.flatnonzero(usable))
    logged = table_objects(table)
    start = {oid: replace(params.model_object(o), name=oid) for oid, o in logged.items()}
    ids = table.text("object_id")
    counts = {oid: ids.count(oid) for oid in logged}
    fit_ids = sorted(oid for oid, n in counts.items() if n >= min_throws)
    report: list[ObjectRefit] = []
    objects = dict(params.objects)
    if fit_ids:
        keep = [i for i, oid in enumerate(ids) if oid in set(fit_ids)]
        data = ThrowData.from_table(table.take(keep), start)
        before = data.residual(data.batch, params.ee)
        _, k = data.factor_columns()
        factors = np.ones(k)
        for _ in range(opt.max_iter):
            # residuals weighed by the documented noise at the current fit (as identify)
            data.weigh(data.batch_with(data.objects_from_factors(factors)), params.ee, opt.noise)
            new = _stage2(data, params.ee, factors, opt)
            change = float(np.max(np.abs(new - factors)))
            factors = new
            if change < opt.tol:
                break
        fitted = data.objects_from_factors(factors)
        after = data.residual(data.batch_with(fitted), params.ee)
        for j, oid in enumerate(data.object_ids):
            rows = data.obj == j
            report.append(
                ObjectRefit(
                    object_id=oid,
                    throws=int(rows.sum()),
                    refitted=True,
                    rmse_before_m=_rmse(before[rows]),
                    rmse_after_m=_rmse(after[rows]),
                    mass_before_kg=float(start[oid].mass),
                    mass_after_kg=float(fitted[oid].mass),
                )
            )
            objects[oid] = fitted[oid]
            log.info("refit %s", report[-1].line())
    if len(fit_ids) < len(logged):
        rest = table.take([i for i, oid in enumerate(ids) if oid not in set(fit_ids)])
        data = ThrowData.from_table(rest, start)
        res = data.residual(data.batch, params.ee)
        for j, oid in enumerate(data.object_ids):
            rmse = _rmse(res[data.obj == j])
            m = float(start[oid].mass)
            report.append(ObjectRefit(oid, counts[oid], False, rmse, rmse, m, m))
    report.sort(key=lambda r: r.object_id)
    refitted = [r for r in report if r.refitted]
    note = params.note
    if refitted:
        note = (
            (note + "; " if note else "")
            + f"η_o of {plural(len(refitted), 'object')} refitted (stage 2, η_ee fixed) from "
            + f"{sum(r.throws for r in refitted)} throws of {table.path or 'a throw log'}: "
            + ", ".join(
                f"{r.object_id} RMSE {r.rmse_before_m:.3f} -> {r.rmse_after_m:.3f} m"
                for r in refitted
            )
        )
    return replace(params, objects=objects, note=note), RefitReport(report)


# The columns the model reads from a throw: a row with any of them not a finite number
# cannot be refitted on (a NaN release would make every residual NaN).
MODEL_COLUMNS = tuple(
    c
    for c in REQUIRED_COLUMNS
    if c not in ("throw_id", "object_id", "shape", "platform", "rotor_rpm")
)


@dataclass(frozen=True)
class StoreThrows:
    """The throws of a store a refit may use, and what was left out.

    Attributes:
        table: the usable rows (None when there are none).
        left_out: reason -> rows left out for it.
    """

    table: ThrowTable | None
    left_out: dict[str, int]


def sort_throws(store: object, objects: dict[str, ObjectParams]) -> StoreThrows:
    """A store's earlier sort throws of these objects, as one table.

    Kept: the rows of each object id of `objects` thrown by the arm in a sort run
    (`cell run`, the rows with a target_bin), of any earlier run or job. Left out,
    each for a reason:

    * other platforms' throws (drone, mobile): their release carries a base velocity
      and rotor wash the arm's parameter file is not about;
    * rows without a target_bin: campaign throws (`cell calibrate`, which the
      parameter file was identified from already) and `cell synth`'s draws of a
      synthetic world (not this scene);
    * rows logging another shape, mass or size than the job's object of that id: an
      ad-hoc item is named by its place in its job (item0_cube), so another job's
      item0_cube is another object;
    * rows with a model column (release, stroke, landing, ...) empty or not finite.

    Args:
        store: a `cell.log.store.ThrowStore` (anything with `table(object_id=...)`).
        objects: the job's objects by object id.
    """
    tables: list[ThrowTable] = []
    left: dict[str, int] = {}

    def drop(reason: str, n: int) -> None:
        if n:
            left[reason] = left.get(reason, 0) + n

    for oid, obj in sorted(objects.items()):
        t: ThrowTable = store.table(object_id=oid)  # type: ignore[attr-defined]
        if not len(t):
            continue
        arm = np.array([p == "arm" for p in t.text("platform")])
        drop("another platform", int((~arm).sum()))
        sort = (
            np.array([b != "" for b in t.text("target_bin")])
            if "target_bin" in t.columns
            else np.zeros(len(t), bool)
        )
        drop("not a sort throw (no target_bin)", int((arm & ~sort).sum()))
        keep = arm & sort
        finite = np.all(np.isfinite(np.column_stack([t.num(c) for c in MODEL_COLUMNS])), axis=1)
        drop("a model column empty or not finite", int((keep & ~finite).sum()))
        keep &= finite
        same = (
            np.array([s == obj.shape for s in t.text("shape")])
            & (t.num("mass_kg") == obj.mass)
            & np.all(
                np.column_stack([t.num(f"size_{a}_m") for a in "xyz"]) == np.asarray(obj.size),
                axis=1,
            )
        )
        drop("another object of the same id (shape, mass or size)", int((keep & ~same).sum()))
        keep &= same
        if keep.any():
            tables.append(t.take(np.flatnonzero(keep)))
    table = concat_tables(tables) if tables else None
    return StoreThrows(table, left)
