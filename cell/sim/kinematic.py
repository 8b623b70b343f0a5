"""A kinematic plant beside PyBullet: the same `cell.seams.Plant`, no contact.

An item is where it was put until it is released (`launch`); then it moves by the model's
free flight (MODEL.md: the centre of mass on a drag-free parabola under gravity, world
frame W, z up) until its centre comes down to the surface under it: a bin's floor plate
(the bin's footprint, `BinSpec`) or the floor (z = 0), plus half its height. There it
rests at once (no bounce, no slide, no walls: nothing touches anything). Time advances
only by `step`, in steps of `dt_s`.

For fast tests of the item loop and of a platform's decisions: the loop's scoring, its
time accounting, the flights it scores between a platform's moves (`ItemLoop.land`), and
the landing of a planned throw, which the closed form of the parabola checks exactly.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from cell.errors import InvalidInput, NoLanding
from cell.model.objects import ObjectParams
from cell.model.params import G
from cell.sim.bins import BinSpec, which_bin
from cell.sim.settle import Outcome, crossing

__all__ = ["KinematicItem", "KinematicPlant"]

DT_S = 1.0 / 240.0  # [s] the step, as the PyBullet scene's


@dataclass(eq=False)  # an item is itself, whatever its state
class KinematicItem:
    """An item of the kinematic plant.

    Attributes:
        obj: what it is (its size sets the height of its centre at rest).
        position: its centre of mass now [m, W].
        released: the plant time it was launched at [s] (None: not released).
        p0, v0: its centre and velocity at the launch [m, W], [m/s, W].
        samples: (t since the launch [s], x, y, z [m]) of each step of its flight.
        rest: the plant time it came to rest at [s] (None: not yet, or not released).
    """

    obj: ObjectParams
    position: np.ndarray
    released: float | None = None
    p0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    v0: np.ndarray = field(default_factory=lambda: np.zeros(3))
    samples: list[tuple[float, float, float, float]] = field(default_factory=list)
    rest: float | None = None


class KinematicPlant:
    """A plant whose items move only by the model's flight (see the module docstring).

    Args:
        bins: the cell's bins.
        dt_s: the step [s].
    """

    def __init__(self, bins: Sequence[BinSpec] = (), *, dt_s: float = DT_S) -> None:
        if not dt_s > 0:
            raise InvalidInput(f"dt_s {dt_s!r}: give a step > 0 s")
        self.bins = list(bins)
        self.dt_s = float(dt_s)
        self.items: list[KinematicItem] = []
        self._steps = 0  # the clock counts steps: t is the same however it was reached
        self.step_wall_s = 0.0  # wall time [s] spent stepping (the loop's `plan_s` is the rest)

    @property
    def t(self) -> float:
        """The plant's time [s]."""
        return self._steps * self.dt_s

    def set_timestep(self, dt_s: float) -> None:
        """The step is fixed: a plant that keeps time in steps of another size refuses."""
        if dt_s != self.dt_s:
            raise InvalidInput(f"the kinematic plant steps {self.dt_s} s, not {dt_s} s")

    def spawn_item(self, obj: ObjectParams, position: Sequence[float]) -> KinematicItem:
        """Put an item with its centre at `position` [m, W]; it stays there until launched."""
        item = KinematicItem(obj, np.asarray(position, float).copy())
        self.items.append(item)
        return item

    def launch(self, item: KinematicItem, velocity: Sequence[float]) -> None:
        """Release the item where it is with `velocity` [m/s, W]: its flight starts now."""
        item.released, item.rest = self.t, None
        item.p0, item.v0 = item.position.copy(), np.asarray(velocity, float).copy()
        x, y, z = (float(v) for v in item.p0)
        item.samples = [(0.0, x, y, z)]

    def surface_z(self, item: KinematicItem, xy: Sequence[float]) -> float:
        """Where the item's centre rests over (x, y) [m, W]: on a bin's floor plate, else on
        the floor, half its height up [m]."""
        inside = which_bin((float(xy[0]), float(xy[1])), self.bins)
        top = 0.0 if inside is None else self._bin(inside).wall
        return top + item.obj.size[2] / 2

    def _bin(self, bin_id: str) -> BinSpec:
        return next(b for b in self.bins if b.id == bin_id)

    def step(self, n: int = 1) -> None:
        """Advance the time n steps; every item in flight moves along its parabola, and
        rests where its centre comes down to the surface under it."""
        t0 = time.perf_counter()
        for _ in range(n):
            self._steps += 1
            for item in self.items:
                if item.released is not None and item.rest is None:
                    self._fly(item)
        self.step_wall_s += time.perf_counter() - t0

    def _fly(self, item: KinematicItem) -> None:
        assert item.released is not None
        tau = self.t - item.released
        p = item.p0 + item.v0 * tau + np.array([0.0, 0.0, -0.5 * G * tau * tau])
        z_rest = self.surface_z(item, p[:2])
        if p[2] <= z_rest and item.v0[2] - G * tau < 0.0:
            p[2] = z_rest
            item.rest = self.t
        item.position = p
        item.samples.append((tau, float(p[0]), float(p[1]), float(p[2])))

    def item_position(self, item: KinematicItem) -> np.ndarray:
        """The item's centre of mass now [m, W]."""
        return item.position.copy()

    def outcome_if_settled(self, item: KinematicItem, *, timeout_s: float = 6.0) -> Outcome | None:
        """The item's Outcome once it rests; None while it flies. NoLanding when it was
        never launched, or flew longer than `timeout_s` [s]."""
        if item.released is None:
            raise NoLanding("the item was never released")
        if item.rest is None:
            if self.t - item.released > timeout_s:
                raise NoLanding(f"the item flew for more than {timeout_s:.1f} s")
            return None
        track = np.asarray(item.samples, float)
        speed = self._speed_at(item, item.rest - item.released)
        rest = tuple(float(v) for v in item.position)
        return Outcome(
            touchdown_xyz=rest,  # type: ignore[arg-type]
            touchdown_speed=speed,
            touchdown_body=-1,
            rest_xyz=rest,  # type: ignore[arg-type]
            bin_id=which_bin(rest, self.bins, above_rim_m=max(item.obj.size) / 2),
            rested=True,
            t_touchdown=item.rest - item.released,
            t_rest=item.rest - item.released,
            track=track,
        )

    @staticmethod
    def _speed_at(item: KinematicItem, tau: float) -> float:
        v = item.v0 + np.array([0.0, 0.0, -G * tau])
        return float(math.sqrt(float(v @ v)))

    def watch_until_rest(self, item: KinematicItem, *, timeout_s: float = 6.0) -> Outcome:
        """Step until the item rests; its Outcome."""
        while (out := self.outcome_if_settled(item, timeout_s=timeout_s)) is None:
            self.step()
        return out

    def watch_until_crossing(
        self, item: KinematicItem, land_z: float, *, timeout_s: float = 4.0
    ) -> tuple[float, float, float]:
        """Step until the item's centre crosses z = land_z going down: (x, y [m], t [s]
        since the launch), between the two steps around it (`cell.sim.settle.crossing`)."""
        assert item.released is not None, "launch the item first"
        while True:
            try:
                return crossing(np.asarray(item.samples, float), land_z)
            except NoLanding:
                if item.rest is not None or self.t - item.released > timeout_s:
                    raise
            self.step()

    def tracker(self, item: KinematicItem) -> KinematicItem:
        """What samples the item's flight (its `samples`: t, x, y, z)."""
        return item

    def tidy(self, item: KinematicItem) -> None:
        """An item at rest in a bin stays; any other is taken away."""
        out = None if item.rest is None else self.outcome_if_settled(item)
        if out is None or out.bin_id is None:
            self.remove_item(item)

    def remove_item(self, item: KinematicItem) -> None:
        """Take the item out of the plant."""
        if item in self.items:
            self.items.remove(item)
