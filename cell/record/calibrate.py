"""A recording of `cell calibrate`: the scene's throws against the model before and after the fit.

Every campaign throw on the `throw` timeline: its release point and throw axis,
where it landed in the scene, where the nominal model and the fitted model say
it lands (`compare.record_landings`, scalars `calibrate/nominal_m` and
`calibrate/fitted_m`), and the fitted model's flight from the release.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import CellError
from cell.identify.report import predicted_landing
from cell.model.throw import throw_axis
from cell.params import ModelParams
from cell.record.compare import AFTER, THROW, layout, record_landings
from cell.record.flight import predicted_flight
from cell.record.stream import Recording

__all__ = ["record_calibration"]

log = logging.getLogger(__name__)


def record_calibration(
    path: str | Path, table: Any, fitted: ModelParams, nominal: ModelParams | None = None
) -> Path:
    """Write the recording of a calibration campaign.

    Args:
        path: the `.rrd` file.
        table: the campaign's throw log (ThrowTable).
        fitted: the identified parameters.
        nominal: the model before the fit (default: the reference parameters).

    Returns:
        The file written.
    """
    nominal = nominal or ModelParams()
    z = table.num("land_z_m")
    obs = np.column_stack([table.landed, z])
    before = np.column_stack([predicted_landing(table, nominal), z])
    after = np.column_stack([predicted_landing(table, fitted), z])
    p0 = np.column_stack([table.num("x_m"), table.num("y_m"), table.num("z_m")])
    u = throw_axis(table.num("elevation_rad"), table.num("azimuth_rad"))
    ids = [f"{t} {o}" for t, o in zip(table.text("throw_id"), table.text("object_id"), strict=True)]
    with Recording(path, "cell_calibrate") as r:
        r.stream.send_blueprint(layout("calibrate", ("nominal", "fitted"), "parameters"))
        r.document("parameters", _params_markdown(fitted))
        record_landings(r, obs, before, after, ids, ("nominal", "fitted"), scalars="calibrate")
        batch = table.to_batch(objects=fitted.objects)
        for k in range(len(table)):
            r.stream.set_time(THROW, sequence=k)
            r.arrows("world/throw/release", p0[k], 0.2 * u[k], labels=[ids[k]], colors=[AFTER])
            try:
                flight = predicted_flight(batch.take(np.array([k])), fitted.ee)
            except CellError as exc:
                log.info("throw %d: no fitted flight (%s)", k, exc)
                continue
            r.strips(
                "world/throw/model_flight",
                [flight[:, 1:4]],
                labels=["fitted model"],
                colors=[AFTER],
                radius=0.004,
            )
        return r.path


def _params_markdown(p: ModelParams) -> str:
    rows = "\n".join(f"| {k} | {v:.6g} |" for k, v in p.ee.as_dict().items())
    return "# fitted end-effector parameters\n\n| | |\n|---|---|\n" + rows + "\n"
