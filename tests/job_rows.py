"""A sort job run from its YAML text, for the tests that check what became of each item."""

from __future__ import annotations

from pathlib import Path

from cell.jobs import parse_job
from cell.orchestrator import Orchestrator


def job_rows(
    text: str, tmp_path: Path, session: str, arm: type[Orchestrator] = Orchestrator
) -> list[tuple[str, str, bool]]:
    """(action, failure, in its bin) of each item of the job `text` (read as
    tmp_path/job.yaml), run in the scene by `arm` (the orchestrator, or a subclass that
    watches its public steps); the orchestrator is closed after."""
    o = arm(parse_job(text, str(tmp_path / "job.yaml")), session=session)
    try:
        summary = o.run()
    finally:
        o.close()
    return [(r.action, r.failure, r.in_bin) for r in summary.results]
