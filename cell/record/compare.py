"""Observed landings against two model predictions, throw by throw (for `cell gap` and
`cell calibrate` recordings).

Static entities show every throw at once; the `throw` timeline steps through
them one by one with their |residual| as scalars.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.record.stream import Recording

__all__ = ["THROW", "record_landings", "layout", "OBS", "BEFORE", "AFTER"]

THROW = "throw"  # timeline: the throw's row in the log
OBS, BEFORE, AFTER = (0, 130, 200), (230, 25, 75), (60, 180, 75)


def record_landings(
    r: Recording,
    observed: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
    labels: Sequence[str],
    names: tuple[str, str] = ("before", "after"),
    scalars: str = "residual",
) -> None:
    """Log landings [m, W], each (n, 3): observed, predicted before and after.

    Entities: `world/landings/observed|model_<name>` and `world/residuals/<name>`
    (static, every throw), `world/throw/observed|model_<name>` (the throw at the
    cursor of the `throw` timeline) and `<scalars>/<name>_m` (|observed − model|
    in the horizontal [m], a gap where the model has no landing).
    """
    obs = np.asarray(observed, float)
    preds = {names[0]: np.asarray(before, float), names[1]: np.asarray(after, float)}
    r.points("world/landings/observed", obs, colors=[OBS], radii=0.01, static=True)
    for (name, p), col in zip(preds.items(), (BEFORE, AFTER), strict=True):
        ok = np.all(np.isfinite(p), axis=1)
        r.points(f"world/landings/model_{name}", p[ok], colors=[col], radii=0.008, static=True)
        segs = list(np.stack([p[ok], obs[ok]], axis=1))
        r.strips(f"world/residuals/{name}", segs, colors=[col], radius=0.002, static=True)
    for k in range(len(obs)):
        r.stream.set_time(THROW, sequence=k)
        r.points("world/throw/observed", obs[k], labels=[str(labels[k])], colors=[OBS], radii=0.03)
        for (name, p), col in zip(preds.items(), (BEFORE, AFTER), strict=True):
            if np.all(np.isfinite(p[k])):
                r.points(f"world/throw/model_{name}", p[k], colors=[col], radii=0.025)
            r.scalar(f"{scalars}/{name}_m", float(np.hypot(*(obs[k, :2] - p[k, :2]))))


def layout(scalars: str, names: tuple[str, str], document: str) -> Any:
    """The viewer's default layout: landings in 3-D beside the residuals and a document."""
    import rerun.blueprint as rrb

    eye = rrb.EyeControls3D(position=(-0.5, -2.5, 2.0), look_target=(1.2, 0.0, 0.0))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="world", name="landings", eye_controls=eye),
            rrb.Vertical(
                rrb.TimeSeriesView(origin=scalars, name=f"|residual| {' / '.join(names)} [m]"),
                rrb.TextDocumentView(origin=document, name=document),
            ),
            column_shares=[2, 1],
        ),
        rrb.TimePanel(timeline=THROW, play_state="paused"),
        collapse_panels=True,
    )
