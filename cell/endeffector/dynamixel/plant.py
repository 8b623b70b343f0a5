"""The emulated mechanism between the two servos: latch gear mesh and spool.

Thesis §2.2.1: M1 moves the lever that meshes gear G1 (on M2) with G2 (on the
spool drum). While meshed, the spool turns with M2 (gear ratio one) and winds
the thread; when M1 opens the mesh the spool spins free and the band pulls the
thread out to its rest stroke at once. The plant keeps the spool's real stroke,
which the driver cannot see directly: tests compare it with the stroke the
driver infers from M2's encoder.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cell.endeffector.dynamixel.registers import ticks_to_rad

if TYPE_CHECKING:
    from cell.endeffector.dynamixel.config import DynamixelConfig
    from cell.endeffector.dynamixel.emulator import EmulatedServo

__all__ = ["SpoolPlant"]


class SpoolPlant:
    """Latch mesh and spool of the end-effector 2.0.

    Args:
        config: the end-effector configuration (positions, spool radius, strokes).
        latch: the emulated M1.
        spool: the emulated M2.

    Attributes:
        true_stroke_m: the spool's real stroke L_s [m].
    """

    def __init__(self, config: DynamixelConfig, latch: EmulatedServo, spool: EmulatedServo) -> None:
        self.cfg = config
        self.latch = latch
        self.spool = spool
        self.true_stroke_m = config.stroke.rest_m
        self._meshed = False
        self._mesh_ticks = 0.0  # M2 position when the mesh closed (spool at rest then)

    def latch_meshed(self) -> bool:
        """The gears mesh while M1 is nearer the engaged than the released position."""
        c = self.cfg.latch
        window = abs(c.released_position - c.engaged_position) / 2.0  # [ticks]
        return abs(self.latch.position - c.engaged_position) < window

    def update(self) -> None:
        """Follow the servos' present positions."""
        meshed = self.latch_meshed()
        rest, spool = self.cfg.stroke.rest_m, self.cfg.spool
        if meshed and not self._meshed:
            self._mesh_ticks = self.spool.position  # the free spool sat at rest
        self._meshed = meshed
        if meshed:
            wound_rad = spool.wind_direction * ticks_to_rad(self.spool.position - self._mesh_ticks)
            # unwinding past rest only slackens the thread: the stroke stays at rest
            self.true_stroke_m = min(rest, rest - spool.radius_m * wound_rad)
        else:
            self.true_stroke_m = rest
