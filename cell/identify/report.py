"""Held-out splits and the prediction errors identification reports.

Reach, as in the thesis (§4.1.1), is the component of the landing point along
the axis straight ahead: here the throw's own horizontal direction (its azimuth)
from the release point. The reach error of a prediction is the difference of
predicted and observed reach; the landing error is the distance between the
predicted and observed landing points on the plane.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from cell.errors import InvalidInput
from cell.log.table import ThrowTable
from cell.model.throw import predict_landing
from cell.params import ModelParams

if TYPE_CHECKING:
    from cell.identify.algorithm import IdentifyResult

__all__ = [
    "ObjectErrors",
    "heldout_split",
    "predicted_landing",
    "reach",
    "errors_by_object",
    "format_table",
    "evidence_json",
    "evidence_lines",
]


def heldout_split(
    table: ThrowTable, fraction: float = 0.2, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Indices (fit, held_out), stratified by object: each object with at least two
    throws keeps round(fraction · n) of them (at least one) out of the fit.

    Raises:
        InvalidInput: fraction outside [0, 0.9].
    """
    if not 0 <= fraction <= 0.9:
        raise InvalidInput(f"held-out fraction {fraction} must be in [0, 0.9]")
    rng = np.random.default_rng(seed)
    ids = np.array(table.text("object_id"))
    held = np.zeros(len(table), dtype=bool)
    if fraction > 0:
        for oid in sorted(set(ids)):
            rows = np.flatnonzero(ids == oid)
            if rows.size < 2:
                continue
            k = min(rows.size - 1, max(1, round(fraction * rows.size)))
            held[rng.choice(rows, size=k, replace=False)] = True
    return np.flatnonzero(~held), np.flatnonzero(held)


def predicted_landing(table: ThrowTable, params: ModelParams) -> np.ndarray:
    """Landing points [m, W] the nominal model with these parameters predicts, shape (n, 2).

    NaN where a throw has no stroke or the model says it never lands.
    """
    stroke = table.num("stroke_m")
    out = np.full((len(table), 2), np.nan)
    ok = np.flatnonzero(np.isfinite(stroke))
    if ok.size:
        sub = table.take(ok)
        land = predict_landing(
            sub.to_batch(objects=params.objects), params.ee, strict=False, check_stroke=False
        )
        out[ok] = land.xy
    return out


def reach(table: ThrowTable, xy: np.ndarray) -> np.ndarray:
    """Reach [m] of landing points: along the throw's azimuth from its release point."""
    a = table.num("azimuth_rad")
    dx = xy[:, 0] - table.num("x_m")
    dy = xy[:, 1] - table.num("y_m")
    return dx * np.cos(a) + dy * np.sin(a)


@dataclass(frozen=True)
class ObjectErrors:
    """Prediction errors of one object's throws (or of all: object_id "all").

    Attributes:
        object_id: the object.
        n: throws evaluated.
        reach_rmse_m: RMSE of the predicted reach [m].
        landing_rmse_m: RMSE of the predicted landing point (distance) [m].
    """

    object_id: str
    n: int
    reach_rmse_m: float
    landing_rmse_m: float


def errors_by_object(table: ThrowTable, predicted_xy: np.ndarray) -> list[ObjectErrors]:
    """Per-object (sorted by id) and overall ("all", last) errors of predictions."""
    obs = table.landed
    ok = np.all(np.isfinite(obs), axis=1) & np.all(np.isfinite(predicted_xy), axis=1)
    d_reach = reach(table, predicted_xy) - reach(table, obs)
    d2 = np.sum((predicted_xy - obs) ** 2, axis=1)
    ids = np.array(table.text("object_id"))
    out = []
    for oid in [*sorted(set(ids)), "all"]:
        m = ok & ((ids == oid) if oid != "all" else True)
        if not m.any():
            out.append(ObjectErrors(oid, 0, float("nan"), float("nan")))
            continue
        out.append(
            ObjectErrors(
                object_id=oid,
                n=int(m.sum()),
                reach_rmse_m=float(np.sqrt(np.mean(d_reach[m] ** 2))),
                landing_rmse_m=float(np.sqrt(np.mean(d2[m]))),
            )
        )
    return out


def format_table(
    before: list[ObjectErrors],
    after: list[ObjectErrors],
    params: ModelParams,
    n_fit: dict[str, int],
) -> str:
    """The per-object table: throws fitted and evaluated, RMSE before/after, and η_o."""
    head = (
        f"{'object':12s} {'fit':>4s} {'eval':>4s}  {'reach RMSE [m]':>17s}  "
        f"{'landing RMSE [m]':>17s}  {'mass [kg]':>9s}  size x, y, z [m]"
    )
    lines = [
        head,
        f"{'':12s} {'':>4s} {'':>4s}  {'before':>8s} {'after':>8s}  {'before':>8s} {'after':>8s}",
        "-" * len(head),
    ]
    for b, a in zip(before, after, strict=True):
        o = params.objects.get(b.object_id)
        extra = (
            f"  {o.mass:9.4f}  {o.size[0]:.4f}, {o.size[1]:.4f}, {o.size[2]:.4f}"
            if o is not None
            else ""
        )
        lines.append(
            f"{b.object_id:12s} {n_fit.get(b.object_id, sum(n_fit.values()) if b.object_id == 'all' else 0):4d} "
            f"{b.n:4d}  {b.reach_rmse_m:8.4f} {a.reach_rmse_m:8.4f}  "
            f"{b.landing_rmse_m:8.4f} {a.landing_rmse_m:8.4f}{extra}"
        )
    return "\n".join(lines)


def evidence_lines(result: IdentifyResult, most: int = 12) -> list[str]:
    """Per object which factors were kept and why (with their 95 % intervals), and the
    parameter combinations involving η_ee the landings determine or not."""
    from cell.identify.problem import EE_NAMES

    lines = []
    if result.objects:
        lines.append("objects (cross-validated prior width of the factors; 0 = catalogue kept):")
        for c in result.objects:
            facs = ", ".join(
                f"{k.split('.', 1)[1]} {v:.3f}±{h:.3f}"
                for k, (v, h) in result.intervals.items()
                if k.startswith(c.object_id + ".")
            )
            lines.append(f"  {c.object_id:12s} {c.reason()}; factors {facs}")
    held = [d for d in result.directions if not d.determined]
    lines.append(
        f"parameter combinations: {result.n_params} of {len(result.directions)} determined "
        f"by the landings; {len(held)} held at the prior"
    )
    ee = set(EE_NAMES)
    shown = [d for d in result.directions if any(n in ee for n, _ in d.components)]
    lines += [f"  {d.text()}" for d in shown[:most]]
    if len(shown) > most:
        lines.append(f"  ... {len(shown) - most} more with the end effector (--json lists all)")
    return lines


def evidence_json(result: IdentifyResult) -> dict[str, Any]:
    """The same for JSON: object choices, combinations, 95 % intervals, -2 log L."""
    return {
        "chi2_fit": result.chi2_fit,
        "determined_combinations": result.n_params,
        "object_choice": {c.object_id: c.as_dict() for c in result.objects},
        "directions": [d.as_dict() for d in result.directions],
        "intervals_95": {
            k: {"value": v, "half_width": h} for k, (v, h) in result.intervals.items()
        },
    }
