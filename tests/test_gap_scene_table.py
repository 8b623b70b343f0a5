"""examples/11_gap_scene_table.py: docs/gap_scene.md's table from the scene check's JSON."""

from __future__ import annotations

import runpy
import sys
from pathlib import Path
from typing import NamedTuple

import pytest

from cell.gap.scene_table import scene_row, scene_table

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "examples/11_gap_scene_table.py"


class Ran(NamedTuple):
    returncode: int
    stdout: str
    stderr: str


def _run(path: Path, capsys: pytest.CaptureFixture[str]) -> Ran:
    """`python examples/11_gap_scene_table.py PATH` run in this process: the script's file
    run as `__main__` with that argv, its exit status and what it wrote. (A child process
    paid the interpreter's start and the import of cell.gap, about 0.9 CPU-s, for no more:
    the script touches neither its file descriptors nor its environment.)"""
    capsys.readouterr()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(sys, "argv", [str(SCRIPT), str(path)])
        with pytest.raises(SystemExit) as ended:
            runpy.run_path(str(SCRIPT), run_name="__main__")
    out, err = capsys.readouterr()
    return Ran(ended.value.code, out, err)  # type: ignore[arg-type]


def test_the_script_prints_the_pages_table(capsys: pytest.CaptureFixture[str]) -> None:
    """The page's table was made outside the repository; the script makes it the same."""
    r = _run(ROOT / "docs/figures/gap_check_scene.json", capsys)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("| case | truth | verdict |")
    assert r.stdout in (ROOT / "docs/gap_scene.md").read_text()


def test_a_row_rounds_as_written() -> None:
    row = {
        "case": "s:wind",
        "truth": "wind",
        "verdict": "wind",
        "phases": {"wind": "flight"},
        "params": {"wind": {"x_mps": 2.4449, "y_mps": -1.0}},
        "laws": {},
        "proposal": "force y [m/s²] = 0.5 + force up [1/m] = 0.1 · |v|² + landing shift [s] = 1",
        "world_truth": {},
        "after_over_floor": 1.005,
        "world_floor_m": 0.0425,
        "passes": False,
    }
    assert scene_row(row) == (
        "| s:wind | wind | wind | wind: flight | wind.x_mps 2.44 (2.5); wind.y_mps -1 (-1.2) "
        "proposal (3 terms): force y [m/s²] = 0.5 + force up [1/m] = 0.1 · \\|v\\|² + … "
        "| 1.00 (F 42 mm) | no |"
    )
    doc = {
        "campaigns": [row],
        "criteria": {"floor_ratio": 1.3},
        "passes": 0,
        "total": 1,
        "diagonal": 1,
        "phase_ok": 1,
        "params_ok": 0,
        "floor_ok": 1,
    }
    assert scene_table(doc).endswith(
        "\n\n0/1 pass; diagonal 1, phase 1, parameters 0, A ≤ 1.3 F 1\n"
    )


@pytest.mark.parametrize(
    "text", ["not json", "[1, 2]", '{"campaigns": [{}]}', "[" * 100000 + "]" * 100000]
)
def test_a_file_that_is_not_the_checks_json_is_refused(
    tmp_path: Path, text: str, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "x.json"
    path.write_text(text)
    r = _run(path, capsys)
    assert r.returncode == 2
    assert r.stderr.startswith(f"cell: error: {path}: ") and "Traceback" not in r.stderr
    assert path.read_text() == text


def test_a_missing_file_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    r = _run(tmp_path / "none.json", capsys)
    assert r.returncode == 2 and r.stderr.startswith("cell: error: ")
    assert not (tmp_path / "none.json").exists()


def test_a_per_object_law_is_shown_object_by_object() -> None:
    row = {
        "case": "s:drag-const",
        "truth": "drag_scale",
        "verdict": "drag_scale",
        "phases": {"drag_scale": "flight"},
        "params": {"drag_scale": {"common": 2.7836, "spread": 0.3166,
                                  "per_object": {"sphere40": 3.16, "cube30": 2.7264}}},
        "laws": {"drag_scale": "factor = a_object"},
        "proposal": None,
        "world_truth": {},
        "after_over_floor": 0.8212,
        "world_floor_m": 0.0519,
        "passes": True,
    }  # fmt: skip
    assert scene_row(row) == (
        "| s:drag-const | drag_scale | drag_scale | drag_scale: flight | drag_scale.common 2.78; "
        "drag_scale.spread 0.317; drag_scale.sphere40 3.16; drag_scale.cube30 2.73 — factor = "
        "a_object | 0.82 (F 52 mm) | yes |"
    )


def test_a_floor_raised_by_the_effects_own_scatter_shows_its_effect_free_part() -> None:
    """F0 (the effect-free throws' floor) is shown where the effect's repeat scatter raises
    F by a millimetre or more: a tumbling block's, not a wind's."""
    row = {
        "case": "s:bounce-slide", "truth": "bounce", "verdict": "bounce",
        "phases": {"bounce": "landing"}, "params": {}, "laws": {}, "world_truth": {},
        "after_over_floor": 1.1, "world_floor_m": 0.0837, "world_floor0_m": 0.0363,
        "passes": True,
    }  # fmt: skip
    assert scene_row(row).endswith("| 1.10 (F 84 mm, F0 36) | yes |")
    row.update(world_floor_m=0.0425, world_floor0_m=0.0421)
    assert scene_row(row).endswith("| 1.10 (F 42 mm) | yes |")


def test_a_floor_on_the_kept_rows_is_shown_with_the_floor_on_every_row() -> None:
    """The ratio is judged on the floor counted on the rows A was counted on; where the
    flagged rows move the floor by a millimetre or more, the floor with them is beside it."""
    row = {
        "case": "s:bounce-slide", "truth": "bounce", "verdict": "unknown",
        "phases": {}, "params": {}, "laws": {}, "world_truth": {},
        "after_over_floor": 1.55, "world_floor_m": 0.0837, "world_floor0_m": 0.0363,
        "world_floor_kept_m": 0.0501, "world_floor0_kept_m": 0.0360, "passes": False,
    }  # fmt: skip
    assert scene_row(row).endswith("| 1.55 (F 50 mm, F0 36; 84 with the flagged rows) | no |")
    row.update(world_floor_kept_m=0.0835, world_floor0_kept_m=0.0362)
    assert scene_row(row).endswith("| 1.55 (F 84 mm, F0 36) | no |")
