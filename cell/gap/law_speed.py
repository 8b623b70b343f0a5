"""A law in the model's launch speed: the release's pitch growing with how fast it leaves.

The laws of `cell.gap.laws` are in a logged quantity of the throw (stroke, mass, grip
width). A release whose elevation error grows with the launch speed (a gripper whose
fingers the faster item drags up, a band that lifts more the harder it pulls) is none of
them: on the eleventh lab round's E3 (0.008 rad per m/s, 0.005-0.040 rad over the log)
the constant stood for it, 0.0254 rad, and no form in the stroke was chosen
(docs/HISTORY.md). So `release_pitch` is also tried as `delta_rad = k · launch_speed_mps`
(`MODEL_COVARIATES`): the launch speed relative to the base that the configured model
gives the throw without any effect (`cell.model.throw.launch_state`), a covariate of the
model rather than of the log, so its class carries the end-effector it is read with.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.model.throw import ThrowBatch, launch_state

__all__ = ["MODEL_COVARIATES", "MODEL_FORMS", "launch_speed"]


def launch_speed(batch: ThrowBatch, ee: Any) -> np.ndarray:
    """The configured model's launch speed [m/s] relative to the base, per throw."""
    _, v = launch_state(batch, ee)
    return np.linalg.norm(v - batch.base_velocity, axis=1)


# covariate -> (its reader from a batch and the end-effector, its typical largest value)
MODEL_COVARIATES: dict[str, tuple[Any, float]] = {"launch_speed_mps": (launch_speed, 6.0)}
# the effects whose law may be in a model covariate: effect name -> the covariates
MODEL_FORMS: dict[str, tuple[str, ...]] = {"release_pitch": ("launch_speed_mps",)}
