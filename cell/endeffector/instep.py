"""The simulated end-effector and a hardware one, driven in step.

`InStep` is an `EndEffector` whose every command goes to the plant's end-effector
(`cell.endeffector.pybullet_backend.PyBulletEndEffector`) and, when one is given, to a
hardware back-end (e.g. the Dynamixel one) in the order a real cell needs: the
hardware grasps after the simulated grip holds the item, throws before the simulated
latch opens (the plant then shows the launch the hardware made), and places after
the simulated place. A platform commands the end-effector through it alone; made by
`cell.endeffector.factory.make_in_step`.
"""

from __future__ import annotations

from typing import Any

from cell.endeffector.base import EndEffector, EndEffectorStatus

__all__ = ["InStep"]


class InStep(EndEffector):
    """The plant's end-effector, and a hardware one in step with it.

    Args:
        sim: the plant's end-effector.
        hardware: a connected hardware end-effector, or None (simulation only).
    """

    def __init__(self, sim: Any, hardware: EndEffector | None = None) -> None:
        self.sim = sim
        self.hardware = hardware

    def grasp(self, stroke_m: float, item: Any = None, yaw_rad: float = 0.0) -> None:
        """Grip at stroke L_s [m]: the simulated end-effector takes `item` into its grip
        turned `yaw_rad` [rad] about the grip's axis (None: the grip already holds it, as
        after a physical pick), then the hardware winds to the same stroke."""
        if item is not None:
            self.sim.grasp(stroke_m, item, yaw_rad=yaw_rad)
        if self.hardware is not None:
            self.hardware.grasp(stroke_m)

    def set_stroke(self, stroke_m: float) -> None:
        """Wind both to stroke L_s [m]."""
        self.sim.set_stroke(stroke_m)
        if self.hardware is not None:
            self.hardware.set_stroke(stroke_m)

    def place(self) -> None:
        """Release gently: the simulated end-effector, then the hardware."""
        self.sim.place()
        if self.hardware is not None:
            self.hardware.place()

    def throw(self) -> None:
        """Release at once: the hardware's latch first, then the simulated one."""
        if self.hardware is not None:
            self.hardware.throw()
        self.sim.throw()

    def stroke(self) -> float:
        """The stroke [m]: the hardware's encoder when there is one, else the plant's."""
        return self.hardware.stroke() if self.hardware is not None else float(self.sim.stroke())

    def status(self) -> EndEffectorStatus:
        """The hardware's status when there is one, else the plant's."""
        return self.hardware.status() if self.hardware is not None else self.sim.status()

    def close(self) -> None:
        """Close the hardware (torque off); the plant's closes with its scene."""
        if self.hardware is not None:
            self.hardware.close()
