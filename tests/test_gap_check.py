"""`cell gap check` on a reduced set: the confusion table must be diagonal."""

from __future__ import annotations

import numpy as np

from cell.cli import main
from cell.gap.check import confusion_table, format_check, run_check


def test_check_reduced_set_is_diagonal() -> None:
    truths = ("stroke_offset", "bounce", "none", "unknown")
    rows = run_check(truths, n=200, seed=1)
    t, v, m = confusion_table(rows)
    assert t == list(truths)
    assert np.array_equal(m[:, : len(t)], np.eye(len(t), dtype=int)), format_check(rows)
    for r in rows:
        assert r.correct, format_check(rows)
        if r.truth not in ("none", "unknown"):
            # the shrink found is close to what the true effect allows
            assert r.shrink_found_pct > r.shrink_allowed_pct - 10


def test_cli_check_rejects_unknown_truth(capsys) -> None:
    assert main(["gap", "check", "--truths", "gremlins"]) == 2
    assert "unknown" in capsys.readouterr().err
