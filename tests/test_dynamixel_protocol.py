"""Protocol 2.0 framing of the emulator against the e-manual and dynamixel-sdk."""

from __future__ import annotations

import dynamixel_sdk as sdk
import pytest

from cell.endeffector.dynamixel import protocol as p
from cell.endeffector.dynamixel.registers import MODELS, rad_to_ticks, ticks_to_rad

# e-manual, Protocol 2.0 examples: PING to ID 1, and ID 1's status reply
# (model 1030, firmware 0x26).
PING_ID1 = bytes.fromhex("FFFFFD0001030001194E")
STATUS_ID1 = bytes.fromhex("FFFFFD000107005500060426655D")


def test_crc_matches_the_emanual_examples() -> None:
    assert p.crc16(PING_ID1[:-2]) == 0x4E19
    assert p.crc16(STATUS_ID1[:-2]) == 0x5D65
    assert p.instruction_packet(1, p.INST_PING) == PING_ID1
    assert p.status_packet(1, 0, bytes([0x06, 0x04, 0x26])) == STATUS_ID1


def test_crc_agrees_with_the_sdk_table() -> None:
    ph = sdk.Protocol2PacketHandler()
    for n in range(0, 200, 7):
        data = bytes((i * 37 + n) & 0xFF for i in range(n))
        assert p.crc16(data) == ph.updateCRC(0, list(data), len(data))


def test_stuffing_round_trip_and_sdk_agreement() -> None:
    body = bytes([0x03, 0x74, 0x00, 0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFF, 0xFD, 0xFD])
    stuffed = p.stuff(body)
    assert stuffed.count(b"\xff\xff\xfd\xfd") == 2
    assert p.unstuff(stuffed) == body
    # the SDK stuffs a whole packet in place: same bytes between header and CRC
    n = len(body) + 2
    pkt = [0xFF, 0xFF, 0xFD, 0x00, 0x02, n & 0xFF, n >> 8, *body, 0, 0]
    out = sdk.Protocol2PacketHandler().addStuffing(pkt)
    assert bytes(out[7:-2]) == stuffed


def test_parser_splits_resyncs_and_flags_bad_crc() -> None:
    a = p.instruction_packet(1, p.INST_READ, bytes([132, 0, 4, 0]))
    b = bytearray(p.instruction_packet(2, p.INST_PING))
    b[-1] ^= 0xFF
    parser = p.PacketParser()
    got = parser.feed(b"\x00\x13" + a[:5])
    assert got == []
    got = parser.feed(a[5:] + bytes(b))
    assert [(g.dxl_id, g.inst, g.crc_ok) for g in got] == [
        (1, p.INST_READ, True),
        (2, p.INST_PING, False),
    ]
    assert got[0].params == bytes([132, 0, 4, 0])


def test_control_tables_hold_the_emanual_addresses() -> None:
    for table in MODELS.values():
        assert table["torque_enable"].address == 64
        assert table["goal_position"].address == 116
        assert table["present_position"].address == 132
        assert table["hardware_error_status"].address == 70
        assert table["operating_mode"].address == 11
        # registers never overlap
        regs = list(table.registers.values())
        for r0, r1 in zip(regs, regs[1:], strict=False):
            assert r0.end <= r1.address, (r0, r1)
    assert MODELS["xm430-w350"].model_number == 1020
    assert MODELS["xl430-w250"].model_number == 1060
    assert "goal_current" not in MODELS["xl430-w250"].registers


@pytest.mark.parametrize("ticks", [0, 1, 2048, 4096, -5215])
def test_tick_angle_round_trip(ticks: int) -> None:
    assert rad_to_ticks(ticks_to_rad(ticks)) == pytest.approx(ticks)
