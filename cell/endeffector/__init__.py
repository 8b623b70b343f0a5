"""The end-effector interface and its back-ends (PyBullet, Dynamixel)."""

from cell.endeffector.base import EndEffector, EndEffectorStatus

__all__ = ["EndEffector", "EndEffectorStatus"]
