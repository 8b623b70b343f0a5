"""The conditions the gap concentrates in: held-out RMSE per level of each factor."""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem

__all__ = ["factor_levels", "conditions", "worst_conditions"]

MIN_LEVEL = 5  # throws a level needs to be reported


def _bins(x: np.ndarray, unit: str, fmt: str, k: int = 3) -> list[str]:
    """Labels of k quantile bins of x (NaN: 'none')."""
    ok = np.isfinite(x)
    if ok.sum() == 0 or np.ptp(x[ok]) == 0:
        v = f"{x[ok][0]:{fmt}} {unit}" if ok.any() else "none"
        return [v if o else "none" for o in ok]
    edges = np.unique(np.quantile(x[ok], np.linspace(0, 1, k + 1)))
    labels = []
    for v, o in zip(x, ok, strict=True):
        if not o:
            labels.append("none")
            continue
        j = int(np.clip(np.searchsorted(edges, v, side="right") - 1, 0, len(edges) - 2))
        labels.append(f"{edges[j]:{fmt}}–{edges[j + 1]:{fmt}} {unit}")
    return labels


def factor_levels(prob: GapProblem) -> dict[str, list[str]]:
    """Per factor, each throw's level (text)."""
    t = prob.table
    dist = np.hypot(prob.observed[:, 0] - t.num("x_m"), prob.observed[:, 1] - t.num("y_m"))
    out = {
        "object_id": t.text("object_id"),
        "shape": t.text("shape"),
        "mass_kg": _bins(t.num("mass_kg"), "kg", ".3f"),
        "stroke_m": _bins(t.num("stroke_m"), "m", ".3f"),
        "distance_m": _bins(dist, "m", ".2f"),
        "platform": t.text("platform"),
    }
    rpm = t.num("rotor_rpm")
    if np.any(rpm > 0):
        lv = _bins(np.where(rpm > 0, rpm, np.nan), "rpm", ".0f")
        out["rotor_rpm"] = ["0 rpm" if r <= 0 else lv[i] for i, r in enumerate(rpm)]
    return out


def conditions(
    prob: GapProblem, before_sq: np.ndarray, after_sq: np.ndarray | None = None
) -> list[dict[str, Any]]:
    """Held-out RMSE [m] per factor level (levels with ≥ MIN_LEVEL throws)."""
    rows = []
    for factor, levels in factor_levels(prob).items():
        arr = np.asarray(levels, dtype=object)
        uniq = list(dict.fromkeys(levels))
        if len(uniq) < 2:
            continue
        for lv in uniq:
            m = arr == lv
            if m.sum() < MIN_LEVEL:
                continue
            row = {
                "factor": factor,
                "level": lv,
                "throws": int(m.sum()),
                "heldout_rmse_m": float(np.sqrt(before_sq[m].mean())),
            }
            if after_sq is not None:
                row["after_rmse_m"] = float(np.sqrt(after_sq[m].mean()))
            rows.append(row)
    return rows


def worst_conditions(rows: list[dict[str, Any]], overall_m: float, k: int = 5) -> list[dict]:
    """The k levels with the largest held-out RMSE above the overall one (at most one
    level per factor first, so the list spans factors)."""
    above = [r for r in rows if r["heldout_rmse_m"] > 1.05 * overall_m]
    above.sort(key=lambda r: -r["heldout_rmse_m"])
    out: list[dict] = []
    seen: set[str] = set()
    for r in above:
        if r["factor"] not in seen:
            out.append(r)
            seen.add(r["factor"])
    for r in above:
        if len(out) >= k:
            break
        if r not in out:
            out.append(r)
    return sorted(out[:k], key=lambda r: -r["heldout_rmse_m"])
