"""Configuration of the Dynamixel end-effector, loaded from YAML.

One file under `robots/` describes the hardware: serial port and baud rate,
the latch servo M1 and the spool servo M2 (ID, model, positions, speeds), the
spool radius and the map from M2's angle to the stroke L_s, and the limits.

The stroke map (spool on M2 through a 1:1 gear, thesis §2.2.1): with the
thread paid out to its rest stroke `stroke.rest_m` at M2 position
`spool.rest_position`, winding the spool by θ [rad] shortens the stroke by
`spool.radius_m` · θ:

    L_s = rest_m - radius_m · wind_direction · (ticks - rest_position) · 2π / 4096
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from cell.endeffector.dynamixel.registers import (
    EXTENDED_POSITION_RANGE,
    MODELS,
    rad_to_ticks,
    ticks_to_rad,
)
from cell.errors import InvalidInput, InvalidParameter
from cell.yamlsafe import read_yaml_text, safe_load

__all__ = [
    "LatchConfig",
    "SpoolConfig",
    "StrokeConfig",
    "TimingConfig",
    "DynamixelConfig",
    "load_config",
]

# Rates both the X series and dynamixel-sdk's PortHandler accept [bit/s].
_BAUDS = (9_600, 57_600, 115_200, 1_000_000, 2_000_000, 3_000_000, 4_000_000)


def _check(problems: list[tuple[str, str]]) -> None:
    if problems:
        raise InvalidParameter("; ".join(f"{k}: {m}" for k, m in problems))


def _servo_problems(servo_id: int, model: str) -> list[tuple[str, str]]:
    """(field, message) for a servo's bus ID and model, those invalid."""
    out = []
    if not 0 <= servo_id <= 252:
        out.append(("id", f"must be a servo ID in 0..252, got {servo_id}"))
    if model not in MODELS:
        out.append(("model", f"unknown model {model!r}; valid: {sorted(MODELS)}"))
    return out


@dataclass(frozen=True)
class LatchConfig:
    """The latch servo M1 (position mode, one turn).

    Attributes:
        id: bus ID.
        model: servo model (see registers.MODELS).
        engaged_position: goal with the gears meshed [ticks, 0..4095].
        released_position: goal with the mesh open [ticks, 0..4095].
        tolerance: how near the engaged position counts as confirmed [ticks].
        profile_velocity: speed for engaging [0.229 rev/min; 0 = fastest].
        throw_profile_velocity: speed for the throw [0.229 rev/min; 0 = fastest].
    """

    id: int = 1
    model: str = "xl430-w250"
    engaged_position: int = 2048
    released_position: int = 2560
    tolerance: int = 20
    profile_velocity: int = 0
    throw_profile_velocity: int = 0

    def problems(self) -> list[tuple[str, str]]:
        """(field, message) for every invalid field."""
        out = _servo_problems(self.id, self.model)
        for name in ("engaged_position", "released_position"):
            if not 0 <= getattr(self, name) <= 4095:
                out.append((name, f"must be in 0..4095 ticks, got {getattr(self, name)}"))
        gap = abs(self.released_position - self.engaged_position)
        if not 0 < self.tolerance < gap / 2:
            out.append(("tolerance", f"must be in (0, {gap / 2:g}) ticks (half the latch travel)"))
        for name in ("profile_velocity", "throw_profile_velocity"):
            if getattr(self, name) < 0:
                out.append((name, "must be >= 0 (0 = fastest)"))
        return out

    def __post_init__(self) -> None:
        _check([(f"latch.{k}", m) for k, m in self.problems()])


@dataclass(frozen=True)
class SpoolConfig:
    """The spool servo M2 (extended position mode, multi-turn).

    Attributes:
        id: bus ID.
        model: servo model.
        radius_m: spool drum radius r_drum [m] (thesis eq. 2.5).
        rest_position: M2 position with the thread paid out to stroke.rest_m [ticks].
        wind_direction: +1 if winding increases M2's position, -1 if it decreases it.
        profile_velocity: winding speed [0.229 rev/min; 0 = fastest].
        place_profile_velocity: slow unwinding speed for place [0.229 rev/min, > 0].
        profile_acceleration: [214.577 rev/min²; 0 = unlimited].
    """

    id: int = 2
    model: str = "xm430-w350"
    radius_m: float = 0.010
    rest_position: int = 0
    wind_direction: int = 1
    profile_velocity: int = 0
    place_profile_velocity: int = 20
    profile_acceleration: int = 0

    def problems(self) -> list[tuple[str, str]]:
        """(field, message) for every invalid field."""
        out = _servo_problems(self.id, self.model)
        if not (math.isfinite(self.radius_m) and 0.001 <= self.radius_m <= 0.1):
            out.append(("radius_m", f"must be in [0.001, 0.1] m, got {self.radius_m}"))
        lo, hi = EXTENDED_POSITION_RANGE
        if not lo <= self.rest_position <= hi:
            out.append(("rest_position", f"must be in {lo}..{hi} ticks"))
        if self.wind_direction not in (1, -1):
            out.append(("wind_direction", f"must be 1 or -1, got {self.wind_direction}"))
        if self.profile_velocity < 0 or self.profile_acceleration < 0:
            out.append(("profile_velocity", "profile velocity/acceleration must be >= 0"))
        if self.place_profile_velocity <= 0:
            out.append(("place_profile_velocity", "must be > 0 (placing unwinds slowly)"))
        return out

    def __post_init__(self) -> None:
        _check([(f"spool.{k}", m) for k, m in self.problems()])


@dataclass(frozen=True)
class StrokeConfig:
    """Stroke limits [m].

    Attributes:
        min_m: shortest allowed stroke (most wound).
        max_m: longest allowed stroke.
        rest_m: stroke with the thread paid out (free spool), within [min_m, max_m].
        tolerance_m: how far the encoder may be from the command.
    """

    min_m: float = 0.03
    max_m: float = 0.11
    rest_m: float = 0.11
    tolerance_m: float = 0.002

    def problems(self) -> list[tuple[str, str]]:
        """(field, message) for every invalid field."""
        out = []
        if not (0.0 < self.min_m < self.max_m):
            out.append(("min_m", f"need 0 < min_m < max_m, got {self.min_m}, {self.max_m}"))
        if not self.min_m <= self.rest_m <= self.max_m:
            out.append(("rest_m", f"must be in [min_m, max_m], got {self.rest_m}"))
        if not 0.0 < self.tolerance_m < (self.max_m - self.min_m):
            out.append(("tolerance_m", f"must be in (0, max_m - min_m), got {self.tolerance_m}"))
        return out

    def __post_init__(self) -> None:
        _check([(f"stroke.{k}", m) for k, m in self.problems()])


@dataclass(frozen=True)
class TimingConfig:
    """Timeouts [s].

    Attributes:
        move_margin_s: time a move may take beyond its duration at the profile
            velocity (1.5 × that duration + this margin), before it counts as failed.
        stall_timeout_s: a move that makes no progress this long has stalled.
        poll_period_s: pause between position reads while waiting.
    """

    move_margin_s: float = 1.0
    stall_timeout_s: float = 0.5
    poll_period_s: float = 0.01

    def problems(self) -> list[tuple[str, str]]:
        """(field, message) for every invalid field."""
        out = []
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not (math.isfinite(v) and v > 0):
                out.append((f.name, f"must be > 0 s, got {v}"))
        return out

    def __post_init__(self) -> None:
        _check([(f"timing.{k}", m) for k, m in self.problems()])


@dataclass(frozen=True)
class DynamixelConfig:
    """The whole end-effector hardware description.

    Attributes:
        port: serial device (e.g. /dev/ttyUSB0).
        baud_rate: [bit/s], as set in the servos.
        retries: repeats of an instruction after a lost or corrupted reply.
        latency_timer_ms: USB adapter latency timer [ms]; a reply is awaited for
            2 × this + 2 ms + its transfer time (16 ms: FTDI default, as the SDK).
        latch: M1.
        spool: M2.
        stroke: stroke limits.
        timing: timeouts.
        source: file it was loaded from ("" if built in code).
    """

    port: str = "/dev/ttyUSB0"
    baud_rate: int = 1_000_000
    retries: int = 3
    latency_timer_ms: float = 16.0
    latch: LatchConfig = field(default_factory=LatchConfig)
    spool: SpoolConfig = field(default_factory=SpoolConfig)
    stroke: StrokeConfig = field(default_factory=StrokeConfig)
    timing: TimingConfig = field(default_factory=TimingConfig)
    source: str = ""

    def __post_init__(self) -> None:
        problems = []
        if self.baud_rate not in _BAUDS:
            problems.append(("baud_rate", f"must be one of {list(_BAUDS)}, got {self.baud_rate}"))
        if not 0 <= self.retries <= 10:
            problems.append(("retries", f"must be in 0..10, got {self.retries}"))
        if not 1.0 <= self.latency_timer_ms <= 1000.0:
            problems.append(
                ("latency_timer_ms", f"must be in [1, 1000] ms, got {self.latency_timer_ms}")
            )
        if self.latch.id == self.spool.id:
            problems.append(("spool.id", f"M1 and M2 share ID {self.spool.id}: IDs must differ"))
        lo, hi = EXTENDED_POSITION_RANGE
        for name in ("min_m", "max_m"):
            t = self.stroke_to_ticks(getattr(self.stroke, name))
            if not lo <= t <= hi:
                problems.append((f"stroke.{name}", f"maps to {t} ticks, outside {lo}..{hi}"))
        _check(problems)

    def stroke_to_ticks(self, stroke_m: float) -> int:
        """M2 goal position [ticks] for a stroke L_s [m] (not range checked)."""
        wound_rad = (self.stroke.rest_m - stroke_m) / self.spool.radius_m
        return self.spool.rest_position + self.spool.wind_direction * round(rad_to_ticks(wound_rad))

    def ticks_to_stroke(self, ticks: float) -> float:
        """Stroke L_s [m] for an M2 position [ticks]."""
        wound_rad = self.spool.wind_direction * ticks_to_rad(ticks - self.spool.rest_position)
        return self.stroke.rest_m - self.spool.radius_m * wound_rad

    def with_port(self, port: str) -> DynamixelConfig:
        """A copy using another serial port."""
        return dataclasses.replace(self, port=port)


_SECTIONS: dict[str, Any] = {
    "latch": LatchConfig,
    "spool": SpoolConfig,
    "stroke": StrokeConfig,
    "timing": TimingConfig,
}
_TOP = {"port": str, "baud_rate": int, "retries": int, "latency_timer_ms": float}


def _coerce(where: str, v: Any, typ: Any) -> Any:
    if typ is int or typ == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            raise InvalidInput(f"{where}: must be an integer, got {v!r}")
        return v
    if typ is float or typ == "float":
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise InvalidInput(f"{where}: must be a number, got {v!r}")
        return float(v)
    if not isinstance(v, str):
        raise InvalidInput(f"{where}: must be a string, got {v!r}")
    return v


def load_config(path: str | Path) -> DynamixelConfig:
    """Read a Dynamixel end-effector YAML file.

    Args:
        path: the YAML file (e.g. robots/throwing_ee/dynamixel.yaml).

    Returns:
        The configuration; missing keys take the defaults of the dataclasses.

    Raises:
        InvalidInput: missing or unreadable file, unknown key, or a bad value;
            the message names the file and the field and says what is valid.
    """
    p = Path(path)
    raw = safe_load(read_yaml_text(p, "end-effector configuration file"), str(p)) or {}
    if not isinstance(raw, dict):
        raise InvalidInput(f"{p}: must be a mapping with keys {sorted([*_TOP, *_SECTIONS])}")
    unknown = set(raw) - set(_TOP) - set(_SECTIONS)
    if unknown:
        raise InvalidInput(
            f"{p}: unknown key(s) {sorted(unknown)}; valid: {sorted([*_TOP, *_SECTIONS])}"
        )
    kw: dict[str, Any] = {k: _coerce(f"{p}: {k}", raw[k], t) for k, t in _TOP.items() if k in raw}
    for name, cls in _SECTIONS.items():
        sec = raw.get(name) or {}
        if not isinstance(sec, dict):
            raise InvalidInput(f"{p}: {name}: must be a mapping")
        types = {f.name: f.type for f in dataclasses.fields(cls)}
        bad = set(sec) - set(types)
        if bad:
            raise InvalidInput(f"{p}: {name}: unknown key(s) {sorted(bad)}; valid: {sorted(types)}")
        args = {k: _coerce(f"{p}: {name}.{k}", v, types[k]) for k, v in sec.items()}
        try:
            kw[name] = cls(**args)
        except InvalidParameter as exc:
            raise InvalidInput(f"{p}: {exc}") from None
    try:
        return DynamixelConfig(**kw, source=str(p))
    except InvalidParameter as exc:
        raise InvalidInput(f"{p}: {exc}") from None
