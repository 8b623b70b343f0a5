"""A user's input file, checked before it is opened: a regular file of a bounded size.

Every reader of a file a user names (a job, a parameter file, a throw log, a track log,
a residual model, a throw store, a Dynamixel configuration) calls `check_input_file`
first. It looks at the path with `os.stat` only, which never blocks: a folder, a
device (/dev/zero, /dev/urandom), a FIFO or a socket is refused by name before any
`open()` could hang on it or read without end, and a regular file larger than the
reader's bound is refused unread. A path too long for the file system is named too.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from cell.errors import InvalidInput

__all__ = ["MAX_NAME_BYTES", "MAX_PATH_BYTES", "check_input_file", "check_path_length", "kind_of"]

MAX_NAME_BYTES = 255  # [B] one path component (NAME_MAX of Linux and macOS file systems)
MAX_PATH_BYTES = 4095  # [B] a whole path (PATH_MAX - 1 on Linux)


def check_path_length(path: str | Path, what: str) -> None:
    """Refuse a path whose whole or any one component is longer than file systems allow.

    Args:
        path: the path as given.
        what: what names it, for the message ("-o", "job file").

    Raises:
        InvalidInput: naming `what`, the longest component's length and the bound.
    """
    raw = os.fsencode(str(path))
    if b"\0" in raw:
        raise InvalidInput(f"{what}: a path with a NUL byte; no file has such a name")
    if len(raw) > MAX_PATH_BYTES:
        raise InvalidInput(
            f"{what}: a path of {len(raw)} bytes; at most {MAX_PATH_BYTES} bytes are valid"
        )
    longest = max((len(part) for part in raw.split(b"/")), default=0)
    if longest > MAX_NAME_BYTES:
        shown = os.fsdecode(raw[:40])
        raise InvalidInput(
            f"{what}: a file or folder name of {longest} bytes ({shown}…); at most "
            f"{MAX_NAME_BYTES} bytes per name are valid"
        )


def kind_of(mode: int) -> str:
    """What a non-regular file is, in words ("a folder", "a character device", ...)."""
    for test, name in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def _a(what: str) -> str:
    return ("an " if what[:1].lower() in "aeiou" else "a ") + what


def check_input_file(path: str | Path, what: str, max_bytes: int) -> Path:
    """Check, without opening it, that `path` is a readable regular file of at most `max_bytes`.

    Args:
        path: the file the user named.
        what: what it should be, for the messages ("job file", "throw log (CSV)").
        max_bytes: the reader's bound on its size [B].

    Returns:
        The path.

    Raises:
        InvalidInput: naming the file: missing, too long a name, a folder, a device, a FIFO
            or a socket, not readable, or larger than `max_bytes`.
    """
    if not str(path):
        raise InvalidInput(f"an empty path where a {what} was expected; give its file name")
    p = Path(path)
    check_path_length(p, f"{p.name[:40]}…" if len(str(p)) > 80 else str(p))
    try:
        st = os.stat(p)  # follows a symbolic link to what it names; never blocks
    except FileNotFoundError:
        raise InvalidInput(f"{p}: no such {what}") from None
    except OSError as exc:
        if exc.errno == errno.ENOTDIR:
            raise InvalidInput(f"{p}: no such {what} (a part of the path is a file)") from None
        raise InvalidInput(f"{p}: cannot read the {what} ({exc.strerror})") from None
    if not stat.S_ISREG(st.st_mode):
        raise InvalidInput(
            f"{p}: is {kind_of(st.st_mode)}; {_a(what)} must be a regular file (it is read whole)"
        )
    if not os.access(p, os.R_OK):
        raise InvalidInput(f"{p}: the {what} is not readable (permission denied)")
    if st.st_size > max_bytes:
        raise InvalidInput(f"{p}: {st.st_size} bytes; {_a(what)} is at most {max_bytes} bytes")
    return p
