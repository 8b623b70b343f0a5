"""Campaigns of independent simulations, serial or on Ray.

`run_campaign(fn, units, workers=N, address=...)` maps a top-level function over
picklable units of work (a layout, an object, a case) and returns the results
in unit order:

- `workers=1` and no address: in this process, one unit after the other; Ray is
  not imported (the default on one machine);
- `workers>1`: a new local Ray with that many CPUs is started (always a new one:
  a cluster that `ray start --head` runs on the same machine is joined only when
  named), unless `address` (or the RAY_ADDRESS environment variable) names a
  running cluster to join; then the cluster's CPUs decide how many units run at
  once. Each unit is one Ray task, so each task's worker process builds its own
  PyBullet client and model. Tasks, not actors: Ray's scheduler balances the
  load and retries a task whose process died, and nothing is shared between
  units, which is what makes the results identical to the serial run (every
  unit carries its own seed; a scene campaign's unit builds its own scene).

The driver is the only writer: `on_result(index, result)` is called here, in
the driver, as each result arrives (in completion order, not unit order; that is
where a caller appends rows to its throw-log store, each in its own
transaction), so a worker that dies loses nothing already written.

Failures. A task whose worker process dies (killed, out of memory, node lost) is
retried by Ray `retries` times (default once); if it dies again, the campaign
stops with `CampaignFailed` naming the unit, after cancelling the outstanding
tasks. A unit whose function raises is not retried (the simulations are
seeded: it would raise again) and is reported the same way, with its error
(in-process, the function's error itself is raised).
Ctrl-C cancels the outstanding tasks and raises KeyboardInterrupt; what
`on_result` has handled is kept.

At most 2 × (the CPUs Ray offers) tasks are in flight at a time: a worker always
finds a queued task, and the driver's bookkeeping stays small for campaigns of
many thousands of units.
"""

from __future__ import annotations

import logging
import os
import socket
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any, TypeVar

from cell.errors import CellError, InvalidInput, MissingDependency

__all__ = ["run_campaign", "add_campaign_args", "CampaignFailed", "one_blas_thread"]

U = TypeVar("U")
R = TypeVar("R")

_REPR_MAX = 160  # characters of a unit's repr in a message


class CampaignFailed(CellError, RuntimeError):
    """A unit of a campaign failed on its worker (after Ray's retry for a dead worker)."""


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Numpy's and scipy's BLAS on one thread within (each library's count given back after).

    The cell's linear algebra is small (toppra's spline through three waypoints solves a
    3 x 3 system with `scipy.linalg.solve`): OpenBLAS waking a second thread for it cost
    about 8 ms of CPU where one thread takes 0.1 ms, and one thread gives the same sums in
    every process, serially or on a Ray worker (OMP_NUM_THREADS=1 there). scipy's own
    OpenBLAS is loaded first: threadpoolctl limits only the libraries already loaded, and a
    job loads scipy's only when it first plans."""
    import scipy.linalg  # noqa: F401 - loaded to be limited with numpy's
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        yield


def add_campaign_args(p: Any) -> None:
    """`--workers N` and `--ray-address ADDR` on an argparse parser."""
    p.add_argument(
        "--workers",
        type=int,
        default=1,
        help="parallel workers on Ray (1: in this process, no Ray)",
    )
    p.add_argument(
        "--ray-address",
        metavar="ADDR",
        help="join this Ray cluster (e.g. 10.0.0.5:6379, or 'auto'; default: $RAY_ADDRESS)",
    )


def _unit_text(unit: Any) -> str:
    text = repr(unit)
    return text if len(text) <= _REPR_MAX else text[: _REPR_MAX - 1] + "…"


def run_campaign(
    fn: Callable[[U], R],
    units: Sequence[U],
    *,
    workers: int = 1,
    address: str | None = None,
    desc: str = "campaign",
    on_result: Callable[[int, R], None] | None = None,
    progress: bool = True,
    retries: int = 1,
) -> list[R]:
    """Run `fn` on every unit; results in unit order.

    Args:
        fn: a module-level function (Ray pickles it by reference).
        units: picklable units of work.
        workers: 1 runs in-process; N > 1 runs N at a time on a local Ray.
        address: a Ray cluster to join (default: $RAY_ADDRESS when workers > 1).
        desc: the progress bar's label.
        on_result: called in the driver with (unit index, result) as results arrive.
        progress: show one progress bar for the whole campaign (on stderr, on a terminal).
        retries: how many times Ray runs again a task whose worker process died.

    Raises:
        InvalidInput: workers < 1 or retries < 0; an address where no Ray answers.
        MissingDependency: workers > 1 and ray is not installed.
        CampaignFailed: on Ray, a unit's function raised on its worker, or its worker
            died on every try (in-process, the function's own error is raised).
        KeyboardInterrupt: Ctrl-C (the outstanding tasks are cancelled first).
    """
    from tqdm import tqdm

    if workers < 1:
        raise InvalidInput(f"--workers {workers}: give 1 or more")
    if retries < 0:
        raise InvalidInput(f"retries={retries}: give 0 or more")
    address = address or (os.environ.get("RAY_ADDRESS") if workers > 1 else None)
    bar = tqdm(
        total=len(units),
        desc=desc,
        unit="unit",
        file=sys.stderr,
        disable=None if progress else True,
    )
    try:
        if workers == 1 and not address:
            out: list[R] = []
            for i, u in enumerate(units):
                r = fn(u)  # an error is raised as it is, in this process
                out.append(r)
                if on_result is not None:
                    on_result(i, r)
                bar.update(1)
            return out
        return _run_ray(fn, units, workers, address, on_result, bar, retries)
    finally:
        bar.close()


def _check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """Fail fast when nothing listens at a host:port address (ray.init would wait minutes).

    "auto" and addresses without a port are left to Ray.

    Raises:
        InvalidInput: the connection is refused or times out.
    """
    hostport = address.split("://", 1)[-1]
    host, sep, port = hostport.rpartition(":")
    if not sep or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]") or "127.0.0.1", int(port)), timeout_s):
            pass
    except OSError as exc:
        raise InvalidInput(
            f"--ray-address {address}: no Ray cluster answers there ({exc}); start its head "
            "with `ray start --head --port=6379` and give HEAD_IP:6379, or leave the address "
            "out to start a local Ray"
        ) from None


def _init_ray(workers: int, address: str | None) -> bool:
    """Connect to (or start) Ray; True when this call started it (and must shut it down)."""
    try:
        import ray
    except ImportError:
        raise MissingDependency(
            f"--workers {workers} needs Ray: pip install 'ray>=2.40' (or --workers 1)"
        ) from None
    if address:
        _check_reachable(address)
    if ray.is_initialized():  # e.g. a test's Ray, or a caller's own cluster connection
        return False
    quiet = {"log_to_driver": False, "logging_level": logging.ERROR}
    if address:
        try:
            ray.init(address=address, **quiet)  # type: ignore[arg-type]
        except (ConnectionError, ValueError, RuntimeError) as exc:
            raise InvalidInput(f"--ray-address {address}: cannot join that Ray ({exc})") from None
    else:
        # "local": a new instance even when `ray start --head` runs here (ray.init() would
        # join that one, and refuse num_cpus for it)
        ray.init(address="local", num_cpus=workers, include_dashboard=False, **quiet)  # type: ignore[arg-type]
    return True


def _run_ray(
    fn: Callable[[Any], Any],
    units: Sequence[Any],
    workers: int,
    address: str | None,
    on_result: Callable[[int, Any], None] | None,
    bar: Any,
    retries: int,
) -> list[Any]:
    started = _init_ray(workers, address)
    import ray

    try:
        cpus = int(ray.cluster_resources().get("CPU", workers))
        in_flight = max(2, 2 * cpus)
        task = ray.remote(max_retries=retries, retry_exceptions=False, num_cpus=1)(fn)
        results: list[Any] = [None] * len(units)
        refs: dict[Any, int] = {}
        pending: list[Any] = []
        next_unit = 0
        try:
            while next_unit < len(units) or pending:
                while next_unit < len(units) and len(pending) < in_flight:
                    ref = task.remote(units[next_unit])
                    refs[ref] = next_unit
                    pending.append(ref)
                    next_unit += 1
                done, pending = ray.wait(pending, num_returns=1)
                ref = done[0]
                i = refs.pop(ref)
                try:
                    r = ray.get(ref)
                except ray.exceptions.RayTaskError as exc:  # fn raised: not retried
                    cause = exc.cause if exc.cause is not None else exc
                    _cancel(ray, pending)
                    raise CampaignFailed(
                        f"unit {i} ({_unit_text(units[i])}) failed: {type(cause).__name__}: {cause}"
                    ) from None
                except ray.exceptions.RayError as exc:  # the worker died on every try
                    _cancel(ray, pending)
                    first_line = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
                    raise CampaignFailed(
                        f"unit {i} ({_unit_text(units[i])}) was lost: its worker died "
                        f"{retries + 1} time(s) ({type(exc).__name__}: {first_line}); the "
                        f"{len(units) - next_unit + len(pending)} units not yet done are "
                        "cancelled, what was handled before is kept"
                    ) from None
                results[i] = r
                if on_result is not None:
                    on_result(i, r)
                bar.update(1)
        except KeyboardInterrupt:
            _cancel(ray, pending)
            raise
        return results
    finally:
        if started:
            ray.shutdown()


def _cancel(ray: Any, pending: list[Any]) -> None:
    for p in pending:
        try:
            ray.cancel(p, force=True)
        except Exception:  # noqa: BLE001 - finished or gone meanwhile: nothing to cancel
            pass
