"""Pieces several subcommands share: the object flags, the campaign flags, JSON output."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from cell.catalogue import get_object
from cell.errors import InvalidInput, InvalidParameter, plural
from cell.model.objects import SHAPES, ObjectParams
from cell.outfile import write_whole
from cell.parallel import add_campaign_args  # --workers N, --ray-address ADDR

__all__ = [
    "add_axis_args",
    "add_json_arg",
    "add_campaign_args",
    "add_object_args",
    "add_vector_arg",
    "check_output_path",
    "human",
    "json_to_stdout",
    "object_from_args",
    "plural",
    "print_json",
    "report",
    "to_jsonable",
    "write_json",
]


def add_object_args(p: argparse.ArgumentParser) -> None:
    """--object ID, or --shape S --mass KG --size X Y Z."""
    g = p.add_argument_group("object (a catalogue id, or shape, mass and extents)")
    g.add_argument("--object", metavar="ID", help="catalogue object id (see `cell throw --list`)")
    g.add_argument("--shape", choices=SHAPES, help="shape class")
    g.add_argument("--mass", type=float, metavar="KG", help="mass [kg]")
    add_vector_arg(g, "--size", "box extents [m], x = grip width")


def add_vector_arg(
    p: Any,
    flag: str,
    help: str,
    *,
    required: bool = False,
    default: tuple[float, float, float] | None = None,
    metavar: tuple[str, str, str] = ("X", "Y", "Z"),
) -> None:
    """A flag that takes three numbers (a point [m] or a velocity [m/s]): `flag X Y Z`.

    Args:
        p: the parser or argument group.
        flag: e.g. "--at".
        help: the help text, with the unit.
        required: the flag must be given.
        default: the value when it is not given (None: not given).
        metavar: the names of the three numbers in the help.
    """
    p.add_argument(
        flag, type=float, nargs=3, required=required, default=default, metavar=metavar, help=help
    )


def add_axis_args(p: argparse.ArgumentParser) -> None:
    """--elevation and --azimuth of the throw axis [rad] (MODEL.md: u = (cos e cos a, cos e sin a, sin e))."""
    p.add_argument(
        "--elevation",
        type=float,
        default=math.radians(30),
        metavar="RAD",
        help="throw-axis elevation [rad] (0.5236 = 30°)",
    )
    p.add_argument("--azimuth", type=float, default=0.0, metavar="RAD", help="azimuth [rad] (0)")


def object_from_args(args: argparse.Namespace) -> ObjectParams:
    """The object the flags name.

    Raises:
        InvalidInput: neither or both forms given, or a part missing.
    """
    adhoc = [args.shape, args.mass, args.size]
    if args.object and any(v is not None for v in adhoc):
        raise InvalidInput("give either --object ID or --shape/--mass/--size, not both")
    if args.object:
        return get_object(args.object)
    if all(v is None for v in adhoc):
        raise InvalidInput(
            "no object: give --object ID (a catalogue id) or --shape S --mass KG --size X Y Z"
        )
    if any(v is None for v in adhoc):
        raise InvalidInput(
            "an ad-hoc object needs all of --shape, --mass [kg] and --size X Y Z [m]"
        )
    try:
        obj = ObjectParams(shape=args.shape, mass=args.mass, size=tuple(args.size))
    except InvalidParameter as exc:
        raise InvalidInput(str(exc)) from None
    _refuse_impossible(obj)
    return obj


def _refuse_impossible(obj: ObjectParams) -> None:
    """Refuse an ad-hoc object no job, throw log or scene takes: denser than any solid,
    lighter than the air its box displaces, or a sphere's or cylinder's extents that say
    no one item (`cell.jobcheck.extents_mismatch`), naming the flag."""
    from cell.jobcheck import extents_mismatch
    from cell.model.objects import denser_than_any_solid, lighter_than_air

    why = denser_than_any_solid(obj.mass, obj.size) or lighter_than_air(obj.mass, obj.size)
    if why:
        raise InvalidInput(f"--mass {obj.mass:g} with --size: {why}")
    why = extents_mismatch(obj.shape, obj.size)
    if why:
        raise InvalidInput(f"--size {' '.join(f'{s:g}' for s in obj.size)}: {why}")


def to_jsonable(v: Any) -> Any:
    """Convert NumPy values and nested containers to plain JSON values."""
    if isinstance(v, dict):
        return {str(k): to_jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [to_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return [to_jsonable(x) for x in v.tolist()]
    if isinstance(v, (np.floating, float)):
        f = float(v)
        return f if math.isfinite(f) else None
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def print_json(obj: Any) -> None:
    """Print one JSON document to stdout."""
    json.dump(to_jsonable(obj), sys.stdout, indent=2)
    sys.stdout.write("\n")


def add_json_arg(p: argparse.ArgumentParser, what: str = "the result") -> None:
    """--json [PATH]: `--json` or `--json -` prints `what` as JSON on standard output instead of
    the text; `--json PATH` prints the text and then writes the JSON to PATH."""
    p.add_argument(
        "--json",
        nargs="?",
        const="-",
        metavar="PATH",
        help=f"{what} as JSON: on standard output instead of the text (--json or --json -), "
        "or written to PATH, a name ending in .json, after the text is printed (--json PATH)",
    )


def json_to_stdout(args: argparse.Namespace) -> bool:
    """True when --json asks for JSON on standard output (bare `--json` or `--json -`)."""
    return getattr(args, "json", None) == "-"


def write_json(args: argparse.Namespace, obj: Any) -> None:
    """The JSON of `obj` into the file --json names (written whole, then moved into place);
    nothing when --json was not given or is standard output (`print_json` prints that)."""
    target = getattr(args, "json", None)
    if not target or target == "-":
        return
    text = json.dumps(to_jsonable(obj), indent=2) + "\n"
    write_whole(target, lambda p: p.write_text(text))


def report(args: argparse.Namespace, doc: Any, lines: Iterable[str]) -> int:
    """A command's result: `doc` as JSON on standard output when --json asks for that (the
    text not made), else the text `lines` printed and then, with --json PATH, `doc`
    written there (`write_json`). Returns the exit status, 0."""
    if json_to_stdout(args):
        print_json(doc)
        return 0
    for line in lines:
        print(line)
    write_json(args, doc)
    return 0


def human(v: Any) -> str:
    """A value as a person writes it: a dict as "a 2, b 3" ("none" when empty), a list joined
    by commas, a float to 4 significant figures; no raw Python reprs."""
    if isinstance(v, dict):
        return ", ".join(f"{k} {human(x)}" for k, x in v.items()) or "none"
    if isinstance(v, (list, tuple)):
        return ", ".join(human(x) for x in v) or "none"
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return "n/a" if not math.isfinite(f) else f"{f:.4g}"
    return str(v)


def check_output_path(path: str | Path, flag: str) -> Path:
    """Check, before any work starts, that a result can be written to `path`.

    The check writes nothing that stays: a file that does not exist yet is created and
    removed again (the only test that holds for every user and file system, /proc included);
    one that exists is opened for appending, which does not change it.

    Args:
        path: the output file the user named.
        flag: the option that named it (for the message), e.g. "-o".

    Returns:
        The path.

    Raises:
        InvalidInput: the path is too long, a folder, a device or FIFO (but /dev/null), its
            folder does not exist, or it cannot be written.
    """
    import stat

    from cell.infile import check_path_length, kind_of

    check_path_length(path, flag)
    p = Path(path)
    try:
        st: os.stat_result | None = os.stat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise InvalidInput(f"{flag} {p}: cannot be written ({exc.strerror})") from None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise InvalidInput(f"{flag} {p}: is a folder; give a file name")
    if st is not None and not stat.S_ISREG(st.st_mode):
        if os.path.samefile(p, os.devnull):
            return p
        raise InvalidInput(f"{flag} {p}: is {kind_of(st.st_mode)}; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInput(f"{flag} {p}: the folder {parent} does not exist; create it first")
    try:
        if st is None:
            fd = os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            os.close(fd)
            os.unlink(p)
        else:
            os.close(os.open(p, os.O_WRONLY | os.O_APPEND))
    except OSError as exc:
        raise InvalidInput(f"{flag} {p}: cannot be written here ({exc.strerror})") from None
    return p
