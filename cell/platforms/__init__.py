"""Platforms that carry the end-effector besides the fixed arm: a drone and a moving base.

* `downwash`: the rotor downwash law and throws through it (pure NumPy);
* `drone`: the iris quadrotor hovering in the PyBullet cell with the
  end-effector beneath, applying the downwash to free items (imports pybullet
  only when a scene is built);
* `mobile`: a mobile base moving at release; throw planning with the base
  velocity free within bounds and the base's ruckig drive to the release state.
"""

from cell.platforms.downwash import DownwashLaw, air_velocity, predict_drone_landing
from cell.platforms.mobile import BaseLimits, BaseTrajectory, MobilePlatform

__all__ = [
    "BaseLimits",
    "BaseTrajectory",
    "DownwashLaw",
    "DronePlatform",
    "DroneScene",
    "MobilePlatform",
    "air_velocity",
    "predict_drone_landing",
    "scene_exit_distance_m",
]


def __getattr__(name: str) -> object:
    # the drone's scene classes import the PyBullet scene module: load them on demand
    if name in ("DronePlatform", "DroneScene", "scene_exit_distance_m"):
        from cell.platforms import drone

        return getattr(drone, name)
    raise AttributeError(f"module 'cell.platforms' has no attribute {name!r}")
