"""Silencing what C code (PyBullet) writes to the process's stdout and stderr."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator


@contextlib.contextmanager
def quiet_c_output(keep_stderr: bool = False) -> Iterator[None]:
    """Silence what C code writes to file descriptors 1 and 2 (2 kept if `keep_stderr`).

    PyBullet prints a banner on import ("pybullet build time") and on every connect
    ("argv[0]="), once per scene: 13 times in a sort job, 34 in a calibration. They are
    not the command's output (`cell calibrate --json` prints JSON on stdout) and say
    nothing to its user, so they go to /dev/null at the file-descriptor level, which is
    where C code writes. A GUI connect keeps stderr: its X server errors are worth seeing.
    """
    import ctypes

    libc = ctypes.CDLL(None)
    fds = (1,) if keep_stderr else (1, 2)
    sys.stdout.flush()
    sys.stderr.flush()
    libc.fflush(None)
    saved = [os.dup(fd) for fd in fds]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in fds:
            os.dup2(null, fd)
        yield
    finally:
        libc.fflush(None)  # C stdio buffers what PyBullet printed: out before the fds are back
        for fd, old in zip(fds, saved, strict=True):
            os.dup2(old, fd)
            os.close(old)
        os.close(null)
