"""`cell run` works on one BLAS thread, as `cell bench sort` does, and a spline through
three waypoints (the 3 x 3 solve that woke OpenBLAS's second thread) is the same to the
bit on one thread as on two."""

import argparse
import ast
import os
import subprocess
import sys

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import cell.cli.cmd_run as cmd_run


def _blas_threads():
    return {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


def test_the_run_works_on_one_blas_thread_and_gives_the_threads_back(monkeypatch):
    seen = []
    monkeypatch.setattr(cmd_run, "_run", lambda args: seen.append(_blas_threads()) or 7)
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert 2 in before.values()
        assert cmd_run.run(argparse.Namespace()) == 7
        after = _blas_threads()
        assert {path: after[path] for path in before} == before
    assert len(seen) == 1 and set(seen[0].values()) == {1}


@pytest.mark.parametrize(
    "module, entry",
    [("cell.cli.cmd_run", "run"), ("cell.bench.bench_sort", "run_layout")],
)
def test_the_libraries_the_job_loads_later_are_on_one_thread_too(module, entry):
    # a fresh process, its OpenBLAS libraries started on two threads: the job loads
    # scipy's (toppra's splines) only once it plans, after `run` began
    code = (
        f"import {module} as m\n"
        "from threadpoolctl import threadpool_info\n"
        "def probe(args):\n"
        "    import toppra  # noqa: F401\n"
        "    print(sorted((i['filepath'], i['num_threads']) for i in threadpool_info()\n"
        "                 if i['user_api'] == 'blas'))\n"
        "    return 0\n"
        f"m._{entry} = probe\n"
        f"m.{entry}(None)\n"
    )
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env["OPENBLAS_NUM_THREADS"] = "2"
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout
    libs = ast.literal_eval(out.strip().splitlines()[-1])
    assert any("scipy.libs" in path for path, _ in libs)  # scipy's own, beside numpy's
    assert len(libs) >= 2 and all(threads == 1 for _, threads in libs)


def test_a_spline_through_three_waypoints_is_the_same_on_one_blas_thread_as_on_two():
    import toppra as ta

    rng = np.random.default_rng(5)
    s = np.linspace(0.0, 1.0, 101)
    for _ in range(20):
        ss = np.array([0.0, rng.uniform(0.1, 0.9), 1.0])
        way = rng.uniform(-2.0, 2.0, size=(3, 7))
        answers = []
        for threads in (1, 2):
            with threadpool_limits(limits=threads, user_api="blas"):
                path = ta.SplineInterpolator(ss, way)
                answers.append([np.asarray(path(s, k)).tobytes() for k in (0, 1, 2)])
        assert answers[0] == answers[1]
