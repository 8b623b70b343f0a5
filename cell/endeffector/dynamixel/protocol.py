"""Dynamixel Protocol 2.0 framing: CRC-16, byte stuffing, packets.

The device side of the protocol, used by the emulated bus (the host side is
dynamixel-sdk's). Written from the e-manual's packet description, bit by bit,
so it is an independent implementation of what the SDK does with tables.

Packet: FF FF FD 00 | ID | LEN_L LEN_H | INST | PARAMS... | CRC_L CRC_H, where
LEN counts INST, PARAMS (after stuffing) and CRC; a status packet's INST is
0x55 followed by an ERROR byte. Stuffing inserts 0xFD after every FF FF FD
met from INST on, so the header never appears inside a packet.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = [
    "HEADER",
    "INST_PING",
    "INST_READ",
    "INST_WRITE",
    "INST_REBOOT",
    "INST_STATUS",
    "INST_SYNC_READ",
    "INST_SYNC_WRITE",
    "BROADCAST_ID",
    "crc16",
    "stuff",
    "unstuff",
    "Instruction",
    "status_packet",
    "PacketParser",
]

HEADER = b"\xff\xff\xfd\x00"
BROADCAST_ID = 0xFE
INST_PING = 0x01
INST_READ = 0x02
INST_WRITE = 0x03
INST_REBOOT = 0x08
INST_STATUS = 0x55
INST_SYNC_READ = 0x82
INST_SYNC_WRITE = 0x83
_CRC_POLY = 0x8005


def crc16(data: bytes | bytearray) -> int:
    """CRC-16 of Protocol 2.0 (polynomial 0x8005, initial 0, not reflected)."""
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ _CRC_POLY) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Insert 0xFD after every FF FF FD in `body` (INST onwards, before CRC).

    The two bytes before `body` in a packet are LEN_L LEN_H, which cannot
    complete an FF FF FD with the first bytes of `body` only if LEN_H != 0xFF;
    packets here are far shorter, so looking inside `body` is enough.
    """
    out = bytearray()
    for b in body:
        out.append(b)
        if b == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF:
            out.append(0xFD)
    return bytes(out)


def unstuff(body: bytes) -> bytes:
    """Remove the 0xFD inserted by `stuff`."""
    out = bytearray()
    i = 0
    while i < len(body):
        b = body[i]
        out.append(b)
        if (
            b == 0xFD
            and len(out) >= 3
            and out[-3] == 0xFF
            and out[-2] == 0xFF
            and i + 1 < len(body)
            and body[i + 1] == 0xFD
        ):
            i += 1  # skip the stuffing byte
        i += 1
    return bytes(out)


def _frame(dxl_id: int, body: bytes) -> bytes:
    stuffed = stuff(body)
    length = len(stuffed) + 2
    pkt = HEADER + bytes([dxl_id, length & 0xFF, length >> 8]) + stuffed
    crc = crc16(pkt)
    return pkt + bytes([crc & 0xFF, crc >> 8])


def status_packet(dxl_id: int, error: int, params: bytes = b"") -> bytes:
    """A status packet from servo `dxl_id` with `error` byte and `params`."""
    return _frame(dxl_id, bytes([INST_STATUS, error & 0xFF]) + bytes(params))


def instruction_packet(dxl_id: int, inst: int, params: bytes = b"") -> bytes:
    """An instruction packet (for tests of the parser)."""
    return _frame(dxl_id, bytes([inst]) + bytes(params))


@dataclass(frozen=True)
class Instruction:
    """A received instruction packet.

    Attributes:
        dxl_id: target ID (0xFE = broadcast).
        inst: instruction code.
        params: parameters, unstuffed.
        crc_ok: False when the CRC did not match (the servo answers with a CRC error).
    """

    dxl_id: int
    inst: int
    params: bytes
    crc_ok: bool = True


class PacketParser:
    """Splits a byte stream into instruction packets, resynchronising on garbage."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[Instruction]:
        """Add received bytes; return the complete packets found."""
        self._buf += data
        out: list[Instruction] = []
        while True:
            start = self._buf.find(HEADER)
            if start < 0:
                # keep a possible partial header at the end
                del self._buf[: max(0, len(self._buf) - 3)]
                return out
            del self._buf[:start]
            if len(self._buf) < 7:
                return out
            length = self._buf[5] | (self._buf[6] << 8)
            total = 7 + length
            if length < 3 or length > 1024:
                del self._buf[:1]  # not a real header: resync
                continue
            if len(self._buf) < total:
                return out
            pkt = bytes(self._buf[:total])
            del self._buf[:total]
            crc = pkt[-2] | (pkt[-1] << 8)
            body = unstuff(pkt[7:-2])
            out.append(Instruction(pkt[4], body[0], body[1:], crc16(pkt[:-2]) == crc))
