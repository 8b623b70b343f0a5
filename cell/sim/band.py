"""The band mechanism in the scene: the force law drives the carriage each sub-step.

Before every physics step the band's state is evaluated from the mechanism's
*current* configuration: the carriage position s (the stroke-equivalent L_s
[m], the `ee_band_joint` value) and the measured grip width a (the sum of the
finger openings [m], at least the hoop width d). MODEL.md's law gives

    ΔL(s, a),  f_e(ΔL),  α(s, a),  f_o = 2 f_e cos α,  f_g = f_e sin α

and the mechanism applies f_o along the end-effector's +z to the carriage
(and its reaction to the housing), and closes each finger on the item with
the force f_g (a motor limited to f_g, so the grip is a contact force). The
latch is the spool's position servo: while engaged it holds the carriage at
the commanded stroke against the band; released, the carriage is free and
the band accelerates it, and the item resting on it, until the band goes
slack and the carriage is caught by its end stop. Nothing sets the item's
velocity: it comes out of the contact with the carriage.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.band import band_angle, band_force, band_stretch
from cell.model.ops import Ops
from cell.model.params import EndEffectorParams
from cell.sim.mechanism import EEGeometry

__all__ = ["BandReading", "BandDrive", "BAND_JOINT", "FINGER_LEFT", "FINGER_RIGHT"]

BAND_JOINT = 0  # ee_band_joint
FINGER_LEFT = 1  # ee_finger_left_joint
FINGER_RIGHT = 2  # ee_finger_right_joint
_LATCH_FORCE_N = 400.0  # [N] most the latch/spool can hold
_FINGER_SPEED = 0.3  # [m/s] closing speed of a finger before contact
_JOINTS = (BAND_JOINT, FINGER_LEFT, FINGER_RIGHT)


def _maximum(x: Any, y: Any) -> Any:
    """np.maximum of two scalars: the larger where they differ (what np.maximum returns
    there), else np.maximum itself (NaN, signed zeros)."""
    if x > y:
        return x
    return y if x < y else float(np.maximum(x, y))


# The band law on one configuration per physics step, on Python floats: the model's own
# formulas (cell.model.band) with scalar operations that give the very bits NumPy's gave
# (IEEE sqrt; libm's cos and sin, which NumPy's float64 cos and sin call here, checked on
# 300,000 values; NumPy's own arctan2, which is not libm's), without NumPy's per-call cost.
_SCALAR = Ops(
    sqrt=math.sqrt,
    cos=math.cos,
    sin=math.sin,
    atan2=lambda y, x: float(np.arctan2(y, x)),
    where=lambda c, a, b: a if c else b,
    fmax=_maximum,
)


@dataclass(frozen=True)
class BandReading:
    """The band at one instant, from the mechanism's current configuration.

    Attributes:
        position_m: carriage position s (stroke-equivalent L_s) [m].
        velocity_mps: carriage velocity along +z of the end-effector [m/s].
        width_m: grip width a used by the law (finger opening, ≥ d) [m].
        stretch_m: ΔL [m].
        band_force_n: f_e [N].
        push_n: f_o [N] applied to the carriage.
        grip_n: f_g [N] each finger's closing force.
        latch_force_n: force the latch exerts on the carriage [N] (0 released).
        latched: latch engaged.
    """

    position_m: float
    velocity_mps: float
    width_m: float
    stretch_m: float
    band_force_n: float
    push_n: float
    grip_n: float
    latch_force_n: float
    latched: bool


class BandDrive:
    """Applies the band law, the latch and the finger grip to the end-effector body.

    Args:
        client: a pybullet BulletClient.
        body: the end-effector multibody (joints as in cell.sim.mechanism: DRIVEN_JOINTS).
        ee: the band's parameters (the law the plant obeys).
        geometry: the mechanism's geometry.
    """

    def __init__(self, client: Any, body: int, ee: EndEffectorParams, geometry: EEGeometry) -> None:
        self.client = client
        self.body = body
        self.ee = ee
        self.geometry = geometry
        self.latched = True
        self.fingers_closing = False
        self.stroke_cmd_m = ee.stroke_max
        self.wind_target_m: float | None = None  # spool winding towards it (see `wind`)
        self.open_to_m: float | None = None  # open fingers stop at this opening (None: widest)
        self.wind_speed_mps = 0.0
        # the last motor command sent to each joint, with the step [s] it was sent for
        # (`_motors`)
        self._sent: dict[int, tuple[Any, ...]] = {}
        for j in (FINGER_LEFT, FINGER_RIGHT):
            client.changeDynamics(
                body,
                j,
                lateralFriction=geometry.pad_friction,
                spinningFriction=geometry.pad_spin_friction_m,
            )
        for j in (-1, BAND_JOINT, FINGER_LEFT, FINGER_RIGHT):
            client.changeDynamics(body, j, linearDamping=0.0, angularDamping=0.0)
        gear = client.createConstraint(
            body,
            FINGER_LEFT,
            body,
            FINGER_RIGHT,
            client.JOINT_GEAR,
            [1, 0, 0],
            [0, 0, 0],
            [0, 0, 0],
        )
        # both joint values are openings: equal openings keep the grip centred
        client.changeConstraint(gear, gearRatio=-1, erp=0.2, maxForce=200)

    # -- state ---------------------------------------------------------------
    def position(self) -> float:
        """Carriage position s [m] (the stroke the encoder would read)."""
        return float(self.client.getJointState(self.body, BAND_JOINT)[0])

    def width(self) -> float:
        """Grip width a = sum of the finger openings [m]."""
        cl = self.client
        return float(
            cl.getJointState(self.body, FINGER_LEFT)[0]
            + cl.getJointState(self.body, FINGER_RIGHT)[0]
        )

    def law(self, s: float, a: float) -> tuple[float, float, float, float]:
        """(ΔL, f_e, f_o, f_g) of the law at carriage position s and width a [m, N]."""
        a_eff = max(a, self.ee.d)
        stretch = float(band_stretch(s, a_eff, self.ee, _SCALAR))
        f_e = float(band_force(stretch, self.ee, _SCALAR))
        if f_e == 0.0 and self.ee.L_t - s > 0.0:
            # a slack band (every step of a flight): with the carriage short of the band's
            # origin, 0 <= α < π/2, so cos α > 0 and sin α >= +0, and 2 f_e cos α and
            # f_e sin α are f_e's own zero, sign and all: α is not needed
            return stretch, f_e, f_e, f_e
        alpha = float(band_angle(s, a_eff, self.ee, _SCALAR))
        return stretch, f_e, 2 * f_e * math.cos(alpha), f_e * math.sin(alpha)

    def reading(self) -> BandReading:
        """The band now (law evaluated at the current configuration)."""
        js = self.client.getJointState(self.body, BAND_JOINT)
        s, v = float(js[0]), float(js[1])
        a = self.width()
        stretch, f_e, push, grip = self.law(s, a)
        latch = -float(js[3]) if self.latched else 0.0
        return BandReading(
            position_m=s,
            velocity_mps=v,
            width_m=max(a, self.ee.d),
            stretch_m=stretch,
            band_force_n=f_e,
            push_n=push,
            grip_n=grip,
            latch_force_n=latch,
            latched=self.latched,
        )

    # -- per sub-step ----------------------------------------------------------
    def apply(self, dt_s: float = 0.0) -> None:
        """Apply the band force, the latch and the finger grip for the next physics step
        of dt_s [s] (the spool winds by its speed times dt_s towards a `wind` target)."""
        cl = self.client
        if self.wind_target_m is not None and self.latched:
            ds = self.wind_target_m - self.stroke_cmd_m
            step = self.wind_speed_mps * dt_s
            if abs(ds) <= step:
                self.stroke_cmd_m, self.wind_target_m = self.wind_target_m, None
            else:
                self.stroke_cmd_m += step if ds > 0 else -step
        # the carriage and both fingers in one call (`position`, `width`)
        band, left, right = cl.getJointStates(self.body, _JOINTS)
        _, _, push, grip = self.law(float(band[0]), float(left[0] + right[0]))
        if push > 0:
            cl.applyExternalForce(self.body, BAND_JOINT, [0, 0, push], [0, 0, 0], cl.LINK_FRAME)
            cl.applyExternalForce(self.body, -1, [0, 0, -push], [0, 0, 0], cl.LINK_FRAME)
        self._motors(dt_s, grip)

    def _motors(self, dt_s: float, grip: float) -> None:
        """Command the latch's motor and the fingers' for a physics step of dt_s [s], each
        only when it differs from the last command that joint was sent (`_sent`), sent for
        a step of the same length. Bullet's joint motor keeps what the last command set
        (the targets, the gains, the velocity clamp, and the force times the step, the
        largest impulse): PhysicsServerCommandProcessor's processSendDesiredStateCommand
        sets nothing else, and no physics step changes it; only this class commands these
        joints. A command sent again would set the same bits: skipping it changes no
        number. Each float compared with its sign (a grip of -0.0 is sent as such)."""
        cl, body, sent = self.client, self.body, self._sent
        if self.latched:
            x = self.stroke_cmd_m
            key: tuple[Any, ...] = ("latch", dt_s, x, math.copysign(1.0, x))
            if sent.get(BAND_JOINT) != key:
                cl.setJointMotorControl2(
                    body,
                    BAND_JOINT,
                    cl.POSITION_CONTROL,
                    targetPosition=x,
                    force=_LATCH_FORCE_N,
                    positionGain=1.0,
                    velocityGain=1.0,
                )
                sent[BAND_JOINT] = key
        elif sent.get(BAND_JOINT) != ("free", dt_s):
            cl.setJointMotorControl2(
                body, BAND_JOINT, cl.VELOCITY_CONTROL, targetVelocity=0, force=0
            )
            sent[BAND_JOINT] = ("free", dt_s)
        if self.fingers_closing:
            key = ("close", dt_s, grip, math.copysign(1.0, grip))
        elif self.open_to_m is None:
            key = ("open", dt_s)
        else:
            key = ("open_to", dt_s, self.open_to_m, math.copysign(1.0, self.open_to_m))
        if sent.get(FINGER_LEFT) == key:  # both fingers are always sent the same command
            return
        for j in (FINGER_LEFT, FINGER_RIGHT):
            if self.fingers_closing:
                cl.setJointMotorControl2(
                    body, j, cl.VELOCITY_CONTROL, targetVelocity=-_FINGER_SPEED, force=grip
                )
            elif self.open_to_m is None:
                cl.setJointMotorControl2(
                    body, j, cl.VELOCITY_CONTROL, targetVelocity=_FINGER_SPEED, force=2.0
                )
            else:
                cl.setJointMotorControl2(
                    body,
                    j,
                    cl.POSITION_CONTROL,
                    targetPosition=self.open_to_m,
                    force=2.0,
                    maxVelocity=_FINGER_SPEED,
                )
        sent[FINGER_LEFT] = key

    # -- commands --------------------------------------------------------------
    def wind(self, stroke_m: float, speed_mps: float) -> None:
        """Wind (or unwind) the spool to a stroke [m] at a speed [m/s] over the next
        physics steps, whatever else moves meanwhile (the arm): the latch is engaged
        first, holding the carriage where it is."""
        if not self.latched:
            self.stroke_cmd_m = self.position()
            self.latched = True
        self.wind_target_m = float(stroke_m)
        self.wind_speed_mps = float(speed_mps)

    def winding(self) -> bool:
        """The spool is still on its way to a `wind` target."""
        return self.wind_target_m is not None

    def reset(self, stroke_m: float, opening_m: float) -> None:
        """Put the carriage at a stroke and the fingers at an opening (no item), latched."""
        cl = self.client
        cl.resetJointState(self.body, BAND_JOINT, stroke_m, 0.0)
        for j in (FINGER_LEFT, FINGER_RIGHT):
            cl.resetJointState(self.body, j, opening_m, 0.0)
        self.stroke_cmd_m = stroke_m
        self.wind_target_m = None
        self.open_to_m = None
        self.latched = True
