"""The diagnosis page's `cell gap check` table (docs/diagnosis.md, moved there from the
README) is the last generated check (docs/figures/gap_check.json, written by `make figures`):
every row quoted matches the JSON, and the check was diagonal."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from cell.gap.check import CASES

ROOT = Path(__file__).resolve().parents[1]


def test_readme_gap_check_table_is_the_last_generated_check() -> None:
    readme = (ROOT / "docs" / "diagnosis.md").read_text()
    check = json.loads((ROOT / "docs/figures/gap_check.json").read_text())
    assert check["correct"] == check["total"] == len(CASES)
    assert [c["case"] for c in check["campaigns"]] == list(CASES)
    m = re.search(r"(\d+)/(\d+) verdicts right", readme)
    assert m and (int(m[1]), int(m[2])) == (check["correct"], check["total"])
    for c in check["campaigns"]:
        row = re.search(
            rf"\| `{re.escape(c['case'])}` \|[^|]*\| ([\w+]+) \| (\w+) \| ([\d.]+) \| ([\d.]+) \| "
            r"([\d.]+) \|",
            readme,
        )
        assert row, c["case"]
        assert row[1] == c["verdict"] == c["truth"]
        assert row[2] == c["where"]
        assert float(row[3]) == pytest.approx(c["noise_floor_m"], abs=5e-5)
        assert float(row[4]) == pytest.approx(c["baseline_m"], abs=5e-5)
        assert float(row[5]) == pytest.approx(c["after_m"] / c["noise_floor_m"], abs=5e-3)
