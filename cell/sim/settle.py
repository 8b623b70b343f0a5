"""Where an item lands and rests: touchdown and rest detection in the scene.

A `Tracker` samples one item on every physics step after its release. The
touchdown is the first step on which the item touches anything other than
the end-effector (its centre of mass there, and its speed just before); the
item rests when its speed and spin stay below small thresholds for a while.
The recorded track also gives the crossing of any horizontal plane z = land_z
while descending (the landing point as MODEL.md defines it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cell.errors import NoLanding

__all__ = ["Outcome", "Tracker", "crossing", "REST_SPEED_MPS", "REST_SPIN_RADPS", "REST_TIME_S"]

REST_SPEED_MPS = 0.01  # [m/s] below this (and the spin below), the item is still
REST_SPIN_RADPS = 0.2  # [rad/s]
REST_TIME_S = 0.1  # [s] still for this long = at rest


def _norm(v: np.ndarray) -> float:
    """|v| of a 3-vector: the bits np.linalg.norm gives (sqrt of the same v·v), cheaper."""
    return math.sqrt(v.dot(v))


def crossing(track: np.ndarray, land_z: float) -> tuple[float, float, float]:
    """Where and when a track first crosses z = land_z going down.

    Linear interpolation between the two samples around the crossing (the
    samples are one physics step apart).

    Args:
        track: (k, 4) samples t [s], x, y, z [m].
        land_z: plane height [m].

    Returns:
        (x [m], y [m], t [s]).

    Raises:
        NoLanding: the track never crosses the plane while descending.
    """
    tr = np.asarray(track, float)
    z = tr[:, 3]
    down = np.flatnonzero((z[:-1] > land_z) & (z[1:] <= land_z))
    if down.size == 0:
        raise NoLanding(
            f"the item's track never crosses z = {land_z:.3f} m while descending "
            f"(lowest z {z.min():.3f} m)"
        )
    i = int(down[0])
    w = (z[i] - land_z) / (z[i] - z[i + 1])
    p = tr[i] + w * (tr[i + 1] - tr[i])
    return float(p[1]), float(p[2]), float(p[0])


@dataclass(frozen=True)
class Outcome:
    """What became of a released item.

    Attributes:
        touchdown_xyz: centre of mass at the first touch of anything but the end-effector [m, W].
        touchdown_speed: speed just before that touch [m/s].
        touchdown_body: PyBullet body id of what it first touched.
        rest_xyz: centre of mass at rest [m, W].
        bin_id: the bin the item rests in, or None.
        rested: False when the watch timed out before the item came to rest.
        t_touchdown: time of the touchdown since release [s].
        t_rest: time since release when the rest was detected [s].
        track: (k, 4) samples t [s], x, y, z [m] of the centre of mass since release.
    """

    touchdown_xyz: tuple[float, float, float]
    touchdown_speed: float
    touchdown_body: int
    rest_xyz: tuple[float, float, float]
    bin_id: str | None
    rested: bool
    t_touchdown: float
    t_rest: float
    track: np.ndarray = field(repr=False, compare=False)

    @property
    def touchdown_xy(self) -> tuple[float, float]:
        """Touchdown point (x, y) [m, W]."""
        return (self.touchdown_xyz[0], self.touchdown_xyz[1])

    def crossing(self, land_z: float) -> tuple[float, float, float]:
        """Where and when the centre of mass first crosses z = land_z going down.

        Returns:
            (x [m], y [m], t [s] since release); see `crossing`.

        Raises:
            NoLanding: the track never crosses the plane while descending.
        """
        return crossing(self.track, land_z)


class Tracker:
    """Samples one item after release; see the module docstring."""

    def __init__(self, body: int, ee_body: int, t0: float) -> None:
        self.body = body
        self.ee_body = ee_body
        self.t0 = t0
        self.samples: list[tuple[float, float, float, float]] = []
        self.touchdown: tuple[tuple[float, float, float], float, int, float] | None = None
        self._still_since: float | None = None
        self._last_speed = 0.0
        self.rest_t: float | None = None

    def sample(
        self, t: float, pos: tuple, vel: np.ndarray, spin: np.ndarray, contacts: list
    ) -> None:
        """Record one step: time [s], position [m], velocity [m/s], spin [rad/s], contacts.

        Once the item is at rest the track is complete: later steps add nothing, so a
        track read late (the loop went on with the next item) is the one read at rest.
        """
        if self.rest_t is not None:
            return
        rel = t - self.t0
        self.samples.append((rel, float(pos[0]), float(pos[1]), float(pos[2])))
        speed = _norm(vel)
        if self.touchdown is None:
            other = [c for c in contacts if c[2] != self.ee_body]
            if other:
                self.touchdown = (
                    (float(pos[0]), float(pos[1]), float(pos[2])),
                    self._last_speed,
                    int(other[0][2]),
                    rel,
                )
        self._last_speed = speed
        still = speed < REST_SPEED_MPS and _norm(spin) < REST_SPIN_RADPS
        if still and self.touchdown is not None:
            if self._still_since is None:
                self._still_since = rel
            elif rel - self._still_since >= REST_TIME_S:
                self.rest_t = rel
        else:
            self._still_since = None

    @property
    def needs_contacts(self) -> bool:
        """`sample` still reads the contacts it is given: until the touchdown (later
        samples may be given none)."""
        return self.touchdown is None and self.rest_t is None

    @property
    def at_rest(self) -> bool:
        """True once the item has been still long enough after a touchdown."""
        return self.rest_t is not None

    def outcome(self, bin_id: str | None) -> Outcome:
        """The outcome so far (call after the watch ends).

        Raises:
            NoLanding: the item never touched anything but the end-effector.
        """
        if self.touchdown is None or not self.samples:
            raise NoLanding(
                f"item body {self.body} never touched down within "
                f"{self.samples[-1][0] if self.samples else 0.0:.2f} s of its release"
            )
        last = self.samples[-1]
        return Outcome(
            touchdown_xyz=self.touchdown[0],
            touchdown_speed=self.touchdown[1],
            touchdown_body=self.touchdown[2],
            rest_xyz=(last[1], last[2], last[3]),
            bin_id=bin_id,
            rested=self.at_rest,
            t_touchdown=self.touchdown[3],
            t_rest=self.rest_t if self.rest_t is not None else last[0],
            track=np.asarray(self.samples),
        )
