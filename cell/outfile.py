"""Writing an output file whole, then moving it into place (docs/cli_inputs.md).

Every output is written to a temporary file beside it and moved over it when complete,
so a reader never sees half a file and a failed write leaves the old one. The temporary
file's name is unique to the write (`tempfile.mkstemp` in the same folder): with one fixed
name (`PATH.tmp`), two commands writing one output at once moved each other's temporary
file away, and one of them failed ("PATH.tmp: No such file or directory") after its work.
An output that exists and is not a regular file (`/dev/null`, the one the command checks
accept) is written into, never replaced: moving a file over it would put a regular file
where the device was, for every program on the machine where the user may do that.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path

__all__ = ["write_whole"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_whole(path: str | Path, write: Callable[[Path], object]) -> None:
    """Call `write(p)` to write the output at `path`: p a temporary file beside it, moved
    over `path` once written (its mode a new file's, 0o666 less the umask); or `path`
    itself where it exists and is not a regular file.

    Args:
        path: the output file.
        write: writes the whole content to the path it is given.
    """
    out = Path(path)
    try:
        mode = os.stat(out).st_mode
    except FileNotFoundError:
        mode = None
    if mode is not None and not stat.S_ISREG(mode):
        write(out)
        return
    fd, name = tempfile.mkstemp(dir=out.parent, prefix=f".{out.name}.", suffix=".tmp")
    os.close(fd)
    tmp = Path(name)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, out)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        if exc.filename not in (None, name, str(tmp)):
            raise
        # a failed write (a full disk: ENOSPC, a quota) names no file, or the temporary
        # one just removed: said of the output, which is as it was
        raise OSError(
            exc.errno,
            f"{exc.strerror or exc}; not written (a file there is left as it was)",
            str(out),
        ) from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
