"""An emulated Dynamixel bus on a pseudo-terminal, with the end-effector's plant.

`EmulatedBus` opens a pty pair, serves Protocol 2.0 on the master side from a
background thread, and gives the slave's path (`.port`) to whoever wants to
talk to it: dynamixel-sdk opens it with pyserial like a USB adapter, so the
driver runs its real serial code path.

Each `EmulatedServo` holds its model's control table in a byte array and moves
its present position toward the goal at the profile velocity (or the velocity
limit when that is 0); `time_scale` speeds the clock up for tests. The plant
couples the two servos as in the thesis' end-effector 2.0 (§2.2.1): while the
latch servo M1 sits within its engagement window, the spool follows M2 gear for
gear; when M1 leaves the window the spool spins free and the band pulls the
thread out to its rest stroke. The encoder the driver reads is M2's present
position; `true_stroke_m()` gives the spool's real stroke, independently.

Faults are injected per servo: lost replies, corrupted CRCs, hardware error
bits (which turn torque off as the Shutdown register says), a mechanical jam
at a position, and an absent servo.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty
from dataclasses import dataclass, field

from cell.endeffector.dynamixel import protocol as p
from cell.endeffector.dynamixel.config import DynamixelConfig
from cell.endeffector.dynamixel.plant import SpoolPlant
from cell.endeffector.dynamixel.registers import (
    ALERT_BIT,
    EXTENDED_POSITION_RANGE,
    MODELS,
    OPERATING_MODE_EXTENDED_POSITION,
    TICKS_PER_REV,
    VELOCITY_UNIT_RPM,
    ControlTable,
)
from cell.errors import HardwareError, InvalidParameter

__all__ = ["EmulatedServo", "EmulatedBus", "Faults"]

log = logging.getLogger(__name__)

_MEM_SIZE = 256
# Status packet error numbers (Protocol 2.0)
ERR_RESULT_FAIL = 1
ERR_INSTRUCTION = 2
ERR_CRC = 3
ERR_RANGE = 4
ERR_LENGTH = 5
ERR_LIMIT = 6
ERR_ACCESS = 7


@dataclass
class Faults:
    """Faults injected into one servo (mutable; the bus thread reads it).

    Attributes:
        drop_replies: the next n replies are lost (the instruction is executed).
        corrupt_replies: the next n replies carry a wrong CRC.
        corrupt_instructions: the next n instructions arrive with a wrong CRC
            (the servo answers with a CRC error and does nothing).
        absent: the servo never answers (unplugged, wrong ID or baud rate).
        jam_ticks: a mechanical stop: the position cannot cross this value [ticks].
        jam_side: the side of `jam_ticks` the servo is on (+1 above, -1 below).
    """

    drop_replies: int = 0
    corrupt_replies: int = 0
    corrupt_instructions: int = 0
    absent: bool = False
    jam_ticks: float | None = None
    jam_side: int = 1


@dataclass
class EmulatedServo:
    """One X-series servo: control table bytes and a position that moves.

    Attributes:
        dxl_id: bus ID.
        table: the model's control table.
        position: present position [ticks] (float: sub-tick motion).
        faults: injected faults.
        goal_log: (goal position, profile velocity) of every goal written.
    """

    dxl_id: int
    table: ControlTable
    position: float = 0.0
    faults: Faults = field(default_factory=Faults)
    mem: bytearray = field(default_factory=lambda: bytearray(_MEM_SIZE), repr=False)
    goal_log: list[tuple[int, int]] = field(default_factory=list, repr=False)
    _t_last: float = field(default=0.0, repr=False)

    def __post_init__(self) -> None:
        for reg in self.table.registers.values():
            self._poke(reg.address, reg.size, reg.default)
        self._poke(self.table["id"].address, 1, self.dxl_id)
        self._poke(self.table["goal_position"].address, 4, round(self.position))

    # -- raw memory
    def _poke(self, address: int, size: int, value: int) -> None:
        self.mem[address : address + size] = (int(value) & ((1 << (8 * size)) - 1)).to_bytes(
            size, "little"
        )

    def value(self, name: str) -> int:
        """A register's value (signed where the register is)."""
        reg = self.table[name]
        raw = bytes(self.mem[reg.address : reg.end])
        return int.from_bytes(raw, "little", signed=reg.signed)

    def set_value(self, name: str, value: int) -> None:
        """Set a register directly (emulator side, no checks)."""
        reg = self.table[name]
        self._poke(reg.address, reg.size, value)

    # -- motion
    def speed_ticks_s(self) -> float:
        """Current speed toward the goal [ticks/s] (unscaled)."""
        pv = self.value("profile_velocity")
        vlim = self.value("velocity_limit")
        units = pv if 0 < pv <= vlim else vlim
        rpm = min(units * VELOCITY_UNIT_RPM, self.table.no_load_speed_rpm)
        return rpm / 60.0 * TICKS_PER_REV

    def advance(self, now: float, time_scale: float) -> None:
        """Move the present position toward the goal up to time `now` [s]."""
        dt = max(0.0, now - self._t_last) * time_scale
        self._t_last = now
        goal = float(self.value("goal_position"))
        if self.value("torque_enable") and dt > 0.0 and self.position != goal:
            step = self.speed_ticks_s() * dt
            delta = goal - self.position
            new = goal if abs(delta) <= step else self.position + step * (1 if delta > 0 else -1)
            jam, side = self.faults.jam_ticks, self.faults.jam_side
            if jam is not None and side * (new - jam) < 0:
                new = jam  # blocked by the obstruction
            self.position = new
        moving = abs(goal - self.position) > self.value("moving_threshold")
        self.set_value("moving", int(moving and bool(self.value("torque_enable"))))
        self.set_value("present_position", round(self.position))
        self.set_value("present_velocity", 0)
        self.set_value("realtime_tick", int(now * 1000) % 32768)

    # -- instructions
    def read(self, address: int, length: int) -> tuple[int, bytes]:
        """READ: (error, data)."""
        if address + length > _MEM_SIZE or length < 1:
            return ERR_RANGE, b""
        return 0, bytes(self.mem[address : address + length])

    def write(self, address: int, data: bytes) -> int:
        """WRITE: returns the error number (0 = done)."""
        if not data:
            return ERR_LENGTH
        if address + len(data) > _MEM_SIZE:
            return ERR_RANGE
        torque_on = bool(self.value("torque_enable"))
        for a in range(address, address + len(data)):
            reg = self.table.covering(a)
            if reg is None or reg.access == "R":
                return ERR_ACCESS
            if reg.area == "EEPROM" and torque_on:
                return ERR_ACCESS
        staged = bytearray(self.mem)
        staged[address : address + len(data)] = data
        goal_reg = self.table["goal_position"]
        if address < goal_reg.end and address + len(data) > goal_reg.address:
            goal = int.from_bytes(staged[goal_reg.address : goal_reg.end], "little", signed=True)
            if self.value("operating_mode") == OPERATING_MODE_EXTENDED_POSITION:
                lo, hi = EXTENDED_POSITION_RANGE
            else:
                lo, hi = self.value("min_position_limit"), self.value("max_position_limit")
            if not lo <= goal <= hi:
                return ERR_LIMIT
            self.goal_log.append((goal, self.value("profile_velocity")))
        te = self.table["torque_enable"].address
        if address <= te < address + len(data):
            if staged[te] > 1:
                return ERR_RANGE
            if staged[te] == 1 and self.value("hardware_error_status"):
                return ERR_RESULT_FAIL  # torque stays off until a reboot
            if staged[te] == 1 and not torque_on:
                # the servo holds where it is when torque comes on
                staged[goal_reg.address : goal_reg.end] = round(self.position).to_bytes(
                    4, "little", signed=True
                )
        self.mem[:] = staged
        return 0

    def set_jam(self, ticks: float | None) -> None:
        """Put an obstruction at `ticks` (None removes it); the servo stays on its side."""
        self.faults.jam_ticks = ticks
        if ticks is not None:
            self.faults.jam_side = 1 if self.position >= ticks else -1

    def set_hardware_error(self, bits: int) -> None:
        """Latch hardware error bits; torque goes off if Shutdown names one."""
        self.set_value("hardware_error_status", bits)
        if bits & self.value("shutdown"):
            self.set_value("torque_enable", 0)

    def reboot(self) -> None:
        """REBOOT: clear errors, torque off (RAM back to defaults would lose little here)."""
        self.set_value("hardware_error_status", 0)
        self.set_value("torque_enable", 0)

    def error_byte(self, errnum: int) -> int:
        """Status packet error byte: instruction error plus the alert bit."""
        return errnum | (ALERT_BIT if self.value("hardware_error_status") else 0)


class EmulatedBus:
    """A Protocol 2.0 bus with servos, served on a pty from a background thread.

    Args:
        servos: the servos on the bus.
        time_scale: simulated seconds per real second (> 1 makes moves faster).
        plant: optional end-effector coupling (see `from_config`).

    Use as a context manager, or call `start()` and `stop()`.
    """

    def __init__(
        self,
        servos: list[EmulatedServo],
        *,
        time_scale: float = 1.0,
        plant: SpoolPlant | None = None,
    ) -> None:
        if time_scale <= 0:
            raise InvalidParameter(f"time_scale must be > 0, got {time_scale}")
        self.servos = {s.dxl_id: s for s in servos}
        self.time_scale = float(time_scale)
        self.plant = plant
        self.lock = threading.RLock()
        self.packets_received = 0
        self.crc_errors_received = 0
        self._master: int | None = None
        self._slave: int | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.port = ""

    @classmethod
    def from_config(cls, config: DynamixelConfig, *, time_scale: float = 1.0) -> EmulatedBus:
        """The end-effector of `config`: latch servo, spool servo and their coupling.

        M2 starts at its rest position with the thread paid out; M1 starts at
        the released position.
        """
        latch = EmulatedServo(
            config.latch.id, MODELS[config.latch.model], float(config.latch.released_position)
        )
        spool = EmulatedServo(
            config.spool.id, MODELS[config.spool.model], float(config.spool.rest_position)
        )
        return cls([latch, spool], time_scale=time_scale, plant=SpoolPlant(config, latch, spool))

    # -- lifecycle
    def start(self) -> EmulatedBus:
        """Open the pty and serve from a daemon thread."""
        master, slave = os.openpty()
        tty.setraw(slave)  # no echo, no line discipline: raw bytes both ways
        self._master, self._slave = master, slave
        self.port = os.ttyname(slave)
        now = time.monotonic()
        for s in self.servos.values():
            s._t_last = now
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="dxl-emulator", daemon=True)
        self._thread.start()
        log.info("emulated Dynamixel bus on %s (IDs %s)", self.port, sorted(self.servos))
        return self

    def stop(self) -> None:
        """Stop serving and close the pty."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for fd in (self._master, self._slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._master = self._slave = None

    def __enter__(self) -> EmulatedBus:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- state for tests and the plant
    def update(self) -> None:
        """Advance every servo and the plant to now."""
        with self.lock:
            now = time.monotonic()
            for s in self.servos.values():
                s.advance(now, self.time_scale)
            if self.plant is not None:
                self.plant.update()

    def servo(self, dxl_id: int) -> EmulatedServo:
        """The servo with `dxl_id`."""
        return self.servos[dxl_id]

    def true_stroke_m(self) -> float:
        """The spool's real stroke L_s [m] (not what the encoder says)."""
        if self.plant is None:
            raise HardwareError("this emulated bus has no end-effector plant")
        self.update()
        return self.plant.true_stroke_m

    # -- serving
    def _serve(self) -> None:
        parser = p.PacketParser()
        assert self._master is not None
        master = self._master
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([master], [], [], 0.05)
                if not ready:
                    continue
                data = os.read(master, 4096)
            except OSError:
                # EIO while no one has the slave open: wait and retry
                time.sleep(0.01)
                continue
            for ins in parser.feed(data):
                reply = self._handle(ins)
                if reply:
                    try:
                        os.write(master, reply)
                    except OSError:
                        pass

    def _reply(self, servo: EmulatedServo, errnum: int, params: bytes = b"") -> bytes:
        f = servo.faults
        if f.drop_replies > 0:
            f.drop_replies -= 1
            return b""
        pkt = bytearray(p.status_packet(servo.dxl_id, servo.error_byte(errnum), params))
        if f.corrupt_replies > 0:
            f.corrupt_replies -= 1
            pkt[-1] ^= 0x5A
        return bytes(pkt)

    def _handle(self, ins: p.Instruction) -> bytes:
        with self.lock:
            self.packets_received += 1
            self.update()
            if ins.dxl_id == p.BROADCAST_ID:
                return self._handle_broadcast(ins)
            servo = self.servos.get(ins.dxl_id)
            if servo is None or servo.faults.absent:
                return b""
            if servo.faults.corrupt_instructions > 0:
                servo.faults.corrupt_instructions -= 1
                ins = p.Instruction(ins.dxl_id, ins.inst, ins.params, crc_ok=False)
            if not ins.crc_ok:
                self.crc_errors_received += 1
                return self._reply(servo, ERR_CRC)
            a = ins.params
            if ins.inst == p.INST_PING:
                num = servo.value("model_number")
                fw = servo.value("firmware_version")
                return self._reply(servo, 0, bytes([num & 0xFF, num >> 8, fw]))
            if ins.inst == p.INST_READ and len(a) == 4:
                err, data = servo.read(a[0] | a[1] << 8, a[2] | a[3] << 8)
                return self._reply(servo, err, data)
            if ins.inst == p.INST_WRITE and len(a) >= 3:
                err = servo.write(a[0] | a[1] << 8, a[2:])
                self.update()
                return self._reply(servo, err)
            if ins.inst == p.INST_REBOOT:
                servo.reboot()
                return self._reply(servo, 0)
            return self._reply(servo, ERR_INSTRUCTION)

    def _handle_broadcast(self, ins: p.Instruction) -> bytes:
        if not ins.crc_ok or len(ins.params) < 4:
            return b""
        a = ins.params
        address, length = a[0] | a[1] << 8, a[2] | a[3] << 8
        if ins.inst == p.INST_SYNC_WRITE:
            rest = a[4:]
            for k in range(0, len(rest) - length + 1, length + 1):
                servo = self.servos.get(rest[k])
                if servo is not None and not servo.faults.absent:
                    servo.write(address, rest[k + 1 : k + 1 + length])
            self.update()
            return b""  # broadcast: no status packets
        if ins.inst == p.INST_SYNC_READ:
            out = b""
            for dxl_id in a[4:]:
                servo = self.servos.get(dxl_id)
                if servo is None or servo.faults.absent:
                    break  # the later servos wait for this one's packet in vain
                err, data = servo.read(address, length)
                out += self._reply(servo, err, data)
            return out
        return b""
