"""A recording of `cell gap`: residuals before and after the verdict, tracks against the model.

Entities (world frame W, z up, metres), with one step of the `throw` timeline
per throw of the log (its row among the throws diagnosed):

- `world/landings/observed`, `.../model_before`, `.../model_after` (static): every
  logged landing and what the configured model, then the model with the
  verdict's effects, predict for it (at the throw's landing-plane height);
- `world/residuals/before`, `.../after` (static): a segment from each prediction to
  the observed landing;
- `world/throw/observed`, `.../model_before`, `.../model_after`: the throw at the
  cursor, and `world/throw/track` beside `world/throw/model_flight` (the configured
  model's flight of that throw) when tracks are given;
- `gap/before_m`, `gap/after_m`: |residual| of each throw [m] (horizontal);
- `verdict`: the report's verdict, held-out RMSE and shrink (Markdown).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import CellError
from cell.record.compare import BEFORE, OBS, THROW, layout, record_landings
from cell.record.flight import predicted_flight
from cell.record.stream import Recording

__all__ = ["record_gap"]

log = logging.getLogger(__name__)


def record_gap(
    path: str | Path, d: Any, prob: Any, tracks: dict[str, np.ndarray] | None = None
) -> Path:
    """Write the recording of a diagnosis (`cell.gap.run.diagnose_log`'s result).

    Args:
        path: the `.rrd` file.
        d: the Diagnosis (report, baseline_residual, verdict_residual).
        prob: the GapProblem it was made on (table, batch, ee, observed).
        tracks: observed tracks {throw_id: (k, 4) t [s], x, y, z [m]} or None.

    Returns:
        The file written.
    """
    obs = np.asarray(prob.observed, float)
    z = np.asarray(prob.batch.land_z, float)
    before = obs - np.asarray(d.baseline_residual, float)
    after = obs - np.asarray(d.verdict_residual, float)
    ids = prob.table.text("throw_id")
    with Recording(path, "cell_gap") as r:
        o3, b3, a3 = (np.column_stack([xy, z]) for xy in (obs, before, after))
        r.stream.send_blueprint(layout("gap", ("before", "after"), "verdict"))
        record_landings(r, o3, b3, a3, ids, scalars="gap")
        r.document("verdict", _verdict_markdown(d.report))
        for k in range(len(obs)):
            tr = None if tracks is None else tracks.get(str(ids[k]))
            if tr is not None:  # lost samples (NaN) are not drawn
                tr = np.asarray(tr, float)
                tr = tr[np.all(np.isfinite(tr), axis=1)] if tr.ndim == 2 else None
            if tr is None or len(tr) < 2:
                continue
            r.stream.set_time(THROW, sequence=k)
            r.strips(
                "world/throw/track",
                [np.asarray(tr)[:, 1:4]],
                labels=["observed"],
                colors=[OBS],
                radius=0.004,
            )
            flight = _model_flight(prob, k)
            if flight is not None:
                r.strips(
                    "world/throw/model_flight",
                    [flight[:, 1:4]],
                    labels=["model"],
                    colors=[BEFORE],
                    radius=0.004,
                )
        return r.path


def _model_flight(prob: Any, k: int) -> np.ndarray | None:
    """The configured model's flight of throw k (None: no stroke logged, or no landing)."""
    if not bool(prob.has_stroke[k]):
        return None
    try:
        return predicted_flight(prob.batch.take(np.array([k])), prob.ee)
    except CellError as exc:
        log.info("throw %d: no model flight (%s)", k, exc)
        return None


def _verdict_markdown(report: dict[str, Any]) -> str:
    v = report.get("verdict", {})
    rows = [
        ("verdict", ", ".join(v.get("effects", [])) or "-"),
        ("held-out RMSE after [m]", v.get("heldout_rmse_m")),
        ("shrink [%]", v.get("shrink_pct")),
        ("shrink interval [%]", v.get("shrink_ci_pct")),
    ]
    for key in ("baseline", "where"):
        if isinstance(report.get(key), dict):
            for k2, v2 in report[key].items():
                if not isinstance(v2, (dict, list)):
                    rows.append((f"{key}.{k2}", v2))
    body = "\n".join(f"| {a} | {b} |" for a, b in rows)
    return "# cell gap\n\n| | |\n|---|---|\n" + body + "\n"
