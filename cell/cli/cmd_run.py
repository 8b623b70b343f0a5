"""`cell run JOB.yaml`: a sort job in the PyBullet cell, with a progress bar and a closing table."""

from __future__ import annotations

import argparse
import contextlib
import logging
import math
import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from cell.cli.columns import terminal_width
from cell.cli.common import add_json_arg, json_to_stdout, plural, print_json, write_json
from cell.cli.guard import refuse_outputs_among
from cell.jobfiles import job_files
from cell.jobs import ORDERS, load_job
from cell.kinds import EE_BACKENDS, PICKS, RELEASES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run a sort job (YAML) in the cell")
    p.add_argument("job", help="job file, e.g. tasks/bins.yaml")
    p.add_argument("--gui", action="store_true", help="show the PyBullet GUI")
    add_json_arg(p, "the summary")  # --json PATH writes it after the table, as before
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no line per item as it finishes (on standard error), nor the warnings of "
        "the items' motions (a place that had not touched down); the job's warnings stay",
    )
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
    _add_arm_args(p)
    p.add_argument(
        "--learn",
        action="store_true",
        help="learn from the throws: before the run, refit each of the job's objects' "
        "effective mass and extents from its earlier sort throws in the --db store (the "
        "parameter file is not changed); during it, correct each aim from the landings "
        "so far (arm platform)",
    )
    p.add_argument(
        "--learn-save",
        metavar="EE.yaml",
        help="with --learn: write the parameters this run plans with (the file's, with the "
        "refitted objects) to this new file (never the input parameter file)",
    )
    p.add_argument(
        "--speed-scale",
        type=float,
        default=1.0,
        help="fraction of the arm's joint velocity and acceleration limits its moves use, "
        "in (0, 1] (1; a carry goes slower where the grip needs it)",
    )
    p.set_defaults(func=run)


def _add_arm_args(p: argparse.ArgumentParser) -> None:
    """The options of the arm platform: pick, release, turn, cycle search, order."""
    p.add_argument(
        "--pick",
        choices=PICKS,
        default="kinematic",
        help="arm platform: how the item gets into the grip: placed there (kinematic, the "
        "default), or gripped by contact from a random pose on the station (physical)",
    )
    p.add_argument(
        "--release",
        choices=RELEASES,
        default="auto",
        help="arm platform: release a throw on the move where the planner finds that sooner "
        "and landing in the bin (auto, the default), or always stop to release (static)",
    )
    p.add_argument(
        "--turn-release",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="arm platform: release a throw to a bin 30° or more round from the pick station "
        "with the arm turned toward the station, the throw axis on the bin, where the "
        "planner's cycle estimate is shorter (on by default; --no-turn-release: always face "
        "the bin)",
    )
    p.add_argument(
        "--cycle-search",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="arm platform: choose each throw's release by its pick-to-pick cycle as the cell "
        "makes it, among the cell's release bounds and lower ones; sooner cycles for "
        "several times the planning (on by default; --no-cycle-search: the release by the "
        "planner's cycle estimate, in the cell's release bounds, for a fraction of the planning)",
    )
    p.add_argument(
        "--plan-workers",
        type=int,
        choices=(1, 2),
        default=None,
        help="arm platform: processes a throw's plan uses: 1, one; 2, its turned facing (or "
        "its last lower release bounds) searched on a second core meanwhile, the same "
        "decisions (default: 2 where the process may use two cores, $CELL_PLAN_WORKERS where "
        "set)",
    )
    p.add_argument(
        "--order",
        choices=ORDERS,
        default="job",
        help="arm platform: the order the items are taken in: as the job lists them (job, the "
        "default), or each bin's items one after another (bins: the items all at hand, as in "
        "a tote; its figures: docs/figures.md)",
    )


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


def _item_line(r: Any, k: int, n: int) -> str:
    """One finished item as a line: what happened to it, where it landed, how long it took."""
    where = f"in {r.bin_id}" if r.bin_id else "in no bin"
    how = "in its bin" if r.in_bin else (r.failure or "not in its bin")
    t = f", {r.cycle_time_s:.1f} s" if math.isfinite(r.cycle_time_s) else ""
    return (
        f"[{k}/{n}] item {r.index} {r.object_id}: {r.action} to {r.target_bin}, {where} ({how}{t})"
    )


def _runner(
    args: argparse.Namespace, job: Any, hardware: Any, params: Any, rec: Any, store: Any
) -> Any:
    """The orchestrator of the job's platform (the arm's, or a drone's or mobile base's)."""
    from cell.errors import InvalidInput
    from cell.orchestrator import Orchestrator

    orch: Any
    if job.platform != "arm":
        from cell.platforms.runner import PlatformRunner

        if args.learn:
            raise InvalidInput(
                f"--learn: the flywheel runs on the arm platform, not {job.platform!r}"
            )
        if args.order != "job":
            raise InvalidInput(
                f"--order {args.order}: only the arm platform takes the items in another "
                f"order than the job's; the {job.platform!r} takes them as listed (--order job)"
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
            params=params,
            speed_scale=args.speed_scale,
            pick=args.pick,
            release=args.release,
            turn_release=args.turn_release,
            cycle_search=args.cycle_search,
            order=args.order,
            plan_workers=args.plan_workers,
        )
    return orch


def run(args: argparse.Namespace) -> int:
    """`cell run`, on one BLAS thread (`cell.parallel.one_blas_thread`), as `cell bench
    sort` runs each layout: the demo's run.json is the same on one thread as on two but for
    its wall-clock fields."""
    from cell.parallel import one_blas_thread

    said = not getattr(args, "quiet", False) or getattr(args, "verbose", False)  # -v: said
    with one_blas_thread(), _library_warnings(said):
        return _run(args)


@contextlib.contextmanager
def _library_warnings(said: bool) -> Iterator[None]:
    """Under -q the library's warnings (`cell: warning: place: the item had not touched
    down ...`, of one item's motion) go unsaid, as the items' lines do; the job's
    warnings, printed by this command before anything moves, are said still."""
    lib = logging.getLogger("cell")
    before = lib.level
    if not said:
        lib.setLevel(logging.ERROR)
    try:
        yield
    finally:
        lib.setLevel(before)


def _run(args: argparse.Namespace) -> int:
    from cell.arm.base import check_speed_scale
    from cell.errors import HardwareError, InvalidInput
    from cell.log.store import StoreWriteError

    if args.no_log and args.db and not args.learn:  # --learn reads --db; --no-log, none
        raise InvalidInput(
            f"--db {args.db} with --no-log: --no-log records no throw, so the store would not "
            "be written; give one of them (--db with --no-log is the store --learn reads)"
        )
    job = load_job(args.job)
    refuse_outputs_among(args, job_files(job))  # the files the job names are inputs too
    for warning in job.warnings:  # items left unsorted, a near bin auto throws into
        print(f"cell: warning: {warning}", file=sys.stderr)
    arm = job.robot if job.platform == "arm" else None  # the other platforms run no arm
    check_speed_scale(args.speed_scale, arm, "--speed-scale")
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
    if args.learn_save and not args.learn:
        raise InvalidInput("--learn-save writes what --learn refits: add --learn")
    params = None
    if args.learn and job.platform == "arm":
        params = _refit(args, job)
    rec = _recorder(args, job)
    store = _store(args)
    orch = _runner(args, job, hardware, params, rec, store)
    total = len(job.expanded_items(args.order))
    image = None
    try:
        done: list[object] = []  # items finished

        def progress(r):  # type: ignore[no-untyped-def]
            done.append(r)
            if not args.quiet:  # a line per item, on a terminal or not; stdout is the table
                print(_item_line(r, len(done), total), file=sys.stderr, flush=True)

        t_wall = time.perf_counter()
        try:
            summary = orch.run(progress)
        except HardwareError as exc:
            orch.close()  # torque off on the servos before anything else
            kept = (
                f"; {plural(len(store), 'throw')} kept in {store.path}" if store is not None else ""
            )
            print(
                f"cell: hardware fault: {type(exc).__name__}: {exc}\n"
                f"cell: the run stopped after {len(done)} of {plural(total, 'item')} with the servos' "
                f"torque off{kept}",
                file=sys.stderr,
            )
            return EXIT_HARDWARE_FAULT
        except (KeyboardInterrupt, StoreWriteError) as exc:
            kept = (
                f"; {plural(len(store), 'throw')} kept in {store.path}"
                if store is not None
                else " (--no-log: no throw recorded)"
            )
            if isinstance(exc, StoreWriteError):  # said by `cell.cli.main` after these lines
                kept += ", the next one's record refused by the store (below)"
            print(
                f"cell run: stopped after {len(done)} of {plural(total, 'item')}{kept}",
                file=sys.stderr,
            )
            _partial_json(args, done, total, time.perf_counter() - t_wall, orch.loop.plan_workers())
            raise
        if args.snapshot:  # rendered now, written after the results are printed
            image = orch.scene.render()
        if rec is not None:
            rec.finish(summary)
    finally:
        if rec is not None:
            rec.close()
        orch.close()
        if store is not None:
            store.close()
    if json_to_stdout(args):
        print_json(summary.as_dict())
    else:
        _table(summary, job.path, store, terminal_width())
    if image is not None:
        from cell.sim.snapshot import save_png

        save_png(image, args.snapshot)
    if not json_to_stdout(args):
        write_json(args, summary.as_dict())
    if summary.items and not summary.in_bin:
        print("cell run: no item came to rest in its target bin", file=sys.stderr)
        return EXIT_NOTHING_SORTED
    return 0


def _partial_json(
    args: argparse.Namespace, done: list[Any], total: int, wall_s: float, plan_workers: int
) -> None:
    """With --json, the summary of the items finished before an interrupt, marked
    `"interrupted": true` with `items_planned` (the job's items), where --json asks for it;
    said on stderr when written to a file."""
    if not getattr(args, "json", None):
        return
    from cell.results import summarise

    summary = summarise(list(done), wall_s, plan_workers)
    doc = {**summary.as_dict(), "interrupted": True, "items_planned": total}
    if json_to_stdout(args):
        print_json(doc)
        return
    write_json(args, doc)
    print(
        f"cell run: the {plural(len(done), 'item')} finished written to {args.json}",
        file=sys.stderr,
    )


def _refit(args: argparse.Namespace, job: Any) -> Any:
    """The job's parameters with its objects' η_o refitted from the store's earlier sort
    throws (`cell.identify.refit.sort_throws`, which says what it leaves out and why), one
    line per object on stderr; the file's parameters when the store has no usable throw or
    cannot be read, or when the job plans with a residual model (said on stderr).
    --learn-save writes them to a new file; the input parameter file is never written.

    Raises:
        InvalidInput: --learn-save names the input parameter file, or cannot be written.
    """
    import sqlite3

    from cell.cli.common import check_output_path
    from cell.errors import CellError, InvalidInput
    from cell.identify.refit import refit_objects, sort_throws
    from cell.log.store import ThrowStore, default_db_path
    from cell.params import load_params, save_params, scene_params_path

    source = job.params or scene_params_path()
    if args.learn_save:
        out = check_output_path(args.learn_save, "--learn-save")
        if source and out.resolve() == Path(source).resolve():
            raise InvalidInput(
                f"--learn-save {args.learn_save}: that is the parameter file this run reads "
                f"({source}); --learn never changes it: give a new file"
            )
    params = load_params(source)
    path = default_db_path(args.db)
    say = "cell run --learn:"
    objects = {spec.obj.name or spec.obj.shape: spec.obj for spec in job.items}
    if job.residual:
        print(
            f"{say} no refit: the job's residual model ({job.residual}) learned ΔL_s against "
            f"the η_o of {source}, and would correct again what a refit corrects; planning "
            "with that file",
            file=sys.stderr,
        )
    elif not path.exists() or path.stat().st_size == 0:
        print(f"{say} no throw store at {path} yet: planning with {source}", file=sys.stderr)
    else:
        try:
            with ThrowStore(path, read_only=True) as store:
                found = sort_throws(store, objects)
            if found.table is None:
                print(
                    f"{say} {path} holds no earlier sort throw of this job's objects: "
                    f"planning with {source}",
                    file=sys.stderr,
                )
            else:
                params, report = refit_objects(found.table, params)
                n = sum(r.throws for r in report.refitted)
                print(
                    f"{say} refitted {plural(len(report.refitted), 'object')} from "
                    f"{plural(n, 'earlier throw')} in {path} (η_ee kept from {source}):",
                    file=sys.stderr,
                )
                for r in report.objects:
                    print(f"  {r.line()}", file=sys.stderr)
            if found.left_out:
                print(
                    f"{say} left out: "
                    + "; ".join(f"{plural(n, 'row')}: {why}" for why, n in found.left_out.items()),
                    file=sys.stderr,
                )
        except (CellError, sqlite3.Error, ValueError) as exc:
            print(
                f"{say} cannot refit from {path} ({type(exc).__name__}: {exc}): planning "
                f"with {source}",
                file=sys.stderr,
            )
    if args.learn_save:
        save_params(params, args.learn_save)
        print(f"{say} wrote the parameters of this run to {args.learn_save}", file=sys.stderr)
    return params


def _fmt(v: float, unit: str = "", digits: int = 3) -> str:
    return "n/a" if not math.isfinite(v) else f"{v:.{digits}f}{unit}"


def _not_in_bin(s) -> str:  # type: ignore[no-untyped-def]
    """The items not at rest in their bin, placed, thrown or not released, and why."""
    n = s.items - s.in_bin
    return f"{n} ({', '.join(f'{k} {v}' for k, v in s.failures.items())})" if n else "none"


def _table(s, path: str, store, width: int | None = None) -> None:  # type: ignore[no-untyped-def]
    """The run's rows and closing table; on a terminal of `width` columns narrower than
    a row, the row broken between its cells (`cell.cli.columns.fitted`)."""
    from cell.cli.columns import column_width, fitted, pad

    print(f"\nsort job {path}")
    wo = column_width(14, (r.object_id for r in s.results))  # names as wide as they show
    wb = column_width(9, (b for r in s.results for b in (r.target_bin, r.bin_id)))
    head = ["item", pad("object", wo), f"{'action':7}", pad("target", wb), pad("landed in", wb)]
    print(fitted([*head, f"{'error':>8}", f"{'stroke':>8}", " failure"], width, 5))
    for r in s.results:
        cells = [f"{r.index:4d}", pad(r.object_id, wo), f"{r.action:7}", pad(r.target_bin, wb)]
        cells += [pad(r.bin_id or "-", wb), f"{_fmt(r.landing_error_m, ' m'):>8}"]
        print(fitted([*cells, f"{_fmt(r.stroke_m, ' m'):>8}", f" {r.failure}"], width, 5))
    failed = [r for r in s.results if r.reason]
    if failed:
        print("\nwhy (full messages):")
        for r in failed:
            print(fitted(f"  item {r.index} ({r.object_id}, {r.failure}): {r.reason}".split(" "), width, 4))  # fmt: skip
    print()
    rows = [
        ("items", f"{s.items}"),
        ("placed", f"{s.placed}"),
        ("thrown", f"{s.thrown}"),
        ("not released", f"{s.failed}"),  # stopped before the release (JSON: `failed`)
        ("not in their bin", _not_in_bin(s)),
        ("in the right bin", f"{s.in_bin} ({100 * s.in_bin_rate:.1f} %)"),
        ("landing error mean", _fmt(s.mean_landing_error_m, " m")),
        ("landing error p95", _fmt(s.p95_landing_error_m, " m")),
        ("mean cycle time", _fmt(s.mean_cycle_time_s, " s (simulated)", 2)),
        ("items per hour", f"{s.items_per_hour:,.0f} (simulated time)"),
        ("wall time", _fmt(s.wall_time_s, " s", 1)),
        (
            "planning per item",
            f"median {_fmt(s.plan_s_median, ' s', 2)}, p95 {_fmt(s.plan_s_p95, ' s', 2)}, "
            f"max {_fmt(s.plan_s_max, ' s', 2)} (wall time, {s.cores} cores, "
            f"{plural(s.plan_workers, 'plan worker')})",
        ),
        (
            "real-time items/h",
            f"{s.items_per_hour_realtime:,.0f} (planning overlapped, docs/realtime.md)",
        ),
    ]
    if store is not None:
        rows.append(("throw log", f"{store.path}"))
    for k, v in rows:  # a value broken after its commas
        print(fitted([f"  {k:20s}", *re.split(r"(?<=,) ", v)], width, 23))
