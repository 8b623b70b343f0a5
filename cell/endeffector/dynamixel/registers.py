"""Dynamixel X-series control tables (Protocol 2.0) as frozen data.

Addresses, sizes and access of the registers the end-effector uses, per model,
from the ROBOTIS e-manual (XL430-W250, XM430-W350, XM540-W270). No logic lives
here: the bus, the driver and the emulator all read these tables, so an
address is written once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

__all__ = [
    "Register",
    "ControlTable",
    "MODELS",
    "HardwareErrorBit",
    "HARDWARE_ERROR_BITS",
    "INSTRUCTION_ERRORS",
    "ALERT_BIT",
    "BAUD_RATES",
    "OPERATING_MODE_POSITION",
    "OPERATING_MODE_EXTENDED_POSITION",
    "EXTENDED_POSITION_RANGE",
    "TICKS_PER_REV",
    "VELOCITY_UNIT_RPM",
    "ticks_to_rad",
    "rad_to_ticks",
]

Access = Literal["R", "RW"]
Area = Literal["EEPROM", "RAM"]

TICKS_PER_REV = 4096  # [ticks/rev] 12-bit absolute encoder of the X series
VELOCITY_UNIT_RPM = 0.229  # [rev/min] one unit of Profile Velocity / Velocity Limit
OPERATING_MODE_POSITION = 3  # position control, 0..4095 ticks
OPERATING_MODE_EXTENDED_POSITION = 4  # multi-turn, -1 048 575..1 048 575 ticks
EXTENDED_POSITION_RANGE = (-1_048_575, 1_048_575)  # [ticks]


def ticks_to_rad(ticks: float) -> float:
    """Servo ticks to an angle [rad]."""
    return float(ticks) * 2.0 * math.pi / TICKS_PER_REV


def rad_to_ticks(angle_rad: float) -> float:
    """An angle [rad] to servo ticks (not rounded)."""
    return float(angle_rad) * TICKS_PER_REV / (2.0 * math.pi)


@dataclass(frozen=True)
class Register:
    """One control-table entry.

    Attributes:
        name: e-manual name in snake case.
        address: byte address.
        size: bytes (1, 2 or 4), little endian.
        access: "R" read-only or "RW".
        area: "EEPROM" (writable only with torque off) or "RAM".
        signed: two's complement value.
        default: factory value.
    """

    name: str
    address: int
    size: int
    access: Access
    area: Area
    signed: bool = False
    default: int = 0

    @property
    def end(self) -> int:
        """First address after this register."""
        return self.address + self.size


def _x_series(model_number: int, *, velocity_limit: int, current: bool) -> dict[str, Register]:
    """The X-series table shared by XL430/XM430/XM540 (XL430 has no current control)."""
    E: Area = "EEPROM"
    R: Area = "RAM"
    regs = [
        Register("model_number", 0, 2, "R", E, default=model_number),
        Register("model_information", 2, 4, "R", E),
        Register("firmware_version", 6, 1, "R", E, default=46),
        Register("id", 7, 1, "RW", E, default=1),
        Register("baud_rate", 8, 1, "RW", E, default=1),
        Register("return_delay_time", 9, 1, "RW", E, default=250),
        Register("drive_mode", 10, 1, "RW", E),
        Register("operating_mode", 11, 1, "RW", E, default=OPERATING_MODE_POSITION),
        Register("secondary_id", 12, 1, "RW", E, default=255),
        Register("protocol_type", 13, 1, "RW", E, default=2),
        Register("homing_offset", 20, 4, "RW", E, signed=True),
        Register("moving_threshold", 24, 4, "RW", E, default=10),
        Register("temperature_limit", 31, 1, "RW", E, default=80 if current else 72),
        Register("max_voltage_limit", 32, 2, "RW", E, default=160 if current else 140),
        Register("min_voltage_limit", 34, 2, "RW", E, default=95 if current else 60),
        Register("pwm_limit", 36, 2, "RW", E, default=885),
        Register("velocity_limit", 44, 4, "RW", E, default=velocity_limit),
        Register("max_position_limit", 48, 4, "RW", E, default=4095),
        Register("min_position_limit", 52, 4, "RW", E, default=0),
        Register("shutdown", 63, 1, "RW", E, default=52),
        Register("torque_enable", 64, 1, "RW", R),
        Register("led", 65, 1, "RW", R),
        Register("status_return_level", 68, 1, "RW", R, default=2),
        Register("registered_instruction", 69, 1, "R", R),
        Register("hardware_error_status", 70, 1, "R", R),
        Register("velocity_i_gain", 76, 2, "RW", R, default=1920 if current else 1000),
        Register("velocity_p_gain", 78, 2, "RW", R, default=100),
        Register("position_d_gain", 80, 2, "RW", R),
        Register("position_i_gain", 82, 2, "RW", R),
        Register("position_p_gain", 84, 2, "RW", R, default=800 if current else 640),
        Register("bus_watchdog", 98, 1, "RW", R),
        Register("goal_pwm", 100, 2, "RW", R, signed=True),
        Register("goal_velocity", 104, 4, "RW", R, signed=True),
        Register("profile_acceleration", 108, 4, "RW", R),
        Register("profile_velocity", 112, 4, "RW", R),
        Register("goal_position", 116, 4, "RW", R, signed=True),
        Register("realtime_tick", 120, 2, "R", R),
        Register("moving", 122, 1, "R", R),
        Register("moving_status", 123, 1, "R", R),
        Register("present_pwm", 124, 2, "R", R, signed=True),
        # XL430 calls 126 "Present Load" [0.1 %]; XM430/XM540 "Present Current" [2.69 mA].
        Register("present_current", 126, 2, "R", R, signed=True),
        Register("present_velocity", 128, 4, "R", R, signed=True),
        Register("present_position", 132, 4, "R", R, signed=True),
        Register("velocity_trajectory", 136, 4, "R", R, signed=True),
        Register("position_trajectory", 140, 4, "R", R, signed=True),
        Register("present_input_voltage", 144, 2, "R", R, default=120),
        Register("present_temperature", 146, 1, "R", R, default=30),
    ]
    if current:
        regs += [
            Register("current_limit", 38, 2, "RW", E, default=1193),
            Register("goal_current", 102, 2, "RW", R, signed=True),
        ]
    return {r.name: r for r in sorted(regs, key=lambda r: r.address)}


@dataclass(frozen=True)
class ControlTable:
    """A servo model's control table.

    Attributes:
        model: model name, lower case (e.g. "xm430-w350").
        model_number: what PING and register 0 report.
        registers: name -> Register, sorted by address.
        no_load_speed_rpm: speed at 12 V with no load [rev/min] (emulator).
    """

    model: str
    model_number: int
    registers: MappingProxyType[str, Register] = field(repr=False)
    no_load_speed_rpm: float

    def __getitem__(self, name: str) -> Register:
        return self.registers[name]

    def covering(self, address: int) -> Register | None:
        """The register whose bytes include `address`, or None (a gap)."""
        for r in self.registers.values():
            if r.address <= address < r.end:
                return r
        return None


def _table(model: str, number: int, *, vlim: int, current: bool, rpm: float) -> ControlTable:
    regs = _x_series(number, velocity_limit=vlim, current=current)
    return ControlTable(model, number, MappingProxyType(regs), rpm)


# Sorted registry of the supported models.
MODELS: MappingProxyType[str, ControlTable] = MappingProxyType(
    {
        "xl430-w250": _table("xl430-w250", 1060, vlim=265, current=False, rpm=61.0),
        "xm430-w350": _table("xm430-w350", 1020, vlim=200, current=True, rpm=46.0),
        "xm540-w270": _table("xm540-w270", 1120, vlim=128, current=True, rpm=30.0),
    }
)


@dataclass(frozen=True)
class HardwareErrorBit:
    """One bit of Hardware Error Status (address 70).

    Attributes:
        bit: bit index.
        name: short name.
        check: what the operator should check.
    """

    bit: int
    name: str
    check: str


HARDWARE_ERROR_BITS: tuple[HardwareErrorBit, ...] = (
    HardwareErrorBit(
        0, "input voltage", "check the supply voltage is within the servo's voltage limits"
    ),
    HardwareErrorBit(2, "overheating", "let the servo cool down and reduce its load or duty cycle"),
    HardwareErrorBit(
        3, "motor encoder", "the servo's encoder is faulty: check or replace the servo"
    ),
    HardwareErrorBit(
        4,
        "electrical shock",
        "check the supply and wiring for a short circuit; the motor may be damaged",
    ),
    HardwareErrorBit(
        5,
        "overload",
        "the load exceeds the servo's torque: check the spool, thread and latch for a jam",
    ),
)

ALERT_BIT = 0x80  # status packet error byte: a hardware error is latched in register 70

# Status packet error byte (low 7 bits) -> meaning (Protocol 2.0).
INSTRUCTION_ERRORS: MappingProxyType[int, str] = MappingProxyType(
    {
        1: "result fail (the servo could not process the instruction)",
        2: "instruction error (undefined instruction, or REG_WRITE without ACTION)",
        3: "CRC error (the servo received a corrupted instruction)",
        4: "data range error (value outside the register's range)",
        5: "data length error (too short for the register)",
        6: "data limit error (value outside the configured limits)",
        7: "access error (read-only register, or EEPROM written with torque on)",
    }
)

# Register value of Baud Rate (address 8) -> bit/s.
BAUD_RATES: MappingProxyType[int, int] = MappingProxyType(
    {
        0: 9_600,
        1: 57_600,
        2: 115_200,
        3: 1_000_000,
        4: 2_000_000,
        5: 3_000_000,
        6: 4_000_000,
        7: 4_500_000,
    }
)
