"""The order test files are handed to `make test`'s workers: the slowest first.

`make test` runs `pytest -n 2 --dist loadfile --no-loadscope-reorder`: each file goes
whole to the next free worker, in collection order. pytest-xdist's own order (the
files with the most tests first) left the slow files of few tests to the end, one
worker running the last of them alone: 4.9 % and 3.5 % over the even split in two
measured runs of the suite (`--durations=0`, each file's sum handed out in that order
to 2 workers). With the files below first, the rest in name order, the same sums come
within 0.4 % and 0.2 % of it. The list is the slowest files of a measured run (see
SLOW_FILES); it orders, it never selects: a file missing from it, or renamed,
runs in its place by name.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from threadpoolctl import threadpool_limits

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

# slow first, from `pytest -n 2 --dist loadfile --durations=0 tests` (per-file sums): the
# sixteen slowest files of the run at cd14b54 (2026-11-30, 805 s of test time), with the
# savings of branch `suite9` (each changed test's fresh-process CPU ratio before/after applied
# to its own duration; the gap files as in that run), slowest first; handed out so, the
# estimated sums end within 0.2 s of each other (0.4 s with the sixteen listed before)
SLOW_FILES = (
    "test_parallel.py",
    "test_gap_rules.py",
    "test_gap_laws.py",
    "test_gap_scene.py",
    "test_same_result.py",
    "test_gap_jet.py",
    "test_gap.py",
    "test_envelope_edges.py",
    "test_residual_learning.py",
    "test_departure.py",
    "test_accounting.py",
    "test_carry.py",
    "test_release_choice.py",
    "test_record_run.py",
    "test_grip_probe.py",
    "test_release_search_cost.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    rank = {name: k for k, name in enumerate(SLOW_FILES)}
    # a stable sort on the file alone: each file's tests stay together and in their order
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))


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
