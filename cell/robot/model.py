"""The arm with the end-effector as a Pinocchio model, reduced to the arm joints.

The world frame W of this module is the arm's base frame (z up, origin at the base link);
a scene that places the arm elsewhere transforms poses into it first.
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput, InvalidParameter, MissingDependency
from cell.frames import axis_frame
from cell.robot.composite import composite_urdf
from cell.robot.kept import Kept
from cell.robot.limits import JointLimits
from cell.robot.mount import MountSpec, load_mount
from cell.robot.paths import example_robot_data_dir, robots_dir

__all__ = [
    "EE_JOINTS",
    "TCP_FRAME",
    "Robot",
    "axis_frame",
    "load_robot",
]

TCP_FRAME = "ee_tcp"
"""The grip centre frame; its +z axis is the throw axis."""

EE_JOINTS = ("ee_finger_left_joint", "ee_finger_right_joint", "ee_band_joint")
"""The end-effector's moving joints (locked in the arm model)."""


class Robot:
    """An arm with the throwing end-effector: Pinocchio model of the arm joints, limits, home.

    Attributes:
        name: robot name.
        spec: the MountSpec (robots/<mount>/mount.yaml).
        urdf: the composite URDF file.
        model: pinocchio.Model reduced to the arm joints (end-effector joints locked).
        data: a pinocchio.Data for `model`, scratch space every kinematics call fills anew
            before reading it (not thread-safe; one Robot per thread).
        tcp_frame: frame index of `ee_tcp` in `model`.
        limits: JointLimits of the arm joints (read-only arrays).
        home: home configuration [rad], shape (n,) (read-only).
    """

    def __init__(self, spec: MountSpec) -> None:
        try:
            import pinocchio as pin
        except ImportError as exc:  # pragma: no cover - pin is a core dependency
            raise MissingDependency("Pinocchio is missing: pip install pin") from exc
        self.name = spec.name
        self.spec = spec
        self.urdf = composite_urdf(spec.path)
        full = pin.buildModelFromUrdf(str(self.urdf))
        names = list(full.names)
        missing = [j for j in spec.arm_joints if j not in names]
        if missing:
            raise InvalidInput(f"{self.urdf}: arm joint(s) {missing} not in the description")
        lock = [full.getJointId(n) for n in names[1:] if n not in spec.arm_joints]
        q_ref = pin.neutral(full)  # every joint not planned at zero, but those held
        for name, value in spec.held_joints:
            jm = full.joints[full.getJointId(name)]
            if jm.nq == 2:  # a continuous joint: (cos θ, sin θ)
                q_ref[jm.idx_q : jm.idx_q + 2] = (math.cos(value), math.sin(value))
            else:
                q_ref[jm.idx_q] = value
        self.model: Any = pin.buildReducedModel(full, lock, q_ref) if lock else full
        self.data: Any = self.model.createData()
        if not self.model.existFrame(TCP_FRAME):
            raise InvalidInput(f"{self.urdf}: no frame {TCP_FRAME!r}")
        self.tcp_frame = int(self.model.getFrameId(TCP_FRAME))
        multi = [
            n
            for n, jm in zip(self.model.names[1:], self.model.joints[1:], strict=True)
            if jm.nq != 1
        ]
        if list(self.model.names)[1:] != list(spec.arm_joints) or multi:
            raise InvalidInput(
                f"{self.urdf}: the reduced model's joints {list(self.model.names)[1:]} are not "
                f"the mount's arm_joints {list(spec.arm_joints)} in order, each with one "
                f"position value (revolute or prismatic; not so: {multi or 'none'})"
            )
        acc = np.array(spec.acceleration_limits, dtype=float)
        jerk = np.array(spec.jerk_limits, dtype=float)
        self.limits = JointLimits(
            lower=np.array(self.model.lowerPositionLimit, dtype=float),
            upper=np.array(self.model.upperPositionLimit, dtype=float),
            velocity=np.array(self.model.velocityLimit, dtype=float),
            acceleration=acc,
            jerk=jerk,
        )
        self.home = np.array(spec.home, dtype=float)
        try:
            self.limits.check_position(self.home, name="home")
        except InvalidInput as exc:  # the mount file's field, named (docs/arms.md)
            raise InvalidParameter(f"{spec.path}: field 'home': {exc}") from None
        # one Robot per process is shared by every run in it (`load_robot`): its arrays are
        # read-only, so no run can change what a later one plans with
        for a in (self.home, *vars(self.limits).values()):
            a.setflags(write=False)
        # `tcp_positions`' answers by the configurations' bytes (bounded: cleared when full)
        self._positions_kept: Kept[np.ndarray] = Kept(64)

    @property
    def dof(self) -> int:
        """Number of arm joints."""
        return int(self.model.nq)

    def tcp_pose(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics of the grip centre.

        Args:
            q: arm configuration [rad], shape (n,).

        Returns:
            (position [m] in W, shape (3,); rotation of ee_tcp in W, shape (3, 3)).
        """
        import pinocchio as pin

        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        oMf = self.data.oMf[self.tcp_frame]
        return np.array(oMf.translation), np.array(oMf.rotation)

    def tcp_positions(self, qs: np.ndarray) -> np.ndarray:
        """The grip centre's position [m, W] at each configuration of qs [rad], shape
        (k, n) → (k, 3): `tcp_pose`'s positions, without copying the rotations. The same
        configurations' answer is made once (`_positions_kept`, by their bytes; a
        read-only array): the arm's route checks ask again for the same configurations,
        189 of tune layout 0's 1,215 calls (counted on `4645969`)."""
        qs = np.asarray(qs, dtype=float)
        key = repr(qs.shape).encode() + qs.tobytes()
        return self._positions_kept.get(key, lambda: self._tcp_positions(qs))

    def _tcp_positions(self, qs: np.ndarray) -> np.ndarray:
        """`tcp_positions` worked out, read-only."""
        import pinocchio as pin

        out = np.empty((len(qs), 3))
        model, data, fid = self.model, self.data, self.tcp_frame
        # the joints' placements, then the grip's frame alone: the same products as
        # `framesForwardKinematics`, which places every frame of the model (28 on the
        # Panda), bit for bit (2,000 random configurations of the Panda and the UR5), in
        # two thirds of its time
        kinematics, place = pin.forwardKinematics, pin.updateFramePlacement
        for i, q in enumerate(qs):
            kinematics(model, data, q)
            out[i] = place(model, data, fid).translation
        out.setflags(write=False)  # kept and shared (`tcp_positions`)
        return out

    def throw_axis(self, q: np.ndarray) -> np.ndarray:
        """The throw axis u (ee_tcp's +z) in W at configuration q, shape (3,)."""
        return self.tcp_pose(q)[1][:, 2]

    def tcp_jacobian(self, q: np.ndarray) -> np.ndarray:
        """The grip centre's Jacobian, world-aligned (linear rows first), shape (6, n).

        Args:
            q: arm configuration [rad], shape (n,).

        Returns:
            J with [v; ω] = J q̇, v the TCP velocity [m/s] and ω the angular velocity [rad/s]
            of ee_tcp, both in W.
        """
        import pinocchio as pin

        q = np.asarray(q, dtype=float)
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        return np.array(
            pin.getFrameJacobian(
                self.model, self.data, self.tcp_frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            )
        )

    def random_configuration(self, rng: np.random.Generator, n: int = 1) -> np.ndarray:
        """Uniform random configurations within the joint limits (±π for wider ranges).

        Args:
            rng: random generator.
            n: how many.

        Returns:
            Array (n, dof) [rad].
        """
        lo = np.maximum(self.limits.lower, -math.pi)
        hi = np.minimum(self.limits.upper, math.pi)
        return rng.uniform(lo, hi, size=(n, self.dof))


@lru_cache(maxsize=8)
def _load(spec: MountSpec, robots: Path, robot_data: Path) -> Robot:
    """The Robot of this mount as described in these folders (`load_robot`): the key is
    the mount's content and where the descriptions are read from, so a run never gets an
    arm read from another mount file or from folders it does not use ($CELL_ROBOTS_DIR,
    $CELL_EXAMPLE_ROBOT_DATA set or changed since)."""
    return Robot(spec)


def load_robot(name: str) -> Robot:
    """The arm with the end-effector, by reference (cached per process, per its mount
    file's content and the folders its description is read from: `cell.robot.paths`).

    Args:
        name: an arm's name under robots/ ("panda", "ur10") or a mount file's path.

    Returns:
        The shared Robot instance of that mount (its `data` is scratch space).

    Raises:
        InvalidInput: unknown robot.
        InvalidParameter: a wrong mount file (naming the file and the field).
        MissingDependency: Pinocchio, example-robot-data or robots/ is missing.
    """
    return _load(load_mount(name), robots_dir(), example_robot_data_dir())
