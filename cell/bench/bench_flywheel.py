"""The flywheel between runs: `cell run --learn` twice into a fresh store.

Each job is run twice with `--learn` into a new throw-log store: the first run has no
earlier throws to learn from (it plans as `cell run` does, and its throws go to the
store), the second refits the job's objects from them before it starts. The figures,
per job: the mean and median landing error of the items thrown in both runs, first run
and second run, how many landed closer the second time, and how many of the job's items
came to rest in their bins each time.

    python -m cell.bench.bench_flywheel [--json OUT.json]

runs `tasks/bins.yaml` and `cell job random --seed 3 --robot ur5` (one step of `make
figures`, `docs/figures/flywheel.json`).
"""

from __future__ import annotations

import json
import math
import tempfile
from contextlib import redirect_stdout
from io import StringIO
from pathlib import Path
from statistics import median
from typing import Any

from cell.outfile import write_whole

__all__ = ["flywheel", "main"]

DEMO_JOB = Path(__file__).resolve().parents[2] / "tasks" / "bins.yaml"


def _run(job: Path, db: Path, out: Path) -> dict[str, Any]:
    from cell.cli import main as cell_main

    with redirect_stdout(StringIO()):  # the run's table: only its JSON is wanted here
        cell_main(["run", str(job), "--learn", "--db", str(db), "--json", str(out)])
    doc: dict[str, Any] = json.loads(out.read_text())
    return doc


def flywheel(job: Path, workdir: Path) -> dict[str, Any]:
    """Run `job` twice with --learn into a fresh store under `workdir`; its figures."""
    db = workdir / f"{job.stem}.sqlite"
    first = _run(job, db, workdir / f"{job.stem}_1.json")
    second = _run(job, db, workdir / f"{job.stem}_2.json")
    pairs = [
        (a["landing_error_m"], b["landing_error_m"])
        for a, b in zip(first["results"], second["results"], strict=True)
        if a["action"] == "throw" and b["action"] == "throw"
    ]
    pairs = [(a, b) for a, b in pairs if a is not None and b is not None]
    n = len(pairs)
    return {
        "items": first["items"],
        "thrown_both": n,
        "mean_landing_error_first_m": sum(a for a, _ in pairs) / n if n else math.nan,
        "mean_landing_error_second_m": sum(b for _, b in pairs) / n if n else math.nan,
        "median_landing_error_first_m": median(a for a, _ in pairs) if n else math.nan,
        "median_landing_error_second_m": median(b for _, b in pairs) if n else math.nan,
        "second_closer": sum(b < a for a, b in pairs),
        "in_bin_first": first["in_bin"],
        "in_bin_second": second["in_bin"],
    }


def main(argv: list[str] | None = None) -> int:
    """`python -m cell.bench.bench_flywheel [--json OUT.json]`."""
    import argparse

    from cell.cli import main as cell_main

    ap = argparse.ArgumentParser(prog="python -m cell.bench.bench_flywheel")
    ap.add_argument("--json", default=None, help="write the figures here")
    args = ap.parse_args(argv)
    doc: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        layout = work / "random_3_ur5.yaml"
        with redirect_stdout(StringIO()):
            cell_main(["job", "random", "--seed", "3", "--robot", "ur5", "-o", str(layout)])
        for name, job in (("bins", DEMO_JOB), ("random_3_ur5", layout)):
            doc[name] = flywheel(job, work)
            f = doc[name]
            print(
                f"{name}: mean landing error {1e3 * f['mean_landing_error_first_m']:.1f} → "
                f"{1e3 * f['mean_landing_error_second_m']:.1f} mm (median "
                f"{1e3 * f['median_landing_error_first_m']:.1f} → "
                f"{1e3 * f['median_landing_error_second_m']:.1f} mm) over {f['thrown_both']} "
                f"items thrown both times, {f['second_closer']} closer the second time; in bin "
                f"{f['in_bin_first']}/{f['items']} → {f['in_bin_second']}/{f['items']}"
            )
    if args.json:
        text = json.dumps(doc, indent=2) + "\n"
        write_whole(args.json, lambda p: p.write_text(text))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
