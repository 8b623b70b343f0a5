"""Make an end-effector back-end by name: what `cell run --ee KIND` calls."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from cell.endeffector.base import EndEffector
from cell.errors import InvalidInput
from cell.kinds import HARDWARE_EE_BACKENDS

__all__ = ["EE_KINDS", "DEFAULT_DYNAMIXEL_CONFIG", "make_end_effector"]

EE_KINDS = HARDWARE_EE_BACKENDS
"""The hardware back-ends this factory makes (the simulated one rides a scene)."""


def _default_config() -> Path:
    from cell.robot.paths import robots_dir

    return robots_dir() / "throwing_ee" / "dynamixel.yaml"


# The shipped configuration, found whatever the current folder is.
DEFAULT_DYNAMIXEL_CONFIG = _default_config()
EMULATED_LATENCY_MS = 50.0  # [ms] reply latency allowed for an emulated bus


def make_end_effector(
    kind: str,
    config_path: str | Path | None = None,
    *,
    port: str | None = None,
    emulate: bool = False,
    time_scale: float = 1.0,
) -> EndEffector:
    """An end-effector back-end, connected and ready.

    Args:
        kind: back-end name, one of EE_KINDS.
        config_path: hardware description (Dynamixel: YAML; default
            robots/throwing_ee/dynamixel.yaml).
        port: serial port overriding the configuration's.
        emulate: drive an emulated bus on a pseudo-terminal instead of hardware;
            it stops when the end-effector is closed.
        time_scale: emulated seconds per real second (emulate only).

    Returns:
        The end-effector; close it (or use `with`) to turn torque off.

    Raises:
        InvalidInput: unknown kind or bad configuration file.
        HardwareError: the hardware cannot be reached.
    """
    if kind == "dynamixel":
        from cell.endeffector.dynamixel import DynamixelEndEffector, EmulatedBus, load_config

        cfg = load_config(config_path if config_path is not None else DEFAULT_DYNAMIXEL_CONFIG)
        if not emulate:
            return DynamixelEndEffector(cfg, port=port)
        # the emulator is a thread of this process: on a busy machine its replies can
        # come later than a USB adapter's, so allow it more than the 34 ms the SDK does
        cfg = dataclasses.replace(
            cfg, latency_timer_ms=max(cfg.latency_timer_ms, EMULATED_LATENCY_MS)
        )
        emu = EmulatedBus.from_config(cfg, time_scale=time_scale).start()
        try:
            return DynamixelEndEffector(cfg, port=emu.port, on_close=emu.stop)
        except BaseException:
            emu.stop()
            raise
    raise InvalidInput(f"unknown end-effector kind {kind!r}; valid: {list(EE_KINDS)}")
