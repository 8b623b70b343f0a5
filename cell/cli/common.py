"""Pieces several subcommands share: the object flags, the campaign flags, JSON output."""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from cell.catalogue import get_object
from cell.errors import InvalidInput, InvalidParameter
from cell.model.objects import SHAPES, ObjectParams
from cell.parallel import add_campaign_args  # --workers N, --ray-address ADDR

__all__ = [
    "add_axis_args",
    "add_campaign_args",
    "add_object_args",
    "check_output_path",
    "object_from_args",
    "print_json",
    "to_jsonable",
]


def add_object_args(p: argparse.ArgumentParser) -> None:
    """--object ID, or --shape S --mass KG --size X Y Z."""
    g = p.add_argument_group("object (a catalogue id, or shape, mass and extents)")
    g.add_argument("--object", metavar="ID", help="catalogue object id (see `cell throw --list`)")
    g.add_argument("--shape", choices=SHAPES, help="shape class")
    g.add_argument("--mass", type=float, metavar="KG", help="mass [kg]")
    g.add_argument(
        "--size",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="box extents [m], x = grip width",
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
        return ObjectParams(shape=args.shape, mass=args.mass, size=tuple(args.size))
    except InvalidParameter as exc:
        raise InvalidInput(str(exc)) from None


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


def check_output_path(path: str | Path, flag: str) -> Path:
    """Check, before any work starts, that a result can be written to `path`.

    Args:
        path: the output file the user named.
        flag: the option that named it (for the message), e.g. "-o".

    Returns:
        The path.

    Raises:
        InvalidInput: the path is a folder, its folder does not exist, or is not writable.
    """
    p = Path(path)
    if p.is_dir():
        raise InvalidInput(f"{flag} {p}: is a folder; give a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInput(f"{flag} {p}: the folder {parent} does not exist; create it first")
    if not os.access(parent, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise InvalidInput(f"{flag} {p}: not writable here")
    return p
