"""Make an end-effector back-end by name: what `cell run --ee KIND` calls."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from cell.endeffector.base import EndEffector
from cell.endeffector.instep import InStep
from cell.errors import InvalidInput
from cell.kinds import EE_BACKENDS, SIM_EE_BACKEND

__all__ = ["EE_KINDS", "DEFAULT_DYNAMIXEL_CONFIG", "make_end_effector", "make_in_step"]

EE_KINDS = EE_BACKENDS
"""The back-ends this factory makes: the simulated one (on a plant) and the hardware ones."""


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
    plant: Any = None,
) -> Any:
    """An end-effector back-end, connected and ready.

    Args:
        kind: back-end name, one of EE_KINDS ("pybullet": the plant's simulated one).
        config_path: hardware description (Dynamixel: YAML; default
            robots/throwing_ee/dynamixel.yaml).
        port: serial port overriding the configuration's.
        emulate: drive an emulated bus on a pseudo-terminal instead of hardware;
            it stops when the end-effector is closed.
        time_scale: emulated seconds per real second (emulate only).
        plant: the PyBullet cell whose end-effector body to drive ("pybullet" only).

    Returns:
        The end-effector; close it (or use `with`) to turn torque off.

    Raises:
        InvalidInput: unknown kind or bad configuration file.
        HardwareError: the hardware cannot be reached.
    """
    if kind == SIM_EE_BACKEND:
        return _simulated(plant)
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


def make_in_step(plant: Any, hardware: EndEffector | None = None) -> InStep:
    """The end-effector a platform commands: the plant's simulated one (built here, on
    the plant's scene) and, when given, a hardware one driven in step with it
    (`cell.endeffector.instep.InStep`).

    Args:
        plant: the PyBullet cell (`cell.sim.CellScene`) whose end-effector body to drive.
        hardware: a connected hardware end-effector (from `make_end_effector`), or None.
    """
    return InStep(_simulated(plant), hardware)


def _simulated(plant: Any) -> Any:
    """The plant's simulated end-effector."""
    if plant is None:
        raise InvalidInput("the pybullet end-effector rides a scene: give its plant")
    from cell.endeffector.pybullet_backend import PyBulletEndEffector

    return PyBulletEndEffector(plant)
