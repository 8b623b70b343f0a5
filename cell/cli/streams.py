"""The command's standard streams as a user's shell may hand them over (docs/cli_inputs.md).

- A standard stream closed by the shell (`cell run JOB >&-`, `2>&-`, `<&-`): its file
  descriptor gets /dev/null before the command opens anything. Left closed, the next file
  opened (the throw store, an output's temporary file) took descriptor 1 or 2, where
  PyBullet's C code writes its banners, and Python's `sys.stdout` was None (a traceback
  from the first flush).
- A standard output that fails while the results are printed (its reader gone,
  `cell run JOB --json out.json | head -1`; a full disk, `> /dev/full`): the rest of the
  printing goes to /dev/null and the command goes on, so the output files it writes after
  the text (`--json PATH`, `-o`, `--snapshot`) are still written; the failure is said when
  the command ends. Before, the first failed write ended the command there and no output
  file was written.
- A character the standard output's encoding has no byte for (a bin named `ящик` with
  `PYTHONIOENCODING=ascii`) is printed as its escape, `\\u044f`, not a traceback.
"""

from __future__ import annotations

import contextlib
import errno
import os
import sys
from collections.abc import Iterator
from typing import Any, TextIO

__all__ = ["Guarded", "guarded_streams", "open_standard_fds", "said_failure"]


def open_standard_fds() -> None:
    """Give /dev/null to file descriptors 0, 1 and 2 where they are closed, and a Python
    stream on it where `sys.stdin`, `sys.stdout` or `sys.stderr` is None."""
    for fd, flags in ((0, os.O_RDONLY), (1, os.O_WRONLY), (2, os.O_WRONLY)):
        try:
            os.fstat(fd)
        except OSError:
            null = os.open(os.devnull, flags)  # the lowest free descriptor: fd itself
            if null != fd:
                os.dup2(null, fd)
                os.close(null)
    if sys.stdin is None:
        sys.stdin = open(0, closefd=False)  # noqa: SIM115 (the process's own stream)
    if sys.stdout is None:
        sys.stdout = open(1, "w", closefd=False)  # noqa: SIM115
    if sys.stderr is None:
        sys.stderr = open(2, "w", closefd=False)  # noqa: SIM115


class Guarded:
    """Standard output that keeps the command going when it fails: the first `OSError` of
    a write or flush is kept in `failure`, descriptor 1 is pointed at /dev/null (so
    Python's last flush at exit does not fail again) and every later write is dropped."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.failure: OSError | None = None

    def write(self, text: str) -> int:
        if self.failure is None:
            try:
                try:
                    self.stream.write(text)
                except UnicodeEncodeError:
                    enc = getattr(self.stream, "encoding", None) or "utf-8"
                    self.stream.write(text.encode(enc, "backslashreplace").decode(enc))
            except OSError as exc:
                self._fail(exc)
        return len(text)

    def flush(self) -> None:
        if self.failure is None:
            try:
                self.stream.flush()
            except OSError as exc:
                self._fail(exc)

    def _fail(self, exc: OSError) -> None:
        self.failure = exc
        with contextlib.suppress(OSError, ValueError):  # a stream with no descriptor
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self.stream.fileno())
            os.close(null)

    def __getattr__(self, name: str) -> Any:  # isatty, fileno, encoding, ...
        return getattr(self.stream, name)


@contextlib.contextmanager
def guarded_streams() -> Iterator[tuple[Guarded, Guarded]]:
    """`sys.stdout` and `sys.stderr` each a `Guarded` of itself while the command runs (a
    reader of `2>&1 | head -1` gone while an item's line is said ends nothing either),
    flushed at the end."""
    out, err = Guarded(sys.stdout), Guarded(sys.stderr)
    sys.stdout, sys.stderr = out, err  # type: ignore[assignment]
    try:
        yield out, err
    finally:
        out.flush()
        err.flush()
        sys.stdout, sys.stderr = out.stream, err.stream


def said_failure(out: Guarded, err: Guarded, code: int) -> int:
    """The exit status once the command has ended with `code`: a reader gone (a broken
    pipe, on either stream) is 141 (128 + SIGPIPE, as a shell reports a command the pipe
    ended) and said nowhere, the reader having asked for no more; any other failure of
    standard output (a full disk) is said on standard error, status 2. A command's own
    failure (`code` not 0) is kept."""
    failed = [g.failure for g in (out, err) if g.failure is not None]
    if not failed:
        return code
    if any(isinstance(e, BrokenPipeError) or e.errno == errno.EPIPE for e in failed):
        return code or 141
    exc = out.failure
    if exc is not None and err.failure is None:
        print(
            f"cell: error: standard output: {exc.strerror or exc}; the text was cut short "
            "there and the command went on (its output files are written after the text)",
            file=sys.stderr,
        )
    return code or 2
