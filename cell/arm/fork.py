"""Planning on a second core: one branch of a decision searched in a forked child process.

A decision's throw is planned at two facings (`Planner._plan_to`: the arm facing the bin at
the release, and turned toward the pick station), searched one after the other, the second
told the first's cycle estimate to beat, and combined by a fixed rule (the second kept only
where its estimate is the shorter, `PlanFork._best_facing`). The arm's motion is executed
by its controller, so the cell's second core is free to plan: `PlanFork` searches the
second facing in a child process (`os.fork`: the child inherits the arm's exact state at
that moment, the scene included, which the planner reads and does not step) while the
parent searches the first, and the parent combines them with the same rule. The child is
not told the first's estimate (it has not got it): a release that cannot beat it is timed
there too, but a plan that cannot beat it is not kept either way, and one that can is the
same plan with or without it (`_release_search`'s bound prunes only what cannot be
chosen), so the choice is the serial one. A throw with one facing has its last lower
release bounds (RELEASE_FALLBACKS) searched so instead, while the parent plans in the
cell's bounds and the first lower ones (`PlanFork._plan_tier`, the same argument:
`soonest_of` keeps a lower bounds' plan only where it beats the ones before). tests/test_plan_fork.py checks the decisions
against the serial path's.

What the serial path's second branch leaves for what follows, the parent gets from the
child: the IK searches it made (`Kinematics._ik_keep`'s record: answers, poses out of
reach, warm starts), replayed in the parent after its own branch, in the serial order; and
the moves it planned (`PlanFork._memo_since`: the carries and paths of `Mover._planned`,
the pick's approach times), kept where the parent has none under the same key, so that the
item's pick and carry plan again only what cannot be pickled (a ruckig move). A
branch's IK depends on the searches made before it (warm starts, poses refused as out of
reach); the child's began without the first branch's, so the parent checks that none of
the first branch's IK poses is within `ArmTuning.ik_warm`'s distance and angle (or equal,
without it) of one the child asked: where one is, the child's answer is dropped and the
branch searched again in the parent, as the serial path would (logged). So too where the
child fails, hangs past FORK_TIMEOUT_S (it is killed), steps the plant, or its answer cannot
be sent: the serial path, logged. No child outlives the join (`_fork_join`,
`_fork_cancel` reap it).
"""

from __future__ import annotations

import logging
import math
import os
import pickle
import select
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from dataclasses import replace as dc_replace
from functools import partial
from typing import Any

import numpy as np

from cell.arm.base import ArmBase
from cell.arm.choice import ThrowChoice, sooner_beat
from cell.arm.steep import steep_kept
from cell.errors import CellError, IKFailed, InvalidInput, UnreachableTarget
from cell.model.objects import ObjectParams

log = logging.getLogger(__name__)

# [s] the longest the parent waits for a child's answer once its own branch is done: the
# slowest branch measured took 2.5 s of CPU (tune layout 0, a loaded machine 4x that); a
# child past it is killed and its branch searched in the parent
FORK_TIMEOUT_S = 60.0

PLAN_WORKERS_ENV = "CELL_PLAN_WORKERS"  # the default plan workers where set (1 or 2)

__all__ = [
    "FORK_TIMEOUT_S",
    "PLAN_WORKERS_ENV",
    "ForkStats",
    "PlanFork",
    "check_plan_workers",
    "lower_outcomes",
    "plan_workers_default",
]


def plan_workers_default() -> int:
    """The processes a decision plans on by default: $CELL_PLAN_WORKERS where it is set
    (1 or 2: the test suite sets 1, its two workers already use both cores), else 2 where
    the process may use two cores or more (`os.sched_getaffinity`), else 1 (the serial
    path). InvalidInput naming the variable for another value."""
    text = os.environ.get(PLAN_WORKERS_ENV, "").strip()
    if text:
        if text not in ("1", "2"):
            raise InvalidInput(f"${PLAN_WORKERS_ENV}={text!r}: give 1 (plan serially) or 2")
        return int(text)
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return 2 if cores >= 2 else 1


def check_plan_workers(n: int | None) -> int:
    """`n` plan workers (None: `plan_workers_default`), or InvalidInput: 1 or 2 are valid."""
    if n is None:
        return plan_workers_default()
    if n not in (1, 2):
        raise InvalidInput(f"plan workers {n!r}: give 1 (plan serially) or 2")
    return n


@dataclass
class ForkStats:
    """What the forked branches did over a run (`PlanFork`): branches forked, answers used,
    branches searched again in the parent by reason, and the children's CPU time [s]
    (user + system, `os.wait4`); the parent's wall time [s] in `os.fork` and waiting for
    the children's answers once its own branch was done; and by how much each child's CPU
    time passed the parent's between the fork and the join [s], summed (`beyond_cpu_s`:
    a decision's CPU time on its critical path is the parent's plus that)."""

    forked: int = 0
    used: int = 0
    cancelled: int = 0
    serial: dict[str, int] = field(default_factory=dict)
    child_cpu_s: float = 0.0
    fork_s: float = 0.0
    wait_s: float = 0.0
    beyond_cpu_s: float = 0.0


@dataclass
class _Child:
    """A forked branch: its process id, the read end of its pipe, the parent's IK record
    since the fork (the first branch's), and what the parent recorded before."""

    pid: int
    fd: int
    mine: list[Any]
    kept_log: list[Any] | None
    cpu0: float = 0.0  # [s] the parent's CPU time when it forked (`time.process_time`)
    cpu_s: float = 0.0  # [s] the child's CPU time, once reaped (`os.wait4`)


def _die_with_parent(parent: int) -> None:
    """In a child: be killed when `parent` ends (Linux's PR_SET_PDEATHSIG), so that a
    parent killed mid-decision leaves no child planning on; elsewhere nothing."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # the parent ended before the call: end now
        os._exit(1)


def _child_main(fn: Callable[[], Any], w: int) -> None:
    """In the child: run `fn` and write its pickled answer to `w`; never returns."""
    code = 0
    try:
        try:
            out: tuple[str, Any] = ("ok", fn())
        except BaseException as exc:  # the branch's error, whatever it is, to the parent
            out = ("err", exc)
        try:
            data = pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # an answer that cannot be sent: the parent searches
            data = pickle.dumps(("unsent", repr(exc)))
        view = memoryview(data)
        while view:
            view = view[os.write(w, view) :]
    except BaseException:
        code = 1
    finally:
        os._exit(code)  # no atexit handlers, no flush of the parent's buffers


class PlanFork(ArmBase):
    """A decision's branch searched in a forked child (a part of the arm;
    `cell.orchestrator.Orchestrator`). `plan_workers`: 1, the serial path; 2, a branch on
    a second process."""

    plan_workers: int = 1
    fork_stats: ForkStats
    _in_child: bool = False

    def _init_forks(self, plan_workers: int | None) -> None:
        """Plan on `plan_workers` processes (`check_plan_workers`), none forked yet."""
        self.plan_workers = check_plan_workers(plan_workers)
        self.fork_stats = ForkStats()

    def _best_facing(
        self,
        plan: Any,
        facings: tuple[float | None, ...],
        beat: float | None,
        err: CellError | None,
        steep: bool,
        obj: ObjectParams,
    ) -> tuple[ThrowChoice | None, CellError | None]:
        """(the plan `_plan_to` keeps of those at `facings`, or None; the first error met)
        where `plan(facing, beat)` plans at a facing (`_plan_facing`) and `steep`: the
        steep tiers' (`steep_kept`). With two plan workers, the second facing is searched
        on a second process meanwhile (`cell.arm.fork`), not told the first's estimate,
        and kept by the same rule: the same choice."""
        best: ThrowChoice | None = None
        child = self._fork_branch(partial(plan, facings[1], beat)) if len(facings) > 1 else None
        try:
            for k, facing in enumerate(facings):
                if self._to_beat(best) is not None and self._budget_spent():
                    break  # a release that holds in hand, the budget spent (`release_budget`)
                serial = partial(plan, facing, sooner_beat(self._to_beat(best), beat))
                try:
                    if child is not None and k == 1:
                        forked, child = child, None
                        r = self._fork_join(forked, serial)
                    else:
                        r = serial()
                except (UnreachableTarget, IKFailed) as exc:
                    err = err or exc
                    continue
                if steep and not steep_kept(r, obj, self.params, self.robot, self.tuning):
                    continue
                cost = r.cost
                log.debug("facing %s: (slips, cycle estimate) %s", facing, cost)
                if best is not None and (
                    cost is None or best.cost is None or r.held < best.held or not cost < best.cost
                ):
                    continue
                best = r
                if cost is None:  # nothing to compare by: the arm faces the bin
                    break
        finally:
            if child is not None:  # a branch the serial path would not search
                self._fork_cancel(child)
        return best, err

    def _plan_tier(
        self,
        obj: ObjectParams,
        goal: tuple[float, float, float],
        item: tuple[int, float],
        tier: list[Any],
        first_kept: bool,
        facing: float | None,
        beat: float | None,
        err: CellError | None,
    ) -> tuple[list[ThrowChoice], CellError | None]:
        """`_plan_facing`'s plans in one tier of release bounds (the first reached kept
        where `first_kept`), and the first error met. With two plan workers and no other
        branch forked (`cell.arm.fork`), the last lower bounds of a tier that keeps the
        soonest are searched on a second process meanwhile, told only `beat`, and used as
        the serial path would (a plan that cannot beat the ones before is not chosen
        either way: `soonest_of`). The last alone: the child's search is not pruned by the
        bounds before it, the parent's are (the first and second lower bounds in the
        child cost tune layout 1 4.1 s of CPU beyond the parents' branches, the second
        alone 0.5 s, at the same critical path; docs/HISTORY.md, branch plan22)."""
        found: list[ThrowChoice] = []
        plan = partial(self._plan_in, obj, goal, *item)
        at = [dc_replace(b, facing_rad=facing) for b in tier]
        child, cut = None, max(1, len(at) - 1)  # the child's: the last of the bounds
        if not first_kept and len(at) > 1 and self.cycle_search:  # else none searched
            child = self._fork_branch(partial(lower_outcomes, plan, at[cut:], beat))
        lowers: list[Any] | None = None
        try:
            for k, bounds in enumerate(at):
                if found and (first_kept or not self._lower_bounds_wanted(found[0])):
                    break  # the first reached is kept
                if self._beat(found) is not None and self._budget_spent():
                    break  # a release that holds in hand, the budget spent (`release_budget`)
                if child is not None and k == cut:  # the last bounds' plans, searched meanwhile
                    forked, child = child, None
                    lowers = self._fork_join(forked, lambda: None)
                try:
                    if lowers is not None:
                        r = lowers[k - cut]
                        if isinstance(r, Exception):
                            raise r
                    else:
                        r = plan(bounds, sooner_beat(self._beat(found), beat), lower=k > 0)
                    found.append(r)
                except (UnreachableTarget, IKFailed) as exc:
                    err = err or exc
        finally:
            if child is not None:  # a branch the serial path would not search
                self._fork_cancel(child)
        return found, err

    def _fork_branch(self, fn: Callable[[], Any]) -> _Child | None:
        """Start `fn` (a branch of the decision) in a forked child, or None: with one
        plan worker, a work budget (`ArmTuning.release_budget` counts across branches),
        `ArmTuning.release_lower_room_s` (whether the lower bounds are searched would
        depend on the plan in the cell's bounds as the other branch's estimate pruned it),
        inside a child or another fork, or where the fork fails."""
        if (
            self.plan_workers < 2
            or self.tuning.release_budget is not None
            or self.tuning.release_lower_room_s is not None
            or self._in_child
            or self._ik_log is not None
            or not hasattr(os, "fork")
        ):
            return None
        r, w = os.pipe()
        t0 = time.perf_counter()
        try:
            parent = os.getpid()  # taken before the fork: a child reading its parent after
            pid = os.fork()  # it died would read init's and live on (`_die_with_parent`)
        except OSError as exc:
            os.close(r)
            os.close(w)
            log.warning("planning serially: the fork failed (%s)", exc)
            return None
        if pid == 0:
            os.close(r)
            _die_with_parent(parent)
            self._in_child = True
            _child_main(lambda: self._child_branch(fn), w)
        os.close(w)
        self.fork_stats.fork_s += time.perf_counter() - t0
        self.fork_stats.forked += 1
        kept, self._ik_log = self._ik_log, []
        return _Child(pid, r, self._ik_log, kept, time.process_time())

    def _child_branch(self, fn: Callable[[], Any]) -> tuple[str, Any, list[Any], bool, bytes]:
        """`fn` run in the child: ("ok", its value) or ("err", its error), the IK record
        it made, whether it stepped the plant, and the paths it planned (`_memo_since`)."""
        self._ik_log = []
        stepped = float(getattr(self.scene, "step_wall_s", 0.0))
        before = self._memo_keys()
        try:
            out: tuple[str, Any] = ("ok", fn())
        except Exception as exc:
            out = ("err", exc.with_traceback(None))
        moved = float(getattr(self.scene, "step_wall_s", 0.0)) != stepped
        return (*out, self._ik_log, moved, self._memo_since(before))

    def _memos(self) -> tuple[dict[Any, Any], ...]:
        """The decision's memos of planned moves (`_new_decision` clears them): the
        pick's approach times and plans (`_approach_s`, `_approach_plan`) and the paths
        and carries (`_planned`)."""
        return (self._approach_memo, self._approach_plans, self._plan_memo)

    def _memo_keys(self) -> list[set[Any]]:
        return [set(m) for m in self._memos()]

    def _memo_since(self, before: list[set[Any]]) -> bytes:
        """The entries the memos gained since `before` (`_memo_keys`), pickled; an entry
        that cannot be is left out (the parent then plans it again where it needs it)."""
        new: list[dict[Any, bytes]] = []
        for m, b in zip(self._memos(), before, strict=True):
            kept: dict[Any, bytes] = {}
            for k, v in m.items():
                if k in b:
                    continue
                try:
                    kept[k] = pickle.dumps(v, protocol=pickle.HIGHEST_PROTOCOL)
                except Exception:  # e.g. a ruckig move (a C++ object): planned again
                    continue
            new.append(kept)
        return pickle.dumps(new, protocol=pickle.HIGHEST_PROTOCOL)

    def _memo_merge(self, data: bytes) -> None:
        """Keep a forked branch's planned moves (`_memo_since`) where the parent has none
        under the same key: the serial path would have them from that branch, and a key
        is the whole of what the move's plan depends on (`Mover._planned`), so either
        process's entry is the same plan."""
        for m, new in zip(self._memos(), pickle.loads(data), strict=True):
            for k, v in new.items():
                if k not in m:
                    m[k] = pickle.loads(v)

    def _fork_join(self, child: _Child, serial: Callable[[], Any]) -> Any:
        """The child's answer to its branch (its value returned, its error raised), its IK
        record replayed after the parent's; or `serial()`, the branch searched in the
        parent, where the answer cannot be used (module docstring; logged)."""
        self._ik_log = child.kept_log
        t0, mine = time.perf_counter(), time.process_time() - child.cpu0
        got, why = self._fork_answer(child)
        self.fork_stats.wait_s += time.perf_counter() - t0
        self.fork_stats.beyond_cpu_s += max(0.0, child.cpu_s - mine)
        if got is not None:
            kind, value, record, moved, memos = got
            why = self._fork_conflict(child.mine, record, moved)
            if not why:
                self.fork_stats.used += 1
                self._ik_replay(record)
                self._memo_merge(memos)
                if kind == "err":
                    raise value
                return value
        log.info("the forked branch searched in the parent: %s", why)
        reason = why.split(":")[0]
        self.fork_stats.serial[reason] = self.fork_stats.serial.get(reason, 0) + 1
        return serial()

    def _fork_cancel(self, child: _Child) -> None:
        """Drop a child whose branch the serial path would not have searched: killed if it
        still runs, reaped, its answer and IK record unused."""
        self._ik_log = child.kept_log
        self.fork_stats.cancelled += 1
        try:
            os.kill(child.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self._fork_reap(child)

    def _fork_answer(self, child: _Child) -> tuple[Any, str]:
        """(the child's unpickled answer, "") or (None, why there is none); the child is
        reaped either way."""
        chunks, deadline, timed_out = [], time.monotonic() + FORK_TIMEOUT_S, False
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([child.fd], [], [], left)[0]:
                timed_out = True
                break
            chunk = os.read(child.fd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
        if timed_out:
            try:
                os.kill(child.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        status = self._fork_reap(child)
        if timed_out:
            return None, f"timeout: no answer in {FORK_TIMEOUT_S:.0f} s, the child killed"
        try:
            got = pickle.loads(b"".join(chunks))
        except Exception as exc:
            return None, f"unreadable: the child's answer ({exc!r}, exit status {status})"
        if got[0] == "unsent":
            return None, f"unsent: the child's answer could not be pickled ({got[1]})"
        if got[0] != "ok":
            return None, f"failed: the child's branch did not end ({got[1]!r})"
        return got[1], ""

    def _fork_reap(self, child: _Child) -> int:
        """Wait for the child to end (it has, or was killed); its CPU time counted."""
        os.close(child.fd)
        _, status, usage = os.wait4(child.pid, 0)
        child.cpu_s = usage.ru_utime + usage.ru_stime
        self.fork_stats.child_cpu_s += child.cpu_s
        return status

    def _fork_conflict(self, mine: list[Any], record: list[Any], moved: bool) -> str:
        """Why the child's branch may differ from the serial path's, or "": it stepped the
        plant; a release pose it searched (`_solve_ik`'s `reach`) is one the parent's
        branch asked IK of, or, with `ik_warm`, within its distance and angle of one the
        parent's branch searched, at the same roll (warm starts, far poses); or a pose and
        seed it asked plainly is one the parent's branch searched (its answer remembered
        would be the search's). Plain asks of the same pose and seed in both are the same
        answer (the search is deterministic)."""
        if moved:
            return "stepped: the child's branch stepped the plant"
        asked = [op for op in mine if op[0] == "ask"]
        theirs = [op for op in record if op[0] == "ask"]
        if not asked or not theirs:
            return ""
        where = {op[2] for op in asked}
        searched_keys = {op[1] for op in asked if op[3] is not None}
        for op in theirs:
            if op[3] is not None and op[2] in where:
                return "shared: both branches asked IK of the same release pose"
            if op[3] is None and op[1] in searched_keys:
                return "shared: a plain IK ask the parent's branch searched"
        warm = self.tuning.ik_warm
        if warm is None:
            return ""
        near = _near_poses([op[3] for op in asked], [op[3] for op in theirs], *warm)
        return "near: both branches searched release poses within ik_warm" if near else ""


def lower_outcomes(plan: Callable[..., Any], bounds: list[Any], beat: float | None) -> list[Any]:
    """`plan(b, beat, lower=True)` for each of the lower release `bounds`: its plan, or the
    UnreachableTarget / IKFailed it raised (`Planner._plan_tier`'s forked branch)."""
    out: list[Any] = []
    for b in bounds:
        try:
            out.append(plan(b, beat, lower=True))
        except (UnreachableTarget, IKFailed) as exc:
            out.append(exc.with_traceback(None))
    return out


def _near_poses(a: list[Any], b: list[Any], within_m: float, within_rad: float) -> bool:
    """Is a pose of `a` within `within_m` [m] and `within_rad` [rad] of one of `b`, at the
    same roll (None: a pose of a search that keeps no warm start nor far pose)?"""
    a = [p for p in a if p is not None]
    b = [p for p in b if p is not None]
    for roll in {repr(p.roll) for p in a}:
        pa = [p for p in a if repr(p.roll) == roll]
        pb = [p for p in b if repr(p.roll) == roll]
        if not pb:
            continue
        xa, xb = np.array([p.position for p in pa]), np.array([p.position for p in pb])
        ua, ub = np.array([p.axis for p in pa]), np.array([p.axis for p in pb])
        gap = xa[:, None, :] - xb[None, :, :]
        close = np.einsum("ijk,ijk->ij", gap, gap) <= within_m * within_m
        close &= ua @ ub.T >= math.cos(within_rad)
        if close.any():
            return True
    return False
