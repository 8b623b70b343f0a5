"""Injected bus faults: retried where safe, then raised as typed errors that say what to check."""

from __future__ import annotations

import logging

import pytest

from cell.endeffector.dynamixel import DynamixelEndEffector, EmulatedBus
from cell.errors import CorruptReply, HardwareError, NoReply, ServoFault
from tests.dynamixel_fixtures import FAST, TIME_SCALE, rig

OVERLOAD, OVERHEATING, VOLTAGE, SHOCK, ENCODER = 1 << 5, 1 << 2, 1 << 0, 1 << 4, 1 << 3


def test_dropped_reply_is_retried(caplog: pytest.LogCaptureFixture) -> None:
    with rig() as (emu, ee):
        ee.grasp(0.05)
        emu.servo(2).faults.drop_replies = FAST.retries  # one fewer than the tries
        before = emu.packets_received
        with caplog.at_level(logging.WARNING):
            assert ee.stroke() == pytest.approx(0.05, abs=2e-5)  # reads M1, then M2
        assert emu.servo(2).faults.drop_replies == 0
        assert "There is no status packet" in caplog.text
        assert emu.packets_received - before >= FAST.retries + 1


def test_dropped_replies_beyond_retries_raise_no_reply() -> None:
    with rig() as (emu, ee):
        emu.servo(2).faults.drop_replies = FAST.retries + 1
        with pytest.raises(NoReply) as exc:
            ee.bus.read(2, ee._spool["present_position"])
        msg = str(exc.value)
        assert "ID 2" in msg and emu.port in msg
        for hint in ("power", "cable", "baud rate", "ID"):
            assert hint in msg
        ee.bus.read(2, ee._spool["present_position"])  # the bus recovers


def test_dropped_write_reply_is_retried_and_the_write_lands() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.07)
        emu.servo(2).faults.drop_replies = 1
        ee.set_stroke(0.05)
        assert emu.true_stroke_m() == pytest.approx(0.05, abs=2e-5)


def test_corrupted_crc_is_retried_then_raised() -> None:
    with rig() as (emu, ee):
        emu.servo(1).faults.corrupt_replies = FAST.retries
        assert ee.bus.ping(1) == 1060
        emu.servo(1).faults.corrupt_replies = FAST.retries + 1
        with pytest.raises(CorruptReply) as exc:
            ee.bus.ping(1)
        assert "ID 1" in str(exc.value) and "cable" in str(exc.value)
        assert "termination" in str(exc.value)


def test_corrupted_instruction_gets_crc_error_and_is_retried() -> None:
    with rig() as (emu, ee):
        emu.servo(2).faults.corrupt_instructions = 1
        crc_before = emu.crc_errors_received
        reg = ee._spool["profile_velocity"]
        ee.bus.write(2, reg, 77)
        assert emu.crc_errors_received == crc_before + 1
        assert emu.servo(2).value("profile_velocity") == 77
        emu.servo(2).faults.corrupt_instructions = FAST.retries + 1
        with pytest.raises(CorruptReply, match="corrupted 3 times .CRC error.: check the cable"):
            ee.bus.write(2, reg, 78)
        assert emu.servo(2).value("profile_velocity") == 77


def test_sync_read_retries_a_dropped_reply() -> None:
    with rig() as (emu, ee):
        emu.servo(1).faults.drop_replies = 1
        st = ee.status()
        assert not st.latch_engaged and st.stroke_m == FAST.stroke.rest_m
        emu.servo(2).faults.drop_replies = FAST.retries + 1
        with pytest.raises(NoReply, match="SYNC READ"):
            ee.status()


@pytest.mark.parametrize(
    ("servo_id", "bits", "name", "hint"),
    [
        (2, OVERLOAD, "overload", "jam"),
        (1, OVERHEATING, "overheating", "cool down"),
        (2, VOLTAGE, "input voltage", "supply voltage"),
        (1, SHOCK, "electrical shock", "short circuit"),
        (2, ENCODER, "motor encoder", "replace"),
    ],
)
def test_error_status_raises_servo_fault(servo_id: int, bits: int, name: str, hint: str) -> None:
    with rig() as (emu, ee):
        ee.grasp(0.06)
        with emu.lock:
            emu.servo(servo_id).set_hardware_error(bits)
        with pytest.raises(ServoFault) as exc:
            ee.set_stroke(0.05)
        assert exc.value.servo_id == servo_id and exc.value.bits == bits
        assert name in str(exc.value) and hint in str(exc.value)
        assert f"ID {servo_id}" in str(exc.value)
        with pytest.raises(ServoFault):
            ee.status()  # SYNC READ sees the alert bit too


def test_overload_shuts_the_servo_down_and_throw_is_refused() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.06)
        with emu.lock:
            emu.servo(1).set_hardware_error(OVERLOAD)  # Shutdown default includes overload
        assert emu.servo(1).value("torque_enable") == 0
        with pytest.raises(ServoFault, match="overload"):
            ee.throw()
        assert emu.servo(1).value("goal_position") == FAST.latch.engaged_position


def test_reboot_clears_a_latched_error() -> None:
    with rig() as (emu, ee):
        with emu.lock:
            emu.servo(2).set_hardware_error(OVERHEATING)
        ee.bus.reboot(2)
        assert emu.servo(2).value("hardware_error_status") == 0
        assert ee.bus.read(2, ee._spool["torque_enable"]) == 0


def test_missing_servo_at_connect_names_it_and_closes_the_port() -> None:
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        emu.servo(2).faults.absent = True
        with pytest.raises(NoReply, match="ID 2"):
            DynamixelEndEffector(FAST, port=emu.port)
        assert emu.servo(1).value("torque_enable") == 0


def test_close_with_a_servo_gone_still_turns_the_other_off() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.05)
        emu.servo(2).faults.absent = True  # unplugged mid-session
        ee.close()  # logs, does not raise
        assert emu.servo(1).value("torque_enable") == 0
        assert not ee.bus.is_open


def test_torque_off_after_a_fault_inside_with() -> None:
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        with pytest.raises(ServoFault):
            with DynamixelEndEffector(FAST, port=emu.port) as ee:
                ee.grasp(0.05)
                with emu.lock:
                    emu.servo(2).set_hardware_error(VOLTAGE)  # not in Shutdown's default
                assert emu.servo(2).value("torque_enable") == 1
                ee.set_stroke(0.04)
        assert emu.servo(1).value("torque_enable") == 0
        assert emu.servo(2).value("torque_enable") == 0


def test_unopenable_port_is_named() -> None:
    with pytest.raises(HardwareError, match="/dev/ttyDOESNOTEXIST"):
        DynamixelEndEffector(FAST, port="/dev/ttyDOESNOTEXIST")


def test_servo_rejections_are_translated() -> None:
    with rig() as (_, ee):
        t = ee._latch
        with pytest.raises(HardwareError, match="access error"):
            ee.bus.write(1, t["operating_mode"], 4)  # EEPROM with torque on
        with pytest.raises(HardwareError, match="data limit error"):
            ee.bus.write(1, t["goal_position"], 5000)  # beyond Max Position Limit
        with pytest.raises(HardwareError, match="access error"):
            ee.bus.write(1, t["present_position"], 0)  # read-only
