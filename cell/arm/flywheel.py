"""The flywheel: landing corrections learned from each observed landing (`learn`)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.joints import clip
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)


@dataclass
class LandingCorrection:
    """What the landings of one object (or class) taught the planner.

    The scene's reach along a throw is ρ times what the model predicted, and its
    direction is turned by δ: the next throw of the object aims at a point moved so
    that, with the same ρ and δ, it lands on the goal.

    Attributes:
        log_ratio: mean of log(observed reach / aimed reach), ρ = exp(log_ratio).
        turn_rad: mean angle from the aimed to the observed landing, seen from the
            release point [rad].
        n: landings averaged.
    """

    log_ratio: float = 0.0
    turn_rad: float = 0.0
    n: int = 0

    def add(self, log_ratio: float, turn_rad: float) -> None:
        """Average one more landing in."""
        self.n += 1
        self.log_ratio += (log_ratio - self.log_ratio) / self.n
        self.turn_rad += (turn_rad - self.turn_rad) / self.n


class Flywheel(ArmBase):
    """The flywheel (a part of the arm; `cell.orchestrator.Orchestrator`)."""

    @staticmethod
    def _class_key(obj: ObjectParams) -> str:
        return f"class:{obj.shape}"

    def _corrected_aim(self, obj: ObjectParams, plan: Any, goal: np.ndarray) -> np.ndarray | None:
        """The aim point that the object's (or its class's) correction asks for, or None."""
        own = self.corrections.get(obj.name or "")
        if own is not None and own.n:
            lr = clip(own.log_ratio, self.tuning.learn_max_log_ratio)
            turn = clip(own.turn_rad, self.tuning.learn_max_turn_rad)
        else:
            cls = self.corrections.get(self._class_key(obj))
            if cls is None or not cls.n:
                return None
            lr = clip(cls.log_ratio, self.tuning.learn_class_max_log_ratio)
            turn = clip(cls.turn_rad, self.tuning.learn_class_max_turn_rad)
        p0 = np.array([plan.x_m, plan.y_m])
        v = goal[:2] - p0
        c, s = math.cos(-turn), math.sin(-turn)
        v = np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]]) / math.exp(lr)
        return np.array([*(p0 + v), goal[2]])

    def _learn_from(self, obj: ObjectParams, plan: Any, cross: Any, aim: np.ndarray) -> None:
        """Average this landing (aimed at `aim`) into the object's and its class's
        corrections."""
        p0 = np.array([plan.x_m, plan.y_m])
        aimed = aim[:2] - p0
        seen = np.asarray(cross[:2], float) - p0
        ra, rs = float(np.hypot(*aimed)), float(np.hypot(*seen))
        if ra < 0.05 or rs < 0.05:
            return  # too short a throw to say anything about its reach
        lr = math.log(rs / ra)
        turn = math.atan2(aimed[0] * seen[1] - aimed[1] * seen[0], float(aimed @ seen))
        for key in (obj.name or "", self._class_key(obj)):
            self.corrections.setdefault(key, LandingCorrection()).add(lr, turn)

    def _same_kind(self, obj: ObjectParams, other: ObjectParams) -> bool:
        """Is `other` (in flight) the same object or class as `obj` (learning waits)?"""
        keys = {obj.name or "", self._class_key(obj)}
        return bool({other.name or "", self._class_key(other)} & keys)
