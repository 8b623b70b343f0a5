"""The PyBullet cell scene: arm, throwing end-effector mechanism, bins, items.

Importing this package does not import pybullet; building a `CellScene` does.
"""

from cell.sim.bins import BinSpec, which_bin
from cell.sim.frames import (
    DEFAULT_BINS,
    EE_TO_TCP_M,
    FLANGE_TO_EE_M,
    FLANGE_YAW_RAD,
    PANDA_READY,
    release_orientation,
)
from cell.sim.mechanism import DEFAULT_GEOMETRY, EEGeometry
from cell.sim.scene import CellScene
from cell.sim.settle import Outcome

__all__ = [
    "BinSpec",
    "CellScene",
    "DEFAULT_BINS",
    "DEFAULT_GEOMETRY",
    "EEGeometry",
    "EE_TO_TCP_M",
    "FLANGE_TO_EE_M",
    "FLANGE_YAW_RAD",
    "Outcome",
    "PANDA_READY",
    "release_orientation",
    "which_bin",
]
