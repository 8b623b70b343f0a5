"""Shared set-up for the Dynamixel tests: a fast configuration and an emulated bus."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from cell.endeffector.dynamixel import DynamixelConfig, DynamixelEndEffector, EmulatedBus
from cell.endeffector.dynamixel.config import LatchConfig, SpoolConfig, StrokeConfig, TimingConfig

TIME_SCALE = 40.0  # emulated seconds per real second: a full wind takes ~40 ms

FAST = DynamixelConfig(
    port="/dev/null",
    baud_rate=1_000_000,
    retries=2,
    latency_timer_ms=60.0,  # replies awaited 122 ms: the emulator thread shares a busy CPU
    latch=LatchConfig(id=1, model="xl430-w250", engaged_position=2048, released_position=2560),
    spool=SpoolConfig(id=2, model="xm430-w350", radius_m=0.010, rest_position=0),
    stroke=StrokeConfig(min_m=0.03, max_m=0.11, rest_m=0.11, tolerance_m=0.002),
    timing=TimingConfig(move_margin_s=1.0, stall_timeout_s=0.1, poll_period_s=0.002),
)


@contextmanager
def rig(config: DynamixelConfig = FAST) -> Iterator[tuple[EmulatedBus, DynamixelEndEffector]]:
    """An emulated end-effector and the driver connected to it through dynamixel-sdk."""
    with EmulatedBus.from_config(config, time_scale=TIME_SCALE) as emu:
        ee = DynamixelEndEffector(config, port=emu.port)
        try:
            yield emu, ee
        finally:
            ee.close()
