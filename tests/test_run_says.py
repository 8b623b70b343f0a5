"""What `cell run` says to its reader: the closing table of a run whose every item missed
its bin, and the plant's warning of an item's motion beside the CLI's own warnings."""

from __future__ import annotations

import json
import logging
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import cell
from cell.cli import main

ROOT = Path(cell.__file__).resolve().parents[1]
STATION = "cell: {robot: panda}\npick_station: {position_m: [0.45, -0.40, 0.20]}\n"
# a 4 g cube thrown 2.6 m: lighter than the lightest calibrated object, it falls 0.83 m
# short (the job check warns of it); every item of the job misses its bin
MISSED = (
    f"{STATION}bins:\n"
    "  - {id: far, position_m: [2.6, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}\n"
    "items:\n"
    "  - {shape: cube, mass_kg: 0.004, size_m: [0.05, 0.05, 0.05], bin: far}\n"
)
# a 3 mm plate placed flat: the pads, longer than it is high, meet the bin's floor before
# it touches down, and the place back-end warns of it (it still comes to rest in the bin)
FLAT = (
    f"{STATION}bins:\n"
    "  - {id: near, position_m: [0.55, 0.35], size_m: [0.3, 0.3], rim_height_m: 0.12}\n"
    "items:\n"
    "  - {shape: cuboid, mass_kg: 0.02, size_m: [0.1, 0.1, 0.003], bin: near}\n"
)
PLACE_WARNING = "place: the item had not touched down when the fingers opened"


def _rows(out: str) -> dict[str, str]:
    """The closing table's rows, `  label   value`, label -> value."""
    return {
        m.group(1): m.group(2)
        for m in re.finditer(r"^  (\S.*?\S) {2,}(\S.*)$", out, re.M)
        if not m.group(1)[0].isdigit()
    }


def test_a_run_whose_every_item_missed_says_so_in_its_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The table's `failed` row counted the items stopped before their release alone, so a
    run whose every item missed its bin read `failed 0` (exit 4). The rows are counted
    against the JSON's item results: placed, thrown and not released partition the items,
    and `not in their bin` counts every item not at rest in its bin."""
    job = tmp_path / "missed.yaml"
    job.write_text(MISSED)
    out_json = tmp_path / "run.json"
    capsys.readouterr()
    code = main(["run", str(job), "--no-log", "-q", "--json", str(out_json)])
    out = capsys.readouterr().out
    results = json.loads(out_json.read_text())["results"]
    assert code == 4 and results and not any(r["in_bin"] for r in results)  # all missed
    rows = _rows(out)
    by_action = {a: sum(r["action"] == a for r in results) for a in ("place", "throw", "failed")}
    assert int(rows["placed"]) == by_action["place"]
    assert int(rows["thrown"]) == by_action["throw"] == len(results)
    assert int(rows["not released"]) == by_action["failed"] == 0
    assert "failed" not in rows, rows  # no row reads `failed 0` beside every item missed
    n_out = sum(not r["in_bin"] for r in results)
    assert rows["not in their bin"] == f"{n_out} (missed_bin {n_out})", rows
    assert rows["in the right bin"] == "0 (0.0 %)"
    # --json's keys are as before: `failed` counts the items not released
    summary = json.loads(out_json.read_text())
    assert (summary["failed"], summary["in_bin"]) == (0, 0)


def test_the_place_warning_is_the_clis_and_q_silences_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture
) -> None:
    """The place back-end's warning was `WARNING cell.endeffector.pybullet_backend: …`
    through logging's default format, under `-q` too. It is `cell: warning: …`, as the
    CLI's own, and `-q` silences it with the items' lines (the job's warnings stay)."""
    job = tmp_path / "flat.yaml"
    job.write_text(FLAT)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "cell", "run", str(job), "--no-log"]
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert res.returncode == 0, res.stderr
    assert f"cell: warning: {PLACE_WARNING}" in res.stderr, res.stderr
    assert "WARNING" not in res.stderr and "[1/1] item 0" in res.stderr, res.stderr
    # -q, in this process (the same run): no warning record reaches logging's handlers
    caplog.set_level(logging.WARNING)
    capsys.readouterr()
    assert main(["run", str(job), "--no-log", "-q"]) == 0
    err = capsys.readouterr().err
    assert PLACE_WARNING not in err + caplog.text and "[1/1]" not in err, caplog.text
    assert logging.getLogger("cell").level == logging.NOTSET  # put back after the run
