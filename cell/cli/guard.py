"""The checks every command's arguments pass before its work starts.

One place for what a new user gets wrong on any command line (issue 62): numbers that are
not finite or of an absurd magnitude, paths too long for the file system, outputs that
cannot be written, an output that names one of the command's inputs (or another output),
a file shipped under `robots/` or `tasks/` written without `--replace`, and `--gui` with
no display to open a window on. Each refusal names the option and what would be valid.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import Any

from cell.errors import InvalidInput

__all__ = [
    "INPUT_DESTS",
    "OUTPUT_DESTS",
    "add_replace_args",
    "check_args",
    "flag_names",
    "refuse_outputs_among",
    "shipped_dirs",
]

# Options that name a file a command writes (dest -> what it is called on the command line).
OUTPUT_DESTS = {
    "output": "-o",
    "json": "--json",
    "report": "--report",
    "snapshot": "--snapshot",
    "record": "--record",
    "learn_save": "--learn-save",
    "plot": "--plot",
    "log": "--log",
    "save_world": "--save-world",
}
# Options and arguments that name a file a command reads.
INPUT_DESTS = {
    "job": "JOB",
    "throws": "THROWS",
    "file": "FILE",
    "params": "--params",
    "start": "--start",
    "world": "--world",
    "tracks": "--tracks",
    "db": "--db",
    "ee_config": "--ee-config",
    "config": "--config",
    "out": "--out",
}
_FOLDER_OUTPUTS = {("identify", "plot")}  # `cell identify --plot DIR` writes into a folder

_TAU = 2 * math.pi
# Physical ranges of the numbers a user types: dest -> (lowest, highest, unit). Values are
# refused outside them, the range named; the commands' own checks refine inside them.
FLOAT_RANGES: dict[str, tuple[float, float, str]] = {
    "mass": (0.0, 100.0, "kg"),
    "size": (0.0, 10.0, "m"),
    "at": (-100.0, 100.0, "m"),
    "target": (-100.0, 100.0, "m"),
    "current": (-100.0, 100.0, "m"),
    "box": (-100.0, 100.0, "m"),
    "land_z": (-100.0, 100.0, "m"),
    "base_velocity": (-20.0, 20.0, "m/s"),
    "moving_base": (0.0, 20.0, "m/s"),
    "elevation": (-math.pi / 2, math.pi / 2, "rad"),
    "elevation_range": (-math.pi / 2, math.pi / 2, "rad"),
    "azimuth": (-_TAU, _TAU, "rad"),
    "roll": (-_TAU, _TAU, "rad"),
    "q_from": (-_TAU, _TAU, "rad"),
    "arm_height": (0.0, 100.0, "m"),
    "holdout": (0.0, 1.0, ""),
    "tol": (0.0, 1.0, ""),
    "speed_scale": (0.0, 1.0, ""),
    "noise_along": (0.0, 10.0, "per m of reach"),
    "noise_across": (0.0, 10.0, "per m of reach"),
    "noise_floor": (0.0, 10.0, "m"),
    "time_scale": (1e-3, 1e3, ""),
}
INT_RANGES: dict[str, tuple[int, int]] = {
    "n": (0, 10_000_000),
    "adhoc": (0, 1_000_000),
    "max_iter": (1, 100_000),
    "repeats": (1, 1_000),
    "hold_out": (0, 1_000),
    "max_items": (0, 1_000_000),
    "layouts": (1, 10_000),
}
ABSURD = 1e6  # any other number: magnitudes beyond this are refused as typos


def flag_names(parser: argparse.ArgumentParser) -> dict[str, str]:
    """dest -> how the command line spells it ("-o", "--mass", "JOB"), over every subcommand."""
    names: dict[str, str] = {}
    todo = [parser]
    while todo:
        p = todo.pop()
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                todo.extend(a.choices.values())
            elif a.dest not in names and a.dest != argparse.SUPPRESS:
                names[a.dest] = a.option_strings[0] if a.option_strings else a.dest.upper()
    return names


def add_replace_args(parser: argparse.ArgumentParser) -> None:
    """Give every subcommand that writes a file `--replace` (unless it has its own)."""
    todo = [parser]
    while todo:
        p = todo.pop()
        dests = {a.dest for a in p._actions}
        for a in p._actions:
            if isinstance(a, argparse._SubParsersAction):
                todo.extend(a.choices.values())
        if p is not parser and dests & set(OUTPUT_DESTS) and "replace" not in dests:
            p.add_argument(
                "--replace",
                action="store_true",
                help="allow an output to overwrite a file shipped with cell (under robots/ "
                "or tasks/)",
            )


def shipped_dirs() -> tuple[Path, ...]:
    """The folders of files shipped with the package's checkout (robots/, tasks/)."""
    root = Path(__file__).resolve().parents[2]
    return tuple(d for d in (root / "robots", root / "tasks") if d.is_dir())


def _numbers(args: argparse.Namespace, names: dict[str, str]) -> None:
    for dest, value in vars(args).items():
        if dest in ("seed", "workers"):  # checked on their own
            continue
        values = value if isinstance(value, (list, tuple)) else [value]
        for v in values:
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                continue
            flag = names.get(dest, "--" + dest.replace("_", "-"))
            if isinstance(v, float) and not math.isfinite(v):
                raise InvalidInput(f"{flag} {v}: not a finite number; give a real value")
            if dest in FLOAT_RANGES:
                lo, hi, unit = FLOAT_RANGES[dest]
                if not lo <= v <= hi:
                    deg = (
                        f" ({math.degrees(lo):g}° … {math.degrees(hi):g}°)" if unit == "rad" else ""
                    )
                    # as many digits as show the value outside: -1.5708 is below -π/2,
                    # which 6 digits print as -1.5708 too
                    raise InvalidInput(
                        f"{flag} {v:g}: outside the valid range {_bounds(lo, hi, v)} "
                        f"{unit}{deg}".rstrip()
                    )
            elif dest in INT_RANGES and isinstance(v, int):
                ilo, ihi = INT_RANGES[dest]
                if not ilo <= v <= ihi:
                    raise InvalidInput(f"{flag} {v}: give {ilo} to {ihi}")
            elif abs(v) > ABSURD:
                raise InvalidInput(
                    f"{flag} {v:g}: an absurd magnitude; give a value within ±{ABSURD:g}"
                )


def _bounds(lo: float, hi: float, v: float) -> str:
    """A range "lo … hi" in the fewest digits (6 at least) that print each bound apart
    from the value `v` refused."""
    for digits in range(6, 17):
        a, b = f"{lo:.{digits}g}", f"{hi:.{digits}g}"
        if f"{v:g}" not in (a, b):
            return f"{a} … {b}"
    return f"{lo!r} … {hi!r}"


def _key(p: Path) -> tuple[int, int] | Path:
    """What identifies a file: its device and inode if it exists, else its resolved path."""
    try:
        st = os.stat(p)
        return (st.st_dev, st.st_ino)
    except (OSError, ValueError):
        return Path(os.path.abspath(p))  # a missing file (or a symbolic-link loop)


def _outputs(args: argparse.Namespace, names: dict[str, str]) -> list[tuple[str, str, str]]:
    """(dest, flag, path) of every output the command line names (not standard output)."""
    outs = []
    command = getattr(args, "command", None)
    for dest, flag in OUTPUT_DESTS.items():
        value = getattr(args, dest, None)
        if isinstance(value, str) and not value.strip():  # `-o ""`, `-o "$UNSET"`
            raise InvalidInput(
                f"{names.get(dest, flag)} {value!r}: an empty path; give a file name"
            )
        if isinstance(value, str) and value != "-":
            outs.append((dest, names.get(dest, flag), value))
    if command == "log" and getattr(args, "log_command", None) == "export" and args.tracks:
        outs.append(("tracks", "--tracks", args.tracks))
    return outs


def _inputs(args: argparse.Namespace, outputs: list[tuple[str, str, str]]) -> list[tuple[str, str]]:
    written = {d for d, _, _ in outputs}
    ins = []
    for dest, flag in INPUT_DESTS.items():
        value = getattr(args, dest, None)
        if isinstance(value, str) and value and dest not in written:
            ins.append((flag, value))
    robot = getattr(args, "robot", None)  # `reach`, `job random`: an arm's name or mount file
    if isinstance(robot, str) and robot:
        from cell.robot.mount import is_mount_path

        if is_mount_path(robot):
            ins.append(("--robot", robot))
    return ins


def _files(args: argparse.Namespace, names: dict[str, str]) -> None:
    from cell.cli.common import check_output_path
    from cell.infile import check_path_length

    outputs = _outputs(args, names)
    inputs = _inputs(args, outputs)
    for flag, value in inputs:
        check_path_length(value, flag)
    command = getattr(args, "command", None)
    seen: dict[Any, str] = {}
    for flag, value in inputs:  # a missing one too: `synth -o s.db --db s.db` would make both
        seen.setdefault(_key(Path(value)), f"{flag} {value}")
    shipped = shipped_dirs()
    for dest, flag, value in outputs:
        if (command, dest) in _FOLDER_OUTPUTS:
            check_path_length(value, flag)
            continue
        out = check_output_path(value, flag)
        key = _key(out)
        if key in seen:
            raise InvalidInput(
                f"{flag} {value}: that is also {seen[key]}, which this command reads or "
                "writes; give another file (an input is never overwritten)"
            )
        seen[key] = f"{flag} {value}"
        where = Path(os.path.realpath(out))
        for folder in shipped:
            if where.is_relative_to(folder) and not getattr(args, "replace", False):
                raise InvalidInput(
                    f"{flag} {value}: a file shipped with cell under {folder}; write to "
                    "another file, or add --replace to overwrite it"
                )


def refuse_outputs_among(args: argparse.Namespace, inputs: list[tuple[str, str]]) -> None:
    """Refuse an output (or `--db`, which a run writes) that is one of `inputs`, (what it
    is: "the parameter file this run reads (...)", path): the files a command learns it reads only once it has read its input, as the
    parameter file, learned model or mount file a job names (same device and inode, or the
    same resolved path).

    Raises:
        InvalidInput: naming the option, its value and the input it is.
    """
    seen = {_key(Path(path)): what for what, path in inputs if path}
    written = [(flag, value) for _, flag, value in _outputs(args, {})]
    db = getattr(args, "db", None)
    if isinstance(db, str) and db and not getattr(args, "no_log", False):
        written.append(("--db", db))
    for flag, value in written:
        key = _key(Path(value))
        if key in seen:
            raise InvalidInput(
                f"{flag} {value}: that is {seen[key]}; give another file (an input is "
                "never overwritten)"
            )


def _display(args: argparse.Namespace) -> None:
    if not getattr(args, "gui", False) or not sys.platform.startswith("linux"):
        return
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise InvalidInput(
            "--gui: no display to open PyBullet's window on (DISPLAY is not set); run "
            "without --gui (the run is the same), or under a virtual display (xvfb-run cell ...)"
        )


def check_args(args: argparse.Namespace, parser: argparse.ArgumentParser) -> None:
    """Refuse, before a command's work starts, every argument the module docstring lists.

    Raises:
        InvalidInput: naming the option, its value and what would be valid.
    """
    names = flag_names(parser)
    seed = getattr(args, "seed", None)
    if isinstance(seed, int) and not 0 <= seed < 2**32:
        raise InvalidInput(f"--seed {seed}: a seed is an integer from 0 to {2**32 - 1}")
    workers = getattr(args, "workers", None)
    if isinstance(workers, int) and not 1 <= workers <= 4096:
        raise InvalidInput(f"--workers {workers}: give 1 (in this process) to 4096")
    _numbers(args, names)
    _files(args, names)
    _display(args)
