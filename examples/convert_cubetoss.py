"""Convert DAIR Lab's real cube tosses (ContactNets) to the slice shipped in
tests/data/contactnets_cube/flights.csv.gz.

Source: github.com/DAIRLab/contact-nets (BSD-3-Clause), folder `data/tosses_processed`:
570 files `N.pt`, one toss each, of an acrylic cube (0.37 kg, 0.1048 m a side) tossed by
hand onto a board and tracked by AprilTags on its faces at 148 frames per second. Each
file is a tensor saved by PyTorch's legacy serializer (a pickle stream followed by the raw
storage), read here without PyTorch: of shape (1, frames, 19), columns position (3, in
units of the cube's half width, 0.0524 m), quaternion (4, real part first), velocity (3),
angular velocity (3), control (6, zeros). The board's frame: z along the board's normal,
the board's top at a corner height of 0. A toss starts after the release, the cube over the
board and falling.

Kept per toss: its frames from the first to 10 after the first contact with the board (the
first frame after which the height's second difference turns upward while the cube's
lowest corner is within 1 cm of the board). Written: toss (0-569), frame (from 0), x_m,
y_m, z_m (the cube's centre in the board's frame, metres, rounded to 0.01 mm). The
orientation, velocity and control columns are dropped; time is frame / 148 Hz (the files
carry no time stamps).

    python examples/convert_cubetoss.py contact-nets/data/tosses_processed \
        tests/data/contactnets_cube/flights.csv.gz
"""

from __future__ import annotations

import argparse
import csv
import gzip
import io
import pickle
import struct
from pathlib import Path
from typing import Any

import numpy as np

HALF_WIDTH_M = 0.0524  # the cube's half width: the files' unit of length
AFTER_CONTACT = 10  # frames kept after the first contact (so that a test can cut it or not)
NEAR_BOARD_M = 0.01  # [m] the lowest corner is this near the board at a contact
COLUMNS = 19


class _Storage:
    def __init__(self, key: str) -> None:
        self.key = key


def _rebuild(storage: _Storage, offset: int, size: tuple, stride: tuple, *_: Any) -> tuple:
    return storage, offset, tuple(size), tuple(stride)


class _Unpickler(pickle.Unpickler):
    """Only what a saved double tensor refers to; anything else is refused."""

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) == ("torch._utils", "_rebuild_tensor_v2"):
            return _rebuild
        if (module, name) == ("torch", "DoubleStorage"):
            return name
        if (module, name) == ("collections", "OrderedDict"):
            return dict
        raise pickle.UnpicklingError(f"not a saved double tensor: {module}.{name}")

    def persistent_load(self, pid: Any) -> _Storage:
        return _Storage(str(pid[2]))


def read_toss(path: Path) -> np.ndarray:
    """(frames, 19) float64 of one toss file (module docstring); SystemExit naming the file
    where it is not a legacy-format double tensor of that shape."""
    fh = io.BytesIO(path.read_bytes())
    try:
        for _ in range(3):  # magic number, protocol version, system info
            pickle.load(fh)
        storage, offset, size, stride = _Unpickler(fh).load()
        keys = pickle.load(fh)
        (count,) = struct.unpack("<q", fh.read(8))
        flat = np.frombuffer(fh.read(8 * count), dtype="<f8")
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError, struct.error) as exc:
        raise SystemExit(f"{path}: not a legacy PyTorch double tensor: {exc}") from exc
    if keys != [storage.key] or len(size) != 3 or size[0] != 1 or size[2] != COLUMNS:
        raise SystemExit(f"{path}: expected one tensor of shape (1, frames, {COLUMNS}), got {size}")
    strides = [8 * s for s in stride]
    return np.lib.stride_tricks.as_strided(flat[offset:], shape=size, strides=strides)[0].copy()


def lowest_corner_m(a: np.ndarray) -> np.ndarray:
    """Height [m] of the cube's lowest corner above the board, per frame."""
    w, x, y, z = a[:, 3], a[:, 4], a[:, 5], a[:, 6]
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    # third row of the rotation matrix: a body vector's height in the board's frame
    row = np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=1)
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)])
    return HALF_WIDTH_M * (a[:, 2:3] + row @ corners.T).min(axis=1)


def first_contact(a: np.ndarray) -> int | None:
    """Index of the last frame before the first contact (module docstring), or None."""
    z = a[:, 2] * HALF_WIDTH_M
    low = lowest_corner_m(a)
    for j in range(1, len(z) - 1):
        if z[j + 1] - 2 * z[j] + z[j - 1] > 0 and min(low[j], low[j + 1]) < NEAR_BOARD_M:
            return j
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="contact-nets' data/tosses_processed")
    ap.add_argument("out", type=Path, help="flights.csv.gz to write")
    args = ap.parse_args(argv)
    files = sorted(args.folder.glob("*.pt"), key=lambda p: int(p.stem) if p.stem.isdigit() else -1)
    if not files or not files[0].stem.isdigit():
        raise SystemExit(f"{args.folder}: no toss files N.pt")
    rows, left_out = [], 0
    for path in files:
        a = read_toss(path)
        j = first_contact(a)
        if j is None:
            left_out += 1
            continue
        for f, p in enumerate(a[: j + 2 + AFTER_CONTACT, :3] * HALF_WIDTH_M):
            rows.append((int(path.stem), f, f"{p[0]:.5f}", f"{p[1]:.5f}", f"{p[2]:.5f}"))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["toss", "frame", "x_m", "y_m", "z_m"])
    w.writerows(rows)
    with open(args.out, "wb") as raw, gzip.GzipFile("", "wb", fileobj=raw, mtime=0) as fh:
        fh.write(buf.getvalue().encode())  # no name, no time: the same bytes every run
    n = len({r[0] for r in rows})
    print(f"{args.out}: {len(rows)} samples of {n} tosses ({left_out} without a contact left out)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
