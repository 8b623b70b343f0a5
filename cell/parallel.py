"""Campaigns of independent simulations, serial or on Ray.

`run_campaign(fn, units, workers=N, address=...)` maps a top-level function over
picklable units of work (a layout, an object, a case) and returns the results
in unit order:

- `workers=1` and no address: in this process, one unit after the other; Ray is
  not imported (the default on one machine);
- `workers>1`: a local Ray with that many CPUs is started, unless `address` (or
  the RAY_ADDRESS environment variable) names a running cluster to join; each
  unit is one Ray task, so each task's worker process builds its own PyBullet
  client and model (nothing is shared between units, which is what makes the
  results identical to the serial run: every unit carries its own seed).

The driver is the only writer: `on_result(index, result)` is called here, in
the driver, as each result arrives (that is where a caller appends rows to its
throw-log store, each in its own transaction), so a worker that dies loses
nothing already written. A task whose worker process dies is retried once by
Ray (`max_retries=1`); a unit whose function raises is not retried (it would
raise again: the simulation is deterministic) and is reported as a CellError
naming the unit. Ctrl-C cancels the outstanding tasks; what `on_result` has
handled is kept.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from cell.errors import CellError, InvalidInput

__all__ = ["run_campaign", "add_campaign_args", "CampaignFailed"]

U = TypeVar("U")
R = TypeVar("R")


class CampaignFailed(CellError, RuntimeError):
    """A unit of a campaign failed on its worker (after Ray's retry for a dead worker)."""


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


def run_campaign(
    fn: Callable[[U], R],
    units: Sequence[U],
    *,
    workers: int = 1,
    address: str | None = None,
    desc: str = "campaign",
    on_result: Callable[[int, R], None] | None = None,
    progress: bool = True,
) -> list[R]:
    """Run `fn` on every unit; results in unit order.

    Args:
        fn: a module-level function (Ray pickles it by reference).
        units: picklable units of work.
        workers: 1 runs in-process; N > 1 runs N at a time on Ray.
        address: a Ray cluster to join (default: $RAY_ADDRESS when workers > 1).
        desc: the progress bar's label.
        on_result: called in the driver with (unit index, result) as results arrive.
        progress: show one progress bar for the whole campaign (on stderr).

    Raises:
        InvalidInput: workers < 1.
        CampaignFailed: a unit's function raised on its worker.
    """
    from tqdm import tqdm

    if workers < 1:
        raise InvalidInput(f"--workers {workers}: give 1 or more")
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
                r = fn(u)
                out.append(r)
                if on_result is not None:
                    on_result(i, r)
                bar.update(1)
            return out
        return _run_ray(fn, units, workers, address, on_result, bar)
    finally:
        bar.close()


def _run_ray(
    fn: Callable[[Any], Any],
    units: Sequence[Any],
    workers: int,
    address: str | None,
    on_result: Callable[[int, Any], None] | None,
    bar: Any,
) -> list[Any]:
    import ray

    started = False
    if not ray.is_initialized():
        if address:
            ray.init(address=address, log_to_driver=False, logging_level=logging.ERROR)
        else:
            ray.init(
                num_cpus=workers,
                include_dashboard=False,
                log_to_driver=False,
                logging_level=logging.ERROR,
            )
        started = True
    try:
        task = ray.remote(max_retries=1, retry_exceptions=False, num_cpus=1)(fn)
        refs = {task.remote(u): i for i, u in enumerate(units)}
        results: list[Any] = [None] * len(units)
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                ref = done[0]
                i = refs[ref]
                try:
                    r = ray.get(ref)
                except ray.exceptions.RayError as exc:
                    for p in pending:
                        ray.cancel(p, force=True)
                    raise CampaignFailed(
                        f"unit {i} ({units[i]!r}) failed on its worker: {exc}"
                    ) from None
                results[i] = r
                if on_result is not None:
                    on_result(i, r)
                bar.update(1)
        except KeyboardInterrupt:
            for p in pending:
                ray.cancel(p, force=True)
            raise
        return results
    finally:
        if started:
            ray.shutdown()
