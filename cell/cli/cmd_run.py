"""`cell run JOB.yaml`: a sort job in the PyBullet cell, with a progress bar and a closing table."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from cell.cli.common import to_jsonable
from cell.jobs import load_job
from cell.kinds import EE_BACKENDS


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a sort job (YAML) in the cell")
    p.add_argument("job", help="job file, e.g. tasks/bins.yaml")
    p.add_argument("--gui", action="store_true", help="show the PyBullet GUI")
    p.add_argument("--json", metavar="OUT.json", help="write the summary as JSON")
    p.add_argument("--snapshot", metavar="OUT.png", help="render the scene at the end (headless)")
    p.add_argument(
        "--db", metavar="PATH", help="throw-log store (default: $CELL_LOG_DB or cell_log.sqlite)"
    )
    p.add_argument("--no-log", action="store_true", help="do not record the throws")
    p.add_argument("--ee", choices=EE_BACKENDS, help="end-effector back-end (overrides the job)")
    p.add_argument(
        "--ee-config",
        metavar="YAML",
        help="Dynamixel configuration (robots/throwing_ee/dynamixel.yaml)",
    )
    p.add_argument("--port", help="serial port of the Dynamixel bus (overrides the configuration)")
    p.add_argument(
        "--emulate", action="store_true", help="drive an emulated Dynamixel bus (no hardware)"
    )
    p.add_argument("--record", metavar="RUN.rrd", help="write a Rerun recording (cell[record])")
    p.add_argument(
        "--pick",
        choices=("kinematic", "physical"),
        default="kinematic",
        help="arm platform: how the item gets into the grip: placed there (kinematic, the "
        "default), or gripped by contact from a random pose on the station (physical)",
    )
    p.add_argument(
        "--release",
        choices=("auto", "static"),
        default="auto",
        help="arm platform: release a throw on the move where the planner finds that sooner "
        "and landing in the bin (auto, the default), or always stop to release (static)",
    )
    p.add_argument(
        "--learn",
        action="store_true",
        help="correct the planner from each observed landing during the run (arm platform)",
    )
    p.add_argument(
        "--speed-scale",
        type=float,
        default=1.0,
        help="fraction of the arm's joint velocity and acceleration limits its moves use, "
        "in (0, 1] (1; a carry goes slower where the grip needs it)",
    )
    p.set_defaults(func=run)


def _store(args: argparse.Namespace):  # type: ignore[no-untyped-def]
    if args.no_log:
        return None
    from cell.log.store import ThrowStore

    return ThrowStore(args.db)


def _recorder(args: argparse.Namespace, job: Any) -> Any:
    if not args.record:
        return None
    if job.platform != "arm":
        from cell.errors import InvalidInput

        raise InvalidInput(f"--record: recordings cover the arm platform, not {job.platform!r}")
    from cell.record.observer import SceneRecorder

    return SceneRecorder(args.record)


EXIT_HARDWARE_FAULT = 3  # the end-effector failed mid-run: stopped safely, torque off
EXIT_NOTHING_SORTED = 4  # the run ended with no item in its target bin


def run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from cell.errors import HardwareError, InvalidInput
    from cell.orchestrator import Orchestrator

    job = load_job(args.job)
    if not 0.0 < args.speed_scale <= 1.0:
        raise InvalidInput(f"--speed-scale {args.speed_scale}: give a fraction in (0, 1]")
    kind = args.ee or job.ee
    if args.emulate and kind != "dynamixel":
        raise InvalidInput(
            f"--emulate drives an emulated Dynamixel bus; this run's end-effector is {kind!r}: "
            "add --ee dynamixel (or set ee: dynamixel in the job)"
        )
    hardware = None
    if kind == "dynamixel":
        from cell.endeffector.factory import make_end_effector

        cfg = args.ee_config or job.ee_config or None
        hardware = make_end_effector("dynamixel", cfg, port=args.port, emulate=args.emulate)
    rec = _recorder(args, job)
    store = _store(args)
    orch: Any
    if job.platform != "arm":
        from cell.platforms.runner import PlatformRunner

        if args.learn:
            raise InvalidInput(
                f"--learn: the flywheel runs on the arm platform, not {job.platform!r}"
            )

        orch = PlatformRunner(job, gui=args.gui, store=store, end_effector=hardware)
    else:
        orch = Orchestrator(
            job,
            gui=args.gui,
            store=store,
            end_effector=hardware,
            observer=rec,
            learn=args.learn,
            speed_scale=args.speed_scale,
            pick=args.pick,
            release=args.release,
        )
    bar = tqdm(
        total=len(job.expanded_items()),
        desc=f"sorting {Path(args.job).name}",
        unit="item",
        file=sys.stderr,
        disable=None,
    )
    try:
        done: list[object] = []  # items finished (the bar does not count when disabled)

        def progress(r):  # type: ignore[no-untyped-def]
            done.append(r)
            bar.update(1)
            bar.set_postfix_str(f"{r.object_id}: {r.action} -> {r.bin_id or '-'}")

        try:
            summary = orch.run(progress)
        except HardwareError as exc:
            orch.close()  # torque off on the servos before anything else
            kept = f"; {len(store)} throws kept in {store.path}" if store is not None else ""
            print(
                f"cell: hardware fault: {type(exc).__name__}: {exc}\n"
                f"cell: the run stopped after {len(done)} of {len(job.expanded_items())} items with the servos' "
                f"torque off{kept}",
                file=sys.stderr,
            )
            return EXIT_HARDWARE_FAULT
        if args.snapshot:
            orch.scene.snapshot(args.snapshot)
        if rec is not None:
            rec.finish(summary)
    finally:
        bar.close()
        if rec is not None:
            rec.close()
        orch.close()
        if store is not None:
            store.close()
    _table(summary, job.path, store)
    if args.json:
        d = summary.as_dict()
        Path(args.json).write_text(json.dumps(to_jsonable(d), indent=2))
    if summary.items and not summary.in_bin:
        print("cell run: no item came to rest in its target bin", file=sys.stderr)
        return EXIT_NOTHING_SORTED
    return 0


def _fmt(v: float, unit: str = "", digits: int = 3) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.{digits}f}{unit}"


def _table(s, path: str, store) -> None:  # type: ignore[no-untyped-def]
    print(f"\nsort job {path}")
    print(
        f"{'item':>4} {'object':14} {'action':7} {'target':9} {'landed in':9} {'error':>8} "
        f"{'stroke':>8}  failure"
    )
    for r in s.results:
        print(
            f"{r.index:4d} {r.object_id:14} {r.action:7} {r.target_bin:9} {r.bin_id or '-':9} "
            f"{_fmt(r.landing_error_m, ' m'):>8} {_fmt(r.stroke_m, ' m'):>8}  {r.failure}"
        )
    failed = [r for r in s.results if r.reason]
    if failed:
        print("\nwhy (full messages):")
        for r in failed:
            print(f"  item {r.index} ({r.object_id}, {r.failure}): {r.reason}")
    print()
    rows = [
        ("items", f"{s.items}"),
        ("placed", f"{s.placed}"),
        ("thrown", f"{s.thrown}"),
        ("failed", f"{s.failed}"),
        ("not in their bin", ", ".join(f"{k} {v}" for k, v in s.failures.items()) or "none"),
        ("in the right bin", f"{s.in_bin} ({100 * s.in_bin_rate:.1f} %)"),
        ("landing error mean", _fmt(s.mean_landing_error_m, " m")),
        ("landing error p95", _fmt(s.p95_landing_error_m, " m")),
        ("mean cycle time", _fmt(s.mean_cycle_time_s, " s (simulated)", 2)),
        ("items per hour", f"{s.items_per_hour:.0f} (simulated time)"),
        ("wall time", _fmt(s.wall_time_s, " s", 1)),
    ]
    if store is not None:
        rows.append(("throw log", f"{store.path}"))
    for k, v in rows:
        print(f"  {k:20s} {v}")
