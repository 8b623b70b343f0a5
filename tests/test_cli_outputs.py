"""Every command checks its outputs and seed before it starts work: a clear error, exit 2,
no traceback and no file written."""

from __future__ import annotations

from pathlib import Path

import pytest

from cell.cli import main


def _cases(tmp: Path) -> list[tuple[list[str], str]]:
    missing = tmp / "no_such_folder"
    return [
        (["synth", "-o", str(tmp), "--n", "5"], "is a folder"),
        (["synth", "-o", str(missing / "t.csv"), "--n", "5"], "does not exist"),
        (["synth", "-o", str(tmp / "t.csv"), "--n", "5", "--seed", "-1"], "--seed -1"),
        (["synth", "-o", str(tmp / "t.csv"), "--n", "5", "--seed", str(2**40)], "--seed"),
        (["predict", "tasks/bins.yaml", "-o", str(tmp)], "is a folder"),
        (["identify", "t.csv", "-o", str(missing / "ee.yaml")], "does not exist"),
        (["learn", "t.csv", "-o", str(tmp)], "is a folder"),
        (["gap", "t.csv", "--json", str(missing / "r.json")], "does not exist"),
        (["gap", "t.csv", "--report", str(tmp)], "is a folder"),
        (["log", "export", "-o", str(tmp)], "is a folder"),
        (["run", "tasks/bins.yaml", "--json", str(missing / "o.json")], "does not exist"),
        (["run", "tasks/bins.yaml", "--snapshot", str(tmp)], "is a folder"),
        (["run", "tasks/bins.yaml", "--emulate"], "--ee dynamixel"),
    ]


@pytest.mark.parametrize("k", range(13))
def test_bad_output_or_seed_is_refused_before_any_work(
    k: int, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv, expected = _cases(tmp_path)[k]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("cell: error: "), err
    assert expected in err and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []
