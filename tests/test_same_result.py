"""The same result in any process: a job's `cell run --json` is the same bytes run in a fresh
process, in this one after another job, and again after that (the run's throw ids, which
name the run, and its wall time aside); `cell bench sort --set` draws its layouts from the
named set only."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from cell.bench.bench_sort import LAYOUT_SETS, LayoutUnit, first_seed, run_layout
from cell.cli import main
from cell.errors import InvalidInput
from cell.results import WALL_CLOCK_KEYS

ROOT = Path(__file__).resolve().parent.parent

# a throw of a box, a place of a cylinder and a throw of a mesh (the duck: the mesh caches
# of the catalogue and of PyBullet, the grip probe), on the Panda
JOB = """\
cell: {robot: panda}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {object: cube50, count: 1, bin: far}
  - {object: cyl70, count: 1, bin: near}
  - {object: duck, count: 1, bin: far}
"""


def _canonical(path: Path) -> str:
    """The run's JSON without what names the run (its throw ids) and its wall-clock
    figures (`WALL_CLOCK_KEYS`: its wall time, the items' planning times)."""
    d = json.loads(path.read_text())
    for k in WALL_CLOCK_KEYS:  # the wall time, the planning times and what they give
        d.pop(k, None)
    for r in d["results"]:
        r.pop("plan_s")
        tid = r.pop("throw_id")  # a throw's: run-<this run's id>-<item>; a place has none
        assert tid.startswith("run-") if r["action"] == "throw" else tid == ""
    return json.dumps(d, indent=2)


def test_a_job_gives_the_same_json_fresh_after_another_job_and_again(tmp_path: Path) -> None:
    job = tmp_path / "job.yaml"
    job.write_text(JOB)
    fresh = tmp_path / "fresh.json"
    p = subprocess.run(
        [sys.executable, "-m", "cell", "run", str(job), "--no-log", "--json", str(fresh)],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
    )
    assert p.returncode == 0, p.stderr
    # another job first in this process: another arm, another item, other caches filled
    # (its first item only: the layout's second is the same ad-hoc cylinder again)
    other = run_layout(LayoutUnit(seed=1, robot="ur5", max_items=1))
    assert len(other["items"]) == 1
    runs = []
    for k in range(2):
        out = tmp_path / f"in_process_{k}.json"
        assert main(["run", str(job), "--no-log", "--json", str(out)]) == 0
        runs.append(_canonical(out))
    want = _canonical(fresh)
    assert [r["action"] for r in json.loads(want)["results"]] == ["throw", "place", "throw"]
    assert runs[0] == want
    assert runs[1] == want


def test_the_tune_and_test_sets_are_disjoint_and_a_campaign_stays_in_its_set() -> None:
    (t0, t1), (s0, s1) = LAYOUT_SETS["tune"], LAYOUT_SETS["test"]
    assert t0 == 0 and t1 >= 20  # the layouts the arm's constants were chosen on: 0-19
    assert t1 <= s0 < s1  # disjoint
    assert first_seed("test", 20) == s0
    assert first_seed("tune", 20) == 0
    assert first_seed("tune", 4, seed=996) == 996
    with pytest.raises(InvalidInput, match="tune set's seeds are 0–999"):
        first_seed("tune", 4, seed=997)  # would run on into the test set
    with pytest.raises(InvalidInput, match="--set tune"):
        first_seed("test", 20, seed=0)
    with pytest.raises(InvalidInput, match="give one of tune, test"):
        first_seed("train", 1)


@pytest.mark.parametrize("what", ["sort", "tradeoff"])
def test_cli_a_seed_outside_the_set_is_refused_before_any_run(
    what: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bench", what, "--seed", "0", "--layouts", "2"]) == 2
    err = capsys.readouterr().err
    assert "cell: error: --seed 0 --layouts 2: the test set's seeds are 1000" in err
    assert "--set tune" in err
    assert "Traceback" not in err


def test_cli_tradeoff_says_which_set_and_seeds_it_ran(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["bench", "tradeoff", "--set", "tune", "--seed", "3", "--layouts", "1"]
    assert main([*argv, "--max-items", "1", "--scales", "1.0", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["set"] == "tune" and out["seeds"] == [3, 3]
    assert [p["speed_scale"] for p in out["points"]] == [1.0]
    assert out["points"][0]["items"] == 1


def test_the_shared_arm_is_read_only_and_read_from_the_folders_in_use(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import shutil

    import numpy as np

    from cell.robot import load_robot, paths

    panda = load_robot("panda")
    with pytest.raises(ValueError, match="read-only"):
        panda.home[0] = 0.1  # a run cannot change what the next one plans with
    with pytest.raises(ValueError, match="read-only"):
        panda.limits.velocity *= 0.5
    # another robots/ folder: its arm, not the one loaded from the first
    for d in ("throwing_ee", "panda_throwing"):
        shutil.copytree(ROOT / "robots" / d, tmp_path / d)
    mount = tmp_path / "panda_throwing" / "mount.yaml"
    mount.write_text(mount.read_text().replace("home: [0.0,", "home: [0.25,"))
    monkeypatch.setenv(paths.ROBOTS_ENV, str(tmp_path))
    paths.robots_dir.cache_clear()
    try:
        assert load_robot("panda").home[0] == 0.25
    finally:
        monkeypatch.delenv(paths.ROBOTS_ENV)
        paths.robots_dir.cache_clear()
    assert load_robot("panda") is panda
    np.testing.assert_array_equal(panda.home[:1], [0.0])
