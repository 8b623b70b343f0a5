"""Independent computations run side by side, their flights integrated as one batch.

A diagnosis fits many effect sets that do not depend on one another (every member of
every family alone, every partner of the chosen effects, every law of an effect). Each
fit integrates flights (`cell.model.flight3d.fly`) a few hundred rows at a time, and a
flight's cost is mostly its steps' NumPy calls, not its rows: 3.2 ms for 200 rows,
0.7 ms a call for ten such calls made as one of 2,000 rows.

`together(thunks)` runs each thunk in its own thread. A `fly` called in one of those
threads does not integrate at once: it waits until every thunk still running waits on a
flight too (or has finished); then all those flights are integrated as one batch (their
rows stacked, each request's own air and extra acceleration given to its own rows by a
composite callback) and each thunk gets its own rows back. Only one thread computes at a
time (the interpreter's lock; the others wait), so the CPU spent is the thunks' own less
the flights' calls saved.

The integrator is row-independent: each row's arithmetic reads only that row (the gap
fit's stacked Jacobian rests on the same property, `cell.gap.fit_jac`), so each
request's crossings are those of its own call, bit for bit, whatever else shares its
batch (tests/test_flight_batch.py). Where one request has an air velocity or an extra
acceleration and another none, the other's rows get zeros: v − 0 is v to the bit, and
a + 0 is a but for the sign of a zero.

The planar flights of the fast path (`cell.model.planar.flight_planar`, the flight of
every fit without a flight effect) are batched alike, but their steps are the batch's: a
step is shortened where the batch's largest k|v| asks for it. A batch none of whose steps
was shortened gives every request its own call's numbers (each request's steps would have
been full too); one that shortened a step is integrated again request by request.
"""

from __future__ import annotations

import contextvars
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from cell.model import flight3d
from cell.model.effects_air import stack_accels
from cell.model.flight3d import Accel, FlightResult
from cell.model.planar import planar_full_steps

__all__ = ["FlightRequest", "PlanarRequest", "fly_merged", "planar_merged", "together"]

T = TypeVar("T")


@dataclass(frozen=True)
class FlightRequest:
    """The arguments of one `flight3d.fly` call (k, land_z and t0 broadcast to (n,))."""

    position: np.ndarray
    velocity: np.ndarray
    k: np.ndarray
    land_z: np.ndarray
    accel: Accel | None
    t0: np.ndarray
    step: float
    t_max: float


@dataclass(frozen=True)
class PlanarRequest:
    """The arguments of one `cell.model.planar.flight_planar` call (arrays of shape (n,))."""

    z: np.ndarray
    vh: np.ndarray
    vz: np.ndarray
    k: np.ndarray
    land_z: np.ndarray
    max_step: float
    t_max: float


def planar_merged(requests: Sequence[PlanarRequest]) -> list[tuple[np.ndarray, ...]]:
    """Each request's `flight_planar` result: the requests of one largest step and time
    limit integrated as one batch; where the batch shortened a step (its largest k|v|),
    each of its requests again on its own (`planar.planar_full_steps`: only full steps
    give every row its own call's numbers)."""
    out: list[tuple[np.ndarray, ...] | None] = [None] * len(requests)
    groups: dict[tuple[float, float], list[int]] = {}
    for i, r in enumerate(requests):
        groups.setdefault((r.max_step, r.t_max), []).append(i)
    for (max_step, t_max), members in groups.items():
        reqs = [requests[i] for i in members]
        z, vh, vz, k, lz = (np.concatenate([getattr(r, f) for r in reqs]) for f in _PLANAR)
        res, full = planar_full_steps(z, vh, vz, k, lz, max_step, t_max)
        if not full and len(reqs) > 1:
            for i, r in zip(members, reqs, strict=True):
                out[i] = planar_full_steps(r.z, r.vh, r.vz, r.k, r.land_z, max_step, t_max)[0]
            continue
        cuts = np.cumsum([r.z.shape[0] for r in reqs])[:-1]
        for i, *parts in zip(members, *(np.split(a, cuts) for a in res), strict=True):
            out[i] = tuple(parts)
    return [r for r in out if r is not None]


_PLANAR = ("z", "vh", "vz", "k", "land_z")


def _merged(requests: Sequence[Any]) -> list[Any]:
    """Each request's result: the 3-D flights (`fly_merged`) and the planar ones
    (`planar_merged`) each as their batches."""
    out: list[Any] = [None] * len(requests)
    for kind, run in ((FlightRequest, fly_merged), (PlanarRequest, planar_merged)):
        idx = [i for i, r in enumerate(requests) if isinstance(r, kind)]
        if idx:
            for i, res in zip(idx, run([requests[i] for i in idx]), strict=True):
                out[i] = res
    return out


class _Composite:
    """One `Accel` for stacked segments of rows: each segment's callback (or None: still
    air, no extra acceleration) is handed its own rows (their indices in the segment, the
    same object while the integrated rows stay the same, as `fly` does) and its air
    velocity and extra acceleration are placed in its rows; rows of a segment without
    them get zeros."""

    def __init__(self, parts: Sequence[tuple[Accel | None, int, int]]) -> None:
        self.parts = [(a, lo, hi) for a, lo, hi in parts if a is not None]
        self.reads_position = any(getattr(a, "reads_position", True) for a, _, _ in self.parts)
        self._idx: np.ndarray | None = None
        self._cuts: list[tuple[int, int, np.ndarray, Accel]] = []

    def __call__(self, p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[Any, Any]:
        if idx is not self._idx:  # idx stays sorted: fly only ever drops rows
            self._idx = idx
            self._cuts = []
            for a, lo, hi in self.parts:
                s, e = (int(i) for i in np.searchsorted(idx, [lo, hi]))
                if e > s:
                    self._cuts.append((s, e, idx[s:e] - lo, a))
        w: np.ndarray | None = None
        extra: np.ndarray | None = None
        for s, e, local, a in self._cuts:
            w_j, x_j = a(p[s:e], v[s:e], local)
            if w_j is not None:
                if w is None:
                    w = np.zeros((idx.size, 3), order="F")
                w[s:e] = w_j
            if x_j is not None:
                if extra is None:
                    extra = np.zeros((idx.size, 3), order="F")
                extra[s:e] = x_j
        return w, extra


def _segment(i: int, accel: Accel | None) -> tuple:
    """Requests of one segment share a callback: none, or the stacked callbacks of one
    kind (`cell.model.effects_air.stack_accels`); any other callback is its own."""
    if accel is None:
        return (0,)
    stack = getattr(accel, "stack", None)
    return (1, stack[0]) if stack is not None else (2, i)


def _merged_accel(reqs: Sequence[FlightRequest], offsets: np.ndarray) -> Accel | None:
    """The callback of requests put end to end, those of one segment next to each other."""
    parts: list[tuple[Accel | None, int, int]] = []
    j = 0
    while j < len(reqs):
        key = _segment(j, reqs[j].accel)
        e = j + 1
        while e < len(reqs) and _segment(e, reqs[e].accel) == key:
            e += 1
        accels = [r.accel for r in reqs[j:e]]
        one = accels[0] if len(accels) == 1 or accels[0] is None else stack_accels(accels)
        parts.append((one, int(offsets[j]), int(offsets[e])))
        j = e
    if len(parts) == 1:
        return parts[0][0]
    return None if all(a is None for a, _, _ in parts) else _Composite(parts)


def fly_merged(requests: Sequence[FlightRequest]) -> list[FlightResult]:
    """Each request's `fly` result, the requests of one step and time limit integrated
    as one batch (those of one segment, `_segment`, next to each other)."""
    out: list[FlightResult | None] = [None] * len(requests)
    groups: dict[tuple[float, float], list[int]] = {}
    for i, r in enumerate(requests):
        groups.setdefault((r.step, r.t_max), []).append(i)
    for (step, t_max), members in groups.items():
        members.sort(key=lambda i: repr(_segment(i, requests[i].accel)))
        reqs = [requests[i] for i in members]
        offsets = np.r_[0, np.cumsum([r.position.shape[0] for r in reqs])]
        res = flight3d._fly(
            np.concatenate([r.position for r in reqs]),
            np.concatenate([r.velocity for r in reqs]),
            np.concatenate([r.k for r in reqs]),
            np.concatenate([r.land_z for r in reqs]),
            accel=_merged_accel(reqs, offsets),
            t0=np.concatenate([r.t0 for r in reqs]),
            step=step,
            t_max=t_max,
        )
        for j, i in enumerate(members):
            lo, hi = offsets[j], offsets[j + 1]
            out[i] = FlightResult(
                position=res.position[lo:hi],
                velocity=res.velocity[lo:hi],
                t=res.t[lo:hi],
                landed=res.landed[lo:hi],
            )
    return [r for r in out if r is not None]


class _Gather:
    """The flights the running thunks wait on, integrated once all of them wait."""

    def __init__(self, live: int) -> None:
        self.cond = threading.Condition()
        self.live = live
        self.pending: list[tuple[FlightRequest | PlanarRequest, dict[str, Any]]] = []

    def submit(self, req: FlightRequest | PlanarRequest) -> Any:
        """In a thunk's thread: wait for the batch that holds this flight."""
        slot: dict[str, Any] = {}
        with self.cond:
            self.pending.append((req, slot))
            self.cond.notify_all()
            while not slot:
                self.cond.wait()
        if "error" in slot:
            raise slot["error"]
        return slot["result"]

    def leave(self) -> None:
        """In a thunk's thread: it has finished."""
        with self.cond:
            self.live -= 1
            self.cond.notify_all()

    def serve(self) -> None:
        """In the caller's thread: integrate the waiting flights whenever every running
        thunk waits, until none runs."""
        with self.cond:
            while True:
                while self.live > 0 and len(self.pending) < self.live:
                    self.cond.wait()
                if self.live == 0:
                    return
                batch, self.pending = self.pending, []
                try:
                    got = _merged([r for r, _ in batch])
                    for (_, slot), res in zip(batch, got, strict=True):
                        slot["result"] = res
                except Exception as exc:  # handed to every thunk that waited on it
                    for _, slot in batch:
                        slot["error"] = exc
                self.cond.notify_all()


def together(thunks: Sequence[Callable[[], T]]) -> list[T]:
    """Each thunk's result, in order; their flights integrated together (module doc).

    Called inside a thunk (or with fewer than two), the thunks run one after another
    (their flights still join the outer batch). An exception in a thunk is raised here
    once every thunk has finished.
    """
    if len(thunks) < 2 or flight3d.current_gather() is not None:
        return [t() for t in thunks]
    gather = _Gather(len(thunks))
    results: list[Any] = [None] * len(thunks)
    errors: list[BaseException | None] = [None] * len(thunks)

    # each thread runs in a copy of the caller's context (NumPy's error state is a
    # context variable: `cell.cli`'s errstate holds in the thunks too)
    contexts = [contextvars.copy_context() for _ in thunks]

    def work(i: int) -> None:
        flight3d.route_flights(gather)
        try:
            results[i] = contexts[i].run(thunks[i])
        except BaseException as exc:  # raised in the caller's thread below
            errors[i] = exc
        finally:
            gather.leave()

    threads = [threading.Thread(target=work, args=(i,), daemon=True) for i in range(len(thunks))]
    for th in threads:
        th.start()
    gather.serve()
    for th in threads:
        th.join()
    for err in errors:
        if err is not None:
            raise err
    return results
