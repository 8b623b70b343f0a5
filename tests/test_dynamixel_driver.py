"""The Dynamixel end-effector through dynamixel-sdk against the emulated bus on a pty.

The stroke the driver reads from M2's encoder is compared with the emulated
spool's real stroke, which the plant keeps on its own.
"""

from __future__ import annotations

import math

import pytest

from cell.endeffector.dynamixel import DynamixelEndEffector, EmulatedBus
from cell.endeffector.dynamixel.config import DynamixelConfig, LatchConfig
from cell.errors import HardwareError, InvalidParameter, SafetyRefusal
from tests.dynamixel_fixtures import FAST, TIME_SCALE, rig

TOL = FAST.stroke.tolerance_m
TICK_M = FAST.spool.radius_m * 2 * math.pi / 4096  # stroke per encoder tick [m]


def test_stroke_map_closed_form() -> None:
    # 0.08 m of thread on a 10 mm drum is 8 rad = 8 * 4096 / 2π ticks
    assert FAST.stroke_to_ticks(0.03) == round(8 * 4096 / (2 * math.pi))
    assert FAST.stroke_to_ticks(0.11) == 0
    for s in (0.03, 0.05, 0.0777, 0.11):
        assert FAST.ticks_to_stroke(FAST.stroke_to_ticks(s)) == pytest.approx(s, abs=TICK_M)


def test_ping_reports_the_configured_models() -> None:
    with rig() as (_, ee):
        assert ee.bus.ping(1) == 1060
        assert ee.bus.ping(2) == 1020


def test_connect_sets_modes_and_torque() -> None:
    with rig() as (emu, _):
        assert emu.servo(1).value("operating_mode") == 3
        assert emu.servo(2).value("operating_mode") == 4
        assert emu.servo(1).value("torque_enable") == 1
        assert emu.servo(2).value("torque_enable") == 1


def test_grasp_winds_to_the_stroke_confirmed_by_the_encoder() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.05)
        st = ee.status()
        assert st.latch_engaged and st.holding
        assert st.stroke_m == pytest.approx(0.05, abs=TICK_M)
        assert ee.stroke() == pytest.approx(emu.true_stroke_m(), abs=1e-9)
        assert emu.servo(1).value("present_position") == FAST.latch.engaged_position


@pytest.mark.parametrize("target", [0.03, 0.042, 0.09, 0.11])
def test_set_stroke_both_ways(target: float) -> None:
    with rig() as (emu, ee):
        ee.grasp(0.07)
        ee.set_stroke(target)
        assert ee.stroke() == pytest.approx(target, abs=TICK_M)
        assert emu.true_stroke_m() == pytest.approx(target, abs=TICK_M)


def test_place_unwinds_slowly_to_rest() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.04)
        ee.place()
        # within an encoder tick of rest: what the driver can see (a loaded machine's
        # polling stopped 13 µm short, under a tick, of the exact rest)
        assert emu.true_stroke_m() == pytest.approx(FAST.stroke.rest_m, abs=TICK_M)
        assert not ee.status().holding
        goal, pv = emu.servo(2).goal_log[-1]
        assert goal == FAST.spool.rest_position
        assert pv == FAST.spool.place_profile_velocity  # the slow unwinding speed
        assert pv < emu.servo(2).value("velocity_limit")


def test_throw_opens_the_latch_at_once() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.045)
        ee.throw()
        goal, pv = emu.servo(1).goal_log[-1]
        assert goal == FAST.latch.released_position and pv == 0  # fastest
        assert emu.true_stroke_m() == pytest.approx(FAST.stroke.rest_m)  # band released
        st = ee.status()
        assert not st.latch_engaged and not st.holding
        assert st.stroke_m == FAST.stroke.rest_m


def test_grasp_after_throw_rehomes_the_spool() -> None:
    with rig() as (emu, ee):
        for s in (0.05, 0.08, 0.035):
            ee.grasp(s)
            assert emu.true_stroke_m() == pytest.approx(s, abs=TICK_M)
            ee.throw()
            assert emu.true_stroke_m() == pytest.approx(FAST.stroke.rest_m)


def test_throw_refused_when_latch_not_engaged() -> None:
    with rig() as (emu, ee):
        n = len(emu.servo(1).goal_log)
        with pytest.raises(SafetyRefusal, match="latch is not confirmed engaged"):
            ee.throw()
        assert len(emu.servo(1).goal_log) == n  # M1 was not moved


def test_throw_refused_when_latch_pushed_out_of_position() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.05)
        with emu.lock:  # something knocks the lever 60 ticks off
            emu.servo(1).position += 60
            emu.servo(1).set_value("goal_position", FAST.latch.engaged_position + 60)
        with pytest.raises(SafetyRefusal, match="latch"):
            ee.throw()
        assert emu.true_stroke_m() == pytest.approx(0.05, abs=TICK_M)


def test_throw_refused_when_stroke_disagrees_with_command() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.06)
        with emu.lock:  # M2 dragged 0.01 m off its goal (e.g. thread slipped on the drum)
            off = FAST.stroke_to_ticks(0.07)
            emu.servo(2).position = off
            emu.servo(2).set_value("goal_position", off)
        with pytest.raises(SafetyRefusal, match="commanded"):
            ee.throw()
        assert emu.servo(1).value("goal_position") == FAST.latch.engaged_position


def test_set_stroke_refused_without_grasp() -> None:
    with rig() as (emu, ee):
        n = len(emu.servo(2).goal_log)
        with pytest.raises(SafetyRefusal, match="grasp first"):
            ee.set_stroke(0.05)
        assert len(emu.servo(2).goal_log) == n


@pytest.mark.parametrize("bad", [0.0299, 0.1101, -1.0, math.nan, math.inf])
def test_stroke_never_leaves_its_range(bad: float) -> None:
    with rig() as (emu, ee):
        with pytest.raises(InvalidParameter, match=r"\[0.03, 0.11\]"):
            ee.grasp(bad)
        ee.grasp(0.05)
        with pytest.raises(InvalidParameter):
            ee.set_stroke(bad)
        goals = [FAST.ticks_to_stroke(g) for g, _ in emu.servo(2).goal_log]
        assert all(0.03 - 1e-9 <= s <= 0.11 + 1e-9 for s in goals)


def test_jammed_spool_is_reported_and_blocks_the_throw() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.08)
        emu.servo(2).set_jam(FAST.stroke_to_ticks(0.06))
        with pytest.raises(HardwareError, match="stroke not reached") as exc:
            ee.set_stroke(0.04)
        assert "jam" in str(exc.value)
        with pytest.raises(SafetyRefusal, match="0.0400 m was commanded"):
            ee.throw()


def test_jammed_latch_is_reported() -> None:
    with rig() as (emu, ee):
        emu.servo(1).set_jam(2300)
        with pytest.raises(HardwareError, match="latch did not engage"):
            ee.grasp(0.05)


def test_torque_off_after_close() -> None:
    with rig() as (emu, ee):
        ee.grasp(0.05)
        ee.close()
        assert emu.servo(1).value("torque_enable") == 0
        assert emu.servo(2).value("torque_enable") == 0
        assert not ee.bus.is_open
        ee.close()  # idempotent
        with pytest.raises(HardwareError):
            ee.stroke()


def test_torque_off_after_an_exception_in_with() -> None:
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        with pytest.raises(ZeroDivisionError):
            with DynamixelEndEffector(FAST, port=emu.port) as ee:
                ee.grasp(0.05)
                assert emu.servo(2).value("torque_enable") == 1
                _ = 1 / 0
        assert emu.servo(1).value("torque_enable") == 0
        assert emu.servo(2).value("torque_enable") == 0


def test_reconnect_adopts_an_engaged_latch() -> None:
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        with DynamixelEndEffector(FAST, port=emu.port) as ee:
            ee.grasp(0.05)
        # torque came off; the servos hold still in the emulator: a new session throws
        with DynamixelEndEffector(FAST, port=emu.port) as ee:
            assert ee.status().latch_engaged
            ee.throw()
        assert emu.true_stroke_m() == pytest.approx(FAST.stroke.rest_m)


def test_wrong_model_is_named() -> None:
    wrong = DynamixelConfig(
        latch=LatchConfig(id=1, model="xm430-w350"), spool=FAST.spool, timing=FAST.timing
    )
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        with pytest.raises(HardwareError, match=r"ID 1 .* model number 1060 \(xl430-w250\)"):
            DynamixelEndEffector(wrong, port=emu.port)


def test_byte_stuffing_through_the_sdk() -> None:
    # goal -131073 = bytes FF FF FD FF: the SDK stuffs it, the emulator unstuffs it,
    # and the read-back status packet is stuffed the other way
    with rig() as (emu, ee):
        reg = ee._spool["goal_position"]
        ee.bus.write(2, reg, -131073)
        assert emu.servo(2).value("goal_position") == -131073
        assert ee.bus.read(2, reg) == -131073


def test_status_reads_both_servos() -> None:
    with rig() as (emu, ee):
        with emu.lock:
            emu.servo(2).set_value("present_temperature", 47)
        st = ee.status()
        assert "M2 spool ID 2 (xm430-w350)" in st.detail and "47 °C" in st.detail
        assert "12.0 V" in st.detail


def test_a_spool_moved_with_torque_off_between_sessions_refuses_the_throw() -> None:
    """The commanded stroke lives in the servo's goal register, not in a process: a new session
    that finds the spool moved by hand (torque off) does not adopt the new position."""
    with EmulatedBus.from_config(FAST, time_scale=TIME_SCALE) as emu:
        with DynamixelEndEffector(FAST, port=emu.port) as ee:
            ee.grasp(0.05)
        # torque is off now; someone turns the spool by hand to 0.035 m (more energy)
        with emu.lock:
            emu.servo(2).position = FAST.stroke_to_ticks(0.035)
        with DynamixelEndEffector(FAST, port=emu.port) as ee:
            st = ee.status()
            assert st.latch_engaged and st.holding  # read from the servos, not remembered
            assert emu.servo(2).value("torque_enable") == 0  # left off: not adopted
            with pytest.raises(SafetyRefusal, match="torque off"):
                ee.throw()
            assert emu.servo(1).value("goal_position") == FAST.latch.engaged_position
            ee.set_stroke(0.05)  # winding it again makes the throw good
            ee.throw()
        assert emu.true_stroke_m() == pytest.approx(FAST.stroke.rest_m)
