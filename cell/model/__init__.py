"""The throwing end-effector's physics: pure, vectorised, no simulator, no I/O."""

from cell.model.band import (
    BandState,
    band_angle,
    band_force,
    band_state,
    band_stretch,
    grip_force,
    push_force,
    stored_energy,
)
from cell.model.objects import SHAPES, ObjectParams, drag_area, inertia_diagonal, shape_code
from cell.model.params import DEFAULT_EE, RHO_AIR, EndEffectorParams, G
from cell.model.throw import (
    Landing,
    ThrowBatch,
    drag_constant,
    launch_state,
    no_landing_error,
    predict_landing,
    reference_landing,
    throw_axis,
)

__all__ = [
    "DEFAULT_EE",
    "G",
    "RHO_AIR",
    "SHAPES",
    "BandState",
    "EndEffectorParams",
    "Landing",
    "ObjectParams",
    "ThrowBatch",
    "band_angle",
    "band_force",
    "band_state",
    "band_stretch",
    "drag_area",
    "drag_constant",
    "grip_force",
    "inertia_diagonal",
    "launch_state",
    "no_landing_error",
    "predict_landing",
    "push_force",
    "reference_landing",
    "shape_code",
    "stored_energy",
    "throw_axis",
]
