"""The end-effector 2.0 on Dynamixel servos: M1 latch, M2 spool (thesis §2.2).

`grasp` returns M2 to its rest position while the mesh is open (the free spool
sits at its rest stroke then, so the stroke map holds), engages the latch with
M1, and winds M2 to the stroke; `set_stroke` winds or unwinds with the latch
engaged; both confirm the stroke from the encoder (M2's present position
through the stroke map). `place` unwinds M2 slowly to the rest stroke; `throw`
turns M1 to open the mesh at once, after checking that the latch is engaged and
the measured stroke agrees with the command. Torque goes off on `close`, which
`with` calls even when the block raises.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from cell.endeffector.base import EndEffector, EndEffectorStatus
from cell.endeffector.dynamixel.bus import DynamixelBus, RegisterBlock
from cell.endeffector.dynamixel.config import DynamixelConfig, LatchConfig, SpoolConfig
from cell.endeffector.dynamixel.registers import (
    MODELS,
    OPERATING_MODE_EXTENDED_POSITION,
    OPERATING_MODE_POSITION,
    TICKS_PER_REV,
    VELOCITY_UNIT_RPM,
    ControlTable,
)
from cell.errors import HardwareError, InvalidParameter, SafetyRefusal

__all__ = ["DynamixelEndEffector"]

log = logging.getLogger(__name__)

_SETTLE_TICKS = 3  # a move is done this near its goal [ticks]


class DynamixelEndEffector(EndEffector):
    """The throwing end-effector driven through a Dynamixel Protocol 2.0 bus.

    Args:
        config: the hardware description (see `load_config`).
        port: serial port overriding `config.port`.
        connect: open the port and set the servos up now.
        on_close: called after the port is closed (e.g. to stop an emulated bus).

    Raises:
        HardwareError: the port cannot be opened, a servo does not answer, or a
            servo is not the model the configuration names.
    """

    def __init__(
        self,
        config: DynamixelConfig,
        *,
        port: str | None = None,
        connect: bool = True,
        on_close: Callable[[], None] | None = None,
    ) -> None:
        self.config = config if port is None else config.with_port(port)
        c = self.config
        self.bus = DynamixelBus(c.port, c.baud_rate, c.retries, c.latency_timer_ms)
        self._latch: ControlTable = MODELS[self.config.latch.model]
        self._spool: ControlTable = MODELS[self.config.spool.model]
        self._on_close = on_close
        self._closed = False
        self._commanded_m: float | None = None  # this process's last stroke command [m]
        if connect:
            self.connect()

    # -- connection
    def connect(self) -> None:
        """Open the port, check both servos' models, set their modes, torque on."""
        self.bus.open()
        try:
            cfg = self.config
            for role, c, table in (
                ("M1 latch", cfg.latch, self._latch),
                ("M2 spool", cfg.spool, self._spool),
            ):
                model = self.bus.ping(c.id)
                if model != table.model_number:
                    names = [m.model for m in MODELS.values() if m.model_number == model]
                    raise HardwareError(
                        f"servo ID {c.id} ({role}) is model number {model} "
                        f"({names[0] if names else 'not supported'}), but "
                        f"{cfg.source or 'the configuration'} says {c.model} "
                        f"({table.model_number}): check the IDs and models"
                    )
            self._setup(cfg.latch, self._latch, OPERATING_MODE_POSITION)
            self._setup(cfg.spool, self._spool, OPERATING_MODE_EXTENDED_POSITION, keep_goal=True)
            self._write(cfg.spool, "profile_acceleration", cfg.spool.profile_acceleration)
        except BaseException:
            self.close()
            raise

    def _setup(
        self,
        c: LatchConfig | SpoolConfig,
        table: ControlTable,
        mode: int,
        *,
        keep_goal: bool = False,
    ) -> None:
        """Set the operating mode and bring torque on where the servo is.

        With `keep_goal` (the spool), the goal position register is the commanded stroke, kept
        by the servo across processes and torque-off. A spool found with torque off and away
        from its goal was moved by hand: it is left with torque off and its goal untouched, so
        a throw stays refused (the stored energy is not what was commanded) until a grasp or
        set_stroke winds it again.
        """
        bus = self.bus
        if bus.read(c.id, table["operating_mode"]) != mode:
            bus.write(c.id, table["torque_enable"], 0)  # EEPROM: writable with torque off
            bus.write(c.id, table["operating_mode"], mode)
            keep_goal = False  # a goal from another mode means nothing
        if bus.read(c.id, table["torque_enable"]):
            return
        present = bus.read(c.id, table["present_position"])
        if keep_goal:
            goal = bus.read(c.id, table["goal_position"])
            off_m = abs(self.config.ticks_to_stroke(goal) - self.config.ticks_to_stroke(present))
            if off_m > self.config.stroke.tolerance_m:
                log.warning(
                    "servo ID %d was moved %.4f m from its goal with torque off: left off "
                    "until the stroke is set again",
                    c.id,
                    off_m,
                )
                return
        bus.write(c.id, table["goal_position"], present)  # hold where it is: no jump
        bus.write(c.id, table["torque_enable"], 1)

    def close(self) -> None:
        """Torque off on both servos, then close the port (idempotent, never raises
        for a servo that cannot be reached: it logs a warning)."""
        if self._closed:
            return
        self._closed = True
        try:
            if self.bus.is_open:
                ids = {self.config.latch.id: 0, self.config.spool.id: 0}
                try:  # broadcast first: reaches every servo even if one misbehaves
                    self.bus.sync_write(self._latch["torque_enable"], ids)
                except HardwareError as exc:
                    log.warning("torque off (broadcast): %s", exc)
                for dxl_id in ids:
                    try:  # then once more with an acknowledgement
                        self.bus.write(dxl_id, self._latch["torque_enable"], 0)
                    except HardwareError as exc:
                        log.warning("torque off, servo ID %d: %s", dxl_id, exc)
        finally:
            self.bus.close()
            if self._on_close is not None:
                self._on_close()

    # -- low level
    def _write(self, c: LatchConfig | SpoolConfig, name: str, value: int) -> None:
        table = self._latch if c is self.config.latch else self._spool
        self.bus.write(c.id, table[name], value)

    def _read(self, c: LatchConfig | SpoolConfig, name: str) -> int:
        table = self._latch if c is self.config.latch else self._spool
        return self.bus.read(c.id, table[name])

    def _move(self, c: LatchConfig | SpoolConfig, goal: int, profile_velocity: int) -> int:
        """Set the profile velocity, write a goal position, and wait until the goal
        is reached, the move stalls, or it overruns its expected duration.

        Returns:
            The last present position [ticks]; the caller judges it.
        """
        if self._closed:
            raise HardwareError("the end-effector is closed: create a new one to move it")
        timing = self.config.timing
        table = self._latch if c is self.config.latch else self._spool
        self._write(c, "profile_velocity", profile_velocity)
        if not self._read(c, "torque_enable"):  # the spool left off at connect (moved by hand)
            self._write(c, "goal_position", self._read(c, "present_position"))
            self._write(c, "torque_enable", 1)  # holds where it is, then moves to the goal
        self._write(c, "goal_position", goal)
        start = self._read(c, "present_position")  # has barely moved yet
        # slowest the servo should go: the profile velocity, or its velocity limit if 0
        units = profile_velocity or table["velocity_limit"].default
        speed = units * VELOCITY_UNIT_RPM / 60.0 * TICKS_PER_REV  # [ticks/s]
        deadline = 1.5 * abs(goal - start) / speed + timing.move_margin_s  # [s]
        t0 = last_change = time.monotonic()
        pos = last_pos = start
        while abs(pos - goal) > _SETTLE_TICKS:
            now = time.monotonic()
            if now - last_change > timing.stall_timeout_s or now - t0 > deadline:
                break
            time.sleep(timing.poll_period_s)
            pos = self._read(c, "present_position")
            if abs(pos - last_pos) > 1:
                last_pos, last_change = pos, time.monotonic()
        return pos

    def _latch_engaged(self) -> bool:
        c = self.config.latch
        pos = self._read(c, "present_position")
        return bool(self._read(c, "torque_enable")) and abs(pos - c.engaged_position) <= c.tolerance

    def _check_stroke(self, stroke_m: float) -> None:
        s = self.config.stroke
        if not (s.min_m <= stroke_m <= s.max_m):  # also rejects NaN
            raise InvalidParameter(
                f"stroke {stroke_m} m is outside the end-effector's range "
                f"[{s.min_m}, {s.max_m}] m ({self.config.source or 'configuration'}: stroke)"
            )

    def _wind_to(self, stroke_m: float, profile_velocity: int) -> None:
        cfg = self.config
        self._commanded_m = stroke_m
        self._move(cfg.spool, cfg.stroke_to_ticks(stroke_m), profile_velocity)
        measured = self._encoder_stroke()
        if abs(measured - stroke_m) > cfg.stroke.tolerance_m:
            raise HardwareError(
                f"stroke not reached: commanded {stroke_m:.4f} m, the encoder reads "
                f"{measured:.4f} m (tolerance {cfg.stroke.tolerance_m} m): check the spool "
                f"and thread for a jam, and M2 (ID {cfg.spool.id}) for its load"
            )

    def _need_latch(self, action: str) -> None:
        c = self.config.latch
        if not self._latch_engaged():
            pos = self._read(c, "present_position")
            raise SafetyRefusal(
                f"{action} refused: the latch is not confirmed engaged (M1 ID {c.id} at {pos} "
                f"ticks, engaged is {c.engaged_position} ± {c.tolerance}){'; grasp first' if action != 'throw' else ''}"
            )

    # -- the interface
    def grasp(self, stroke_m: float) -> None:
        """Engage the latch and wind the spool to stroke L_s [m].

        Raises:
            InvalidParameter: the stroke is outside the configured range.
            HardwareError: the latch did not engage or the stroke was not reached
                (plus the bus errors: NoReply, CorruptReply, ServoFault).
        """
        self._check_stroke(stroke_m)
        cfg = self.config
        if not self._latch_engaged():
            # mesh open: the free spool is at rest, so bring M2 to the rest position first
            self._move(cfg.spool, cfg.spool.rest_position, cfg.spool.profile_velocity)
            pos = self._move(cfg.latch, cfg.latch.engaged_position, cfg.latch.profile_velocity)
            if abs(pos - cfg.latch.engaged_position) > cfg.latch.tolerance:
                raise HardwareError(
                    f"latch did not engage: M1 (ID {cfg.latch.id}) stopped at {pos} ticks, "
                    f"engaged is {cfg.latch.engaged_position} ± {cfg.latch.tolerance}: check "
                    "the latch lever and gears for an obstruction"
                )
        self._wind_to(stroke_m, cfg.spool.profile_velocity)

    def set_stroke(self, stroke_m: float) -> None:
        """Wind or unwind to stroke L_s [m]; the latch must be engaged.

        Raises:
            InvalidParameter: the stroke is outside the configured range.
            SafetyRefusal: the latch is not engaged.
            HardwareError: the stroke was not reached, or a bus error.
        """
        self._check_stroke(stroke_m)
        self._need_latch("set_stroke")
        self._wind_to(stroke_m, self.config.spool.profile_velocity)

    def place(self) -> None:
        """Unwind the spool slowly to the rest stroke: the band lets go gently.

        Raises:
            HardwareError: the rest stroke was not reached, or a bus error.
        """
        cfg = self.config
        if not self._latch_engaged():
            log.info("place: latch open, the spool is already free at rest")
            return
        self._wind_to(cfg.stroke.rest_m, cfg.spool.place_profile_velocity)

    def throw(self) -> None:
        """Open the latch at once: the band releases its stored energy.

        Raises:
            SafetyRefusal: the latch is not confirmed engaged, no stroke was
                commanded, or the measured stroke disagrees with the command.
            HardwareError: the latch did not open, or a bus error.
        """
        cfg = self.config
        self._need_latch("throw")
        measured = self._encoder_stroke()
        # the servo's goal register is the command across processes; this process's own
        # last command, when it made one, must agree too (a slip that moved the goal)
        commanded = self._goal_stroke()
        if self._commanded_m is not None and abs(commanded - self._commanded_m) > 1e-9:
            commanded = self._commanded_m
        if not self._read(cfg.spool, "torque_enable"):
            raise SafetyRefusal(
                f"throw refused: the spool (M2 ID {cfg.spool.id}) has torque off: it was moved "
                "away from its commanded stroke while off; set the stroke again"
            )
        if abs(measured - commanded) > cfg.stroke.tolerance_m:
            raise SafetyRefusal(
                f"throw refused: the encoder reads {measured:.4f} m but {commanded:.4f} m "
                f"was commanded (tolerance {cfg.stroke.tolerance_m} m): the stored energy is "
                "not what the plan assumed; check the spool and thread, then set the stroke again"
            )
        pos = self._move(cfg.latch, cfg.latch.released_position, cfg.latch.throw_profile_velocity)
        self._commanded_m = None
        if abs(pos - cfg.latch.released_position) > cfg.latch.tolerance:
            raise HardwareError(
                f"latch did not open: M1 (ID {cfg.latch.id}) stopped at {pos} ticks, released "
                f"is {cfg.latch.released_position}: check the latch lever for an obstruction"
            )

    def stroke(self) -> float:
        """The stroke L_s [m]: M2's encoder through the stroke map while the latch is
        engaged; with the mesh open the spool is free and the band holds it at rest."""
        if not self._latch_engaged():
            return self.config.stroke.rest_m
        return self._encoder_stroke()

    def _goal_stroke(self) -> float:
        """The stroke the spool servo is commanded to hold: its goal position register."""
        return self.config.ticks_to_stroke(self._read(self.config.spool, "goal_position"))

    def _encoder_stroke(self) -> float:
        return self.config.ticks_to_stroke(self._read(self.config.spool, "present_position"))

    def status(self) -> EndEffectorStatus:
        """Both servos' state in one SYNC READ (raises ServoFault if one reports an error)."""
        cfg, t = self.config, self._spool
        blocks = self.bus.sync_read(
            [cfg.latch.id, cfg.spool.id], t["torque_enable"], t["present_temperature"]
        )
        m1, m2 = blocks[cfg.latch.id], blocks[cfg.spool.id]
        latch_pos = m1[self._latch["present_position"]]
        engaged = bool(m1[self._latch["torque_enable"]]) and (
            abs(latch_pos - cfg.latch.engaged_position) <= cfg.latch.tolerance
        )
        stroke_m = cfg.ticks_to_stroke(m2[t["present_position"]]) if engaged else cfg.stroke.rest_m
        detail = "; ".join(
            self._describe(name, c.id, table, blk)
            for name, c, table, blk in (
                ("M1 latch", cfg.latch, self._latch, m1),
                ("M2 spool", cfg.spool, t, m2),
            )
        )
        # holding is read from the servos, not remembered: another process may have thrown
        holding = engaged and abs(stroke_m - cfg.stroke.rest_m) > cfg.stroke.tolerance_m
        return EndEffectorStatus(stroke_m, engaged, holding, detail)

    @staticmethod
    def _describe(name: str, dxl_id: int, table: ControlTable, blk: RegisterBlock) -> str:
        torque = "on" if blk[table["torque_enable"]] else "off"
        return (
            f"{name} ID {dxl_id} ({table.model}): {blk[table['present_position']]} ticks, "
            f"torque {torque}, {blk[table['present_temperature']]} °C, "
            f"{blk[table['present_input_voltage']] / 10:.1f} V"
        )
