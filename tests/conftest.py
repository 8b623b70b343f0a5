"""The order test files are handed to `make test`'s workers: the heaviest first.

`make test` runs `pytest -n 2 --dist loadfile --no-loadscope-reorder`: each file goes
whole to the next free worker, in collection order. The files go in the order of their
weights (tests/file_weights.py: each file's seconds in a measured run of the whole suite),
heaviest first, so that the last files handed out are short and the two workers end
together. A file the table does not know (new or renamed) goes first: run last, a slow one
would leave the other worker idle for its length. The weights order, they never select.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from threadpoolctl import threadpool_limits

from tests.file_weights import WEIGHTS

# One BLAS thread in each test process and the processes it starts (the `cell` CLI in a
# subprocess, Ray's workers take OMP_NUM_THREADS=1 themselves): `make test`'s two workers
# on two cores each woke two OpenBLAS threads for every small solve (toppra's splines: a
# 3 x 3 `scipy.linalg.solve` took 8 ms of CPU, 0.05 ms on one thread), which spin while the
# other worker holds the core: tests/test_tall_item.py 14.9 -> 10.0 CPU-s. A layout gives
# the same numbers on one thread (`cell bench sort` runs each so, cell/bench/bench_sort.py).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
threadpool_limits(limits=1)
# One planning process per decision (`cell.arm.fork`): the suite's two workers already use
# both cores, so a second planning process would add CPU and save no wall time; the tests
# of the forked planning (tests/test_plan_fork.py) ask for two themselves
os.environ["CELL_PLAN_WORKERS"] = "1"


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    # a stable sort on the file alone: each file's tests stay together and in their order
    items.sort(key=lambda item: -WEIGHTS.get(item.path.name, float("inf")))


class Calls:
    """How many times a counted function was called since the last `reset`."""

    def __init__(self) -> None:
        self.n = 0

    def reset(self) -> None:
        self.n = 0


@pytest.fixture
def ik_solve_calls(monkeypatch: pytest.MonkeyPatch) -> Calls:
    """`cell.robot.ik.solve_ik` counted while the real solver runs: for tests that a pose
    searched once is not searched again (`reset` before the calls to count)."""
    from cell.robot import ik

    calls = Calls()
    real = ik.solve_ik

    def counting(*args: object, **kwargs: object) -> object:
        calls.n += 1
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(ik, "solve_ik", counting)
    return calls


@pytest.fixture(scope="module")
def orchestrator_on(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[..., Any]]:
    """A maker of orchestrators on a job's text, closed when the module's tests end:
    `orchestrator_on(JOB, "session", cycle_search=True)` (the job parsed as a file in a
    fresh temporary folder named after the session)."""
    from cell.jobs import parse_job
    from cell.orchestrator import Orchestrator

    made: list[Orchestrator] = []

    def make(job_text: str, session: str, **options: Any) -> Orchestrator:
        tmp = tmp_path_factory.mktemp(session)
        o = Orchestrator(parse_job(job_text, str(tmp / "job.yaml")), session=session, **options)
        made.append(o)
        return o

    yield make
    for o in made:
        o.close()
