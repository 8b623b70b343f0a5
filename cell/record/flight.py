"""The model's predicted flight of a throw, sampled in time (to draw beside the observed one).

The push phase is integrated as `predict_landing` does (`launch_state`), then
the free flight with drag by the 3-D integrator (`sample_path`), from the end
of the push to the crossing of the landing plane. Times are since the start of
the push (the release), the clock of the scene's observed tracks.
"""

from __future__ import annotations

import numpy as np

from cell.model.flight3d import sample_path
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, drag_constant, launch_state, predict_landing

__all__ = ["predicted_flight"]


def predicted_flight(
    batch: ThrowBatch, ee: EndEffectorParams, *, n: int = 60, step: float = 0.002
) -> np.ndarray:
    """Samples t [s], x, y, z [m, W] of the predicted flight of a one-throw batch.

    Args:
        batch: one throw (e.g. `ThrowPlan.to_batch(model_object)`).
        ee: the end-effector parameters the prediction uses.
        n: samples across the free flight (plus the release point).
        step: RK4 step of the free flight [s].

    Returns:
        Shape (n + 1, 4): the release point at t = 0, then the free flight from
        the end of the push to the landing-plane crossing.

    Raises:
        NoLanding: the throw never reaches its landing plane.
        InvalidParameter: its stroke is outside the end-effector's range.
    """
    land = predict_landing(batch, ee)
    p1, v1 = launch_state(batch, ee)
    k = drag_constant(batch.shape, batch.mass, batch.size)
    t_free = float(land.t_flight[0]) - ee.dt
    t_rel = np.linspace(0.0, t_free, n)[None, :]
    path = sample_path(p1[:1], v1[:1], k[:1], t_rel, step=step)[0]
    t = np.concatenate([[0.0], ee.dt + t_rel[0]])
    xyz = np.vstack([batch.position[:1], path])
    return np.column_stack([t, xyz])
