"""The moving-base platform in PyBullet: the end-effector carried along a base's drive.

`MovingBaseScene` is the cell without an arm whose end-effector mount follows
a mobile base: the base's ruckig drive (cell.platforms.mobile.BaseTrajectory)
gives the grip centre's path; each physics step moves the end-effector's
mount target to the pose that keeps the gripped item's centre on that path
with the throw axis fixed. Past the drive's end the base keeps its release
velocity (the release happens while it moves). The item gets its velocity
from the grip's contacts, as on a real base; the launch adds the band's push.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.errors import InvalidInput
from cell.model.objects import ObjectParams
from cell.platforms.mobile import BaseTrajectory
from cell.sim.frames import ee_pose_for_item_centre
from cell.sim.scene import CellScene

__all__ = ["MovingBaseScene"]


class MovingBaseScene(CellScene):
    """The cell without an arm, the end-effector on a mobile base.

    Args:
        **scene: CellScene's keywords (bins, pick_station_xy, dt_s …); robot is None.
    """

    def __init__(self, **scene: Any) -> None:
        scene.pop("robot", None)
        super().__init__(robot=None, **scene)
        self._drive: BaseTrajectory | None = None
        self._pending: BaseTrajectory | None = None
        self._t_start = 0.0
        self._offset = np.zeros(3)
        self._orn: list[float] = [0.0, 0.0, 0.0, 1.0]

    def start_drive(
        self,
        drive: BaseTrajectory,
        elevation: float,
        azimuth: float,
        stroke_m: float,
        obj: ObjectParams,
        roll: float = 0.0,
    ) -> None:
        """Put the end-effector at the drive's start (teleport); `drive_to_release` drives it.

        Args:
            drive: the base's drive; its positions are the gripped item's centre [m, W].
            elevation, azimuth, roll: the throw axis, fixed during the drive [rad].
            stroke_m: the stroke the item will be gripped at [m].
            obj: the item (its size sets where E sits behind its centre).
        """
        origin, self._orn = ee_pose_for_item_centre(
            (0, 0, 0), elevation, azimuth, stroke_m, obj, roll
        )
        self._offset = np.asarray(origin, float)  # E from the item's centre [m, W]
        p0, _, _ = drive.sample(0.0)
        self.hold_ee((p0 + self._offset).tolist(), self._orn, teleport=True)
        self._pending = drive

    def drive_to_release(self) -> None:
        """Drive from the start (at rest) and step until the base reaches the release state.

        The mount keeps following the drive (at the release velocity past its
        end) until `stop_drive`.

        Raises:
            InvalidInput: no drive started.
        """
        if self._pending is None:
            raise InvalidInput("drive_to_release: call start_drive first")
        self._drive, self._pending = self._pending, None
        self._t_start = self.t
        self.set_timestep(self.dt_s)
        self.run_for(self._drive.duration_s)

    def stop_drive(self) -> None:
        """Stop moving the mount (the end-effector stays where it is)."""
        self._drive = self._pending = None

    def _grip_centre(self, drive: BaseTrajectory, tau: float) -> np.ndarray:
        if tau <= drive.duration_s:
            return drive.sample(tau)[0]
        p1, v1, _ = drive.end_state()
        return p1 + v1 * (tau - drive.duration_s)

    def step(self, n: int = 1) -> None:
        """Advance n steps; each first moves the mount along the drive (if one is active)."""
        for _ in range(n):
            if self._drive is not None:
                tau = self.t + self._dt_now - self._t_start
                centre = self._grip_centre(self._drive, tau)
                self.hold_ee((centre + self._offset).tolist(), self._orn)
            super().step(1)
