"""The names the cell knows, each list defined here once.

* The arms are not listed here: they are the mount files under robots/ (and any a job
  names), `cell.robot.mount.robot_names`.
* `PLATFORMS`: what carries the end-effector. Its order is an encoding (the gap
  diagnosis codes a platform by its index, a synthetic world draws them in this order):
  add new names at the end.
* `PICKS`: how the arm gets an item into the grip (kinematic: moved into it; physical: by
  contact). `RELEASES`: how it lets a throw go ("auto": on the move where the planner finds
  that sooner, cell.robot.moving_release; "static": always at a stop).
* `EE_BACKENDS`: the end-effector back-ends; `pybullet` is the simulated one, the
  others are hardware (`HARDWARE_EE_BACKENDS`).
"""

from __future__ import annotations

__all__ = [
    "EE_BACKENDS",
    "HARDWARE_EE_BACKENDS",
    "PICKS",
    "PLATFORMS",
    "RELEASES",
    "SIM_EE_BACKEND",
]

PLATFORMS: tuple[str, ...] = ("arm", "mobile", "drone")
SIM_EE_BACKEND = "pybullet"
EE_BACKENDS: tuple[str, ...] = (SIM_EE_BACKEND, "dynamixel")
HARDWARE_EE_BACKENDS: tuple[str, ...] = tuple(k for k in EE_BACKENDS if k != SIM_EE_BACKEND)
PICKS: tuple[str, ...] = ("kinematic", "physical")
RELEASES: tuple[str, ...] = ("auto", "static")
