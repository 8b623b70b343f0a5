"""A thin Protocol 2.0 bus over dynamixel-sdk, with retries and typed errors.

Every instruction the driver sends is idempotent (reads and absolute register
writes), so repeating one after a lost or corrupted reply is safe: the bus
retries those `retries` times, then raises `NoReply` or `CorruptReply` with
what to check. A status packet whose alert bit is set makes the bus read the
servo's Hardware Error Status and raise `ServoFault` naming each error and its
remedy; that is not retried, because the error stays latched until a reboot.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Mapping
from typing import Any

from cell.endeffector.dynamixel.registers import (
    ALERT_BIT,
    HARDWARE_ERROR_BITS,
    INSTRUCTION_ERRORS,
    MODELS,
    Register,
)
from cell.errors import CorruptReply, HardwareError, MissingDependency, NoReply, ServoFault

__all__ = ["DynamixelBus", "RegisterBlock", "describe_hardware_error"]

log = logging.getLogger(__name__)

_HW_ERROR = MODELS["xm430-w350"]["hardware_error_status"]  # same address on every X model
_CRC_ERRNUM = 3


def describe_hardware_error(bits: int) -> str:
    """Names and remedies of the set bits of Hardware Error Status."""
    parts = [f"{b.name} ({b.check})" for b in HARDWARE_ERROR_BITS if bits & (1 << b.bit)]
    return "; ".join(parts) if parts else f"unknown hardware error bits 0x{bits:02x}"


def _decode(reg: Register, data: bytes | list[int]) -> int:
    return int.from_bytes(bytes(data[: reg.size]), "little", signed=reg.signed)


def _encode(reg: Register, value: int) -> list[int]:
    lo = -(1 << (8 * reg.size - 1)) if reg.signed else 0
    hi = (1 << (8 * reg.size - 1)) - 1 if reg.signed else (1 << (8 * reg.size)) - 1
    if not lo <= value <= hi:
        raise HardwareError(f"value {value} does not fit register {reg.name} ({lo}..{hi})")
    return list(int(value).to_bytes(reg.size, "little", signed=reg.signed))


def _port_handler(sdk: Any, name: str, latency_timer_ms: float) -> Any:
    """dynamixel-sdk's PortHandler with the reply timeout's latency as a parameter
    (the SDK hard-codes 16 ms, the FTDI default)."""

    class _Port(sdk.PortHandler):  # type: ignore[misc, name-defined]
        def setPacketTimeout(self, packet_length: int) -> None:  # noqa: N802 - SDK name
            self.packet_start_time = self.getCurrentTime()
            self.packet_timeout = (
                self.tx_time_per_byte * packet_length + 2.0 * latency_timer_ms + 2.0
            )

    return _Port(name)


class RegisterBlock:
    """Bytes read from consecutive addresses of one servo."""

    def __init__(self, start: int, data: bytes) -> None:
        self.start = start
        self.data = data

    def __getitem__(self, reg: Register) -> int:
        i = reg.address - self.start
        if i < 0 or i + reg.size > len(self.data):
            raise KeyError(f"register {reg.name} is outside the block read")
        return _decode(reg, self.data[i : i + reg.size])


class DynamixelBus:
    """One serial port with Protocol 2.0 servos on it.

    Args:
        port: serial device path.
        baud_rate: [bit/s].
        retries: repeats after a lost or corrupted reply.
        latency_timer_ms: the USB adapter's latency timer [ms]; a reply is
            awaited for twice this plus 2 ms plus its transfer time, as the SDK does.
    """

    def __init__(
        self, port: str, baud_rate: int, retries: int = 3, latency_timer_ms: float = 16.0
    ) -> None:
        try:
            import dynamixel_sdk as sdk
        except ImportError:
            raise MissingDependency(
                "the Dynamixel end-effector needs dynamixel-sdk: pip install dynamixel-sdk"
            ) from None
        self._sdk: Any = sdk
        self.port = port
        self.baud_rate = baud_rate
        self.retries = retries
        self.latency_timer_ms = latency_timer_ms
        self._port: Any = None
        self._ph: Any = sdk.PacketHandler(2.0)

    # -- connection
    @property
    def is_open(self) -> bool:
        """True while the port is open."""
        return self._port is not None

    def open(self) -> None:
        """Open the serial port at the configured baud rate.

        Raises:
            HardwareError: the port cannot be opened (names the port and what to check).
        """
        if self._port is not None:
            return
        port = _port_handler(self._sdk, self.port, self.latency_timer_ms)
        port.baudrate = self.baud_rate
        try:
            ok = port.openPort()
        except Exception as exc:  # pyserial raises SerialException (an OSError) or ValueError
            raise HardwareError(
                f"cannot open serial port {self.port!r}: {exc}. Check the adapter is plugged in, "
                "the path is right (ls /dev/ttyUSB* /dev/ttyACM*), you may use it (group dialout), "
                "and no other program holds it"
            ) from None
        if not ok:
            raise HardwareError(
                f"serial port {self.port!r} refused baud rate {self.baud_rate}: use one of "
                "9600, 57600, 115200, 1000000, 2000000, 3000000, 4000000"
            )
        try:
            # FTDI adapters then pass bytes on at once instead of every 16 ms; a pty
            # or a non-FTDI adapter refuses the ioctl, which is harmless
            port.ser.set_low_latency_mode(True)
        except (OSError, ValueError, AttributeError) as exc:
            log.debug("low-latency mode unavailable on %s: %s", self.port, exc)
        self._port = port

    def close(self) -> None:
        """Close the port (idempotent)."""
        if self._port is not None:
            try:
                self._port.closePort()
            except Exception as exc:  # closing must not hide the error that led here
                log.warning("closing %s: %s", self.port, exc)
            self._port = None

    def _need_port(self) -> Any:
        if self._port is None:
            raise HardwareError(f"bus {self.port!r} is not open: call open() first")
        return self._port

    # -- errors
    def _comm_error(self, result: int, dxl_id: int, what: str) -> HardwareError:
        sdk = self._sdk
        where = f"servo ID {dxl_id} on {self.port} ({what})"
        if result == sdk.COMM_RX_TIMEOUT:
            return NoReply(
                f"no reply from {where} after {self.retries + 1} tries: check power, "
                f"the cable, the baud rate ({self.baud_rate}) and the ID"
            )
        if result in (sdk.COMM_RX_CORRUPT, sdk.COMM_RX_FAIL):
            return CorruptReply(
                f"corrupted reply from {where} after {self.retries + 1} tries: check the cable, "
                "its termination and connectors, and the baud rate"
            )
        return HardwareError(
            f"{where}: {self._ph.getTxRxResult(result)} check that no other program uses the port"
        )

    def _fault(self, dxl_id: int) -> ServoFault:
        data, result, _ = self._ph.readTxRx(
            self._need_port(), dxl_id, _HW_ERROR.address, _HW_ERROR.size
        )
        bits = _decode(_HW_ERROR, data) if result == self._sdk.COMM_SUCCESS else 0
        text = describe_hardware_error(bits) if bits else "hardware error status unreadable"
        return ServoFault(
            f"servo ID {dxl_id} on {self.port} reports: {text}. The error stays latched "
            "(and torque off if its Shutdown register names it) until the servo is rebooted: "
            "fix the cause, then power-cycle or reboot it",
            servo_id=dxl_id,
            bits=bits,
        )

    def _transact(self, dxl_id: int, what: str, fn: Any) -> tuple[Any, int]:
        """Run `fn() -> (payload, result, error)` with retries; (payload, error byte)."""
        sdk = self._sdk
        result = sdk.COMM_TX_FAIL
        for attempt in range(self.retries + 1):
            payload, result, error = fn()
            if result == sdk.COMM_SUCCESS:
                if error & ALERT_BIT:
                    raise self._fault(dxl_id)
                errnum = error & ~ALERT_BIT
                if errnum == _CRC_ERRNUM:
                    if attempt < self.retries:
                        log.warning("servo ID %d got a corrupted %s; retrying", dxl_id, what)
                        continue
                    raise CorruptReply(
                        f"servo ID {dxl_id} on {self.port} received {what} corrupted "
                        f"{self.retries + 1} times (CRC error): check the cable, its termination "
                        "and connectors, and the baud rate"
                    )
                if errnum:
                    raise HardwareError(
                        f"servo ID {dxl_id} on {self.port} rejected {what}: "
                        f"{INSTRUCTION_ERRORS.get(errnum, f'error {errnum}')}"
                    )
                return payload, error
            if result not in (sdk.COMM_RX_TIMEOUT, sdk.COMM_RX_CORRUPT):
                break  # port busy or tx failure: not a line fault a retry would fix
            log.warning(
                "servo ID %d, %s: %s (try %d of %d)",
                dxl_id,
                what,
                self._ph.getTxRxResult(result),
                attempt + 1,
                self.retries + 1,
            )
        raise self._comm_error(result, dxl_id, what)

    # -- instructions
    def ping(self, dxl_id: int) -> int:
        """PING a servo; its model number."""
        port = self._need_port()
        model, _ = self._transact(dxl_id, "PING", lambda: self._ph.ping(port, dxl_id))
        return int(model)

    def read(self, dxl_id: int, reg: Register) -> int:
        """READ one register (signed where the register is)."""
        port = self._need_port()
        data, _ = self._transact(
            dxl_id,
            f"READ {reg.name}",
            lambda: self._ph.readTxRx(port, dxl_id, reg.address, reg.size),
        )
        return _decode(reg, data)

    def write(self, dxl_id: int, reg: Register, value: int) -> None:
        """WRITE one register and wait for the servo's acknowledgement."""
        port = self._need_port()
        data = _encode(reg, value)

        def op() -> tuple[None, int, int]:
            result, error = self._ph.writeTxRx(port, dxl_id, reg.address, reg.size, data)
            return None, result, error

        self._transact(dxl_id, f"WRITE {reg.name}={value}", op)

    def sync_read(
        self, ids: Iterable[int], first: Register, last: Register
    ) -> dict[int, RegisterBlock]:
        """SYNC READ registers `first`..`last` (inclusive) from several servos at once.

        Returns:
            ID -> the block read.
        """
        port = self._need_port()
        ids = list(ids)
        start, length = first.address, last.end - first.address
        sdk = self._sdk
        out: dict[int, RegisterBlock] = {}
        result, bad_id = sdk.COMM_TX_FAIL, ids[0]
        for attempt in range(self.retries + 1):
            result = self._ph.syncReadTx(port, start, length, ids, len(ids), False)
            if result != sdk.COMM_SUCCESS:
                port.is_using = False
                break
            faulted: int | None = None
            for dxl_id in ids:
                data, result, error = self._ph.readRx(port, dxl_id, length)
                if result != sdk.COMM_SUCCESS:
                    bad_id = dxl_id
                    break
                if error & ALERT_BIT and faulted is None:
                    faulted = dxl_id
                out[dxl_id] = RegisterBlock(start, bytes(data))
            if result == sdk.COMM_SUCCESS:
                if faulted is not None:
                    raise self._fault(faulted)
                return out
            log.warning(
                "SYNC READ, servo ID %d: %s (try %d of %d)",
                bad_id,
                self._ph.getTxRxResult(result),
                attempt + 1,
                self.retries + 1,
            )
        raise self._comm_error(result, bad_id, f"SYNC READ {first.name}..{last.name}")

    def sync_write(self, reg: Register, values: Mapping[int, int]) -> None:
        """SYNC WRITE one register on several servos (broadcast: no acknowledgement)."""
        port = self._need_port()
        group = self._sdk.GroupSyncWrite(port, self._ph, reg.address, reg.size)
        for dxl_id, value in values.items():
            group.addParam(dxl_id, _encode(reg, value))
        result = group.txPacket()
        if result != self._sdk.COMM_SUCCESS:
            raise HardwareError(
                f"SYNC WRITE {reg.name} on {self.port}: {self._ph.getTxRxResult(result)}"
            )

    def reboot(self, dxl_id: int) -> None:
        """REBOOT a servo (clears a latched hardware error; torque comes back off)."""
        port = self._need_port()

        def op() -> tuple[None, int, int]:
            result, error = self._ph.reboot(port, dxl_id)
            return None, result, error & ~ALERT_BIT

        self._transact(dxl_id, "REBOOT", op)
