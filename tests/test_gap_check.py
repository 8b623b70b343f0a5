"""`cell gap check` on a reduced set: the confusion table must be diagonal."""

from __future__ import annotations

import json
import pickle

import numpy as np

from cell.cli import main
from cell.gap.check import CASES, CheckRow, check_case, confusion_table, format_check, make_cases


def test_check_reduced_set_is_diagonal() -> None:
    # the full set is run by `make figures` (docs/figures/gap_check.json, test_gap_readme.py);
    # here a launch effect, none and an effect outside the vocabulary
    truths = ("stroke_offset", "none", "unknown")
    cases = make_cases(truths, n=100, seed=1)
    rows = []
    for case in cases:
        # a case and its result are plain data: they can be shipped to a worker and back
        assert pickle.loads(pickle.dumps(case)) == case
        out = check_case(case)
        assert json.loads(json.dumps(out)) == out
        rows.append(CheckRow(**out))
    t, v, m = confusion_table(rows)
    assert t == list(truths)
    assert np.array_equal(m[:, : len(t)], np.eye(len(t), dtype=int)), format_check(rows)
    for r in rows:
        assert r.correct, format_check(rows)
        if r.truth not in ("none", "unknown"):
            # the shrink found is close to what the true effect allows
            assert r.shrink_found_pct > r.shrink_allowed_pct - 10


def test_check_covers_other_laws_and_new_cases() -> None:
    """The check's cases include worlds with other laws than the tool's, the new effect,
    tracks-only campaigns, a compound flight gap and effects outside the vocabulary."""
    cases = {c["name"]: c for c in make_cases(CASES, n=100)}
    assert "drag_scale" in cases
    laws = [c for c in cases.values() if "laws" in c]
    assert any(c["options"].get("other_launcher") for c in laws)
    assert any("+" in c["truth"] for c in laws)
    assert sum(c["truth"] == "unknown" for c in cases.values()) >= 2
    assert {c["truth"] for c in laws} >= {"bounce", "downwash", "drag_scale", "tracking_scale"}


def test_cli_check_rejects_unknown_truth(capsys) -> None:
    assert main(["gap", "check", "--truths", "gremlins"]) == 2
    assert "unknown" in capsys.readouterr().err
