"""Convert MPI-IS's recorded table-tennis episodes (tennicam ball tracking) to the slice
shipped in tests/data/tabletennis_tennicam/flights.csv.gz.

Source: github.com/intelligent-soft-robots/pam_configuration (BSD-3-Clause), file
`config/context/ball_trajectories/o80_robot_ball.zip`: 50 episodes `o80_robot_ball_NNN`,
each a text file of one Python tuple per line, `((ball_id, time_stamp_ns, [x, y, z],
[vx, vy, vz]), (robot ...))`, written by the lab's o80 logger while the ball launcher
shot a ball at the table and the robot played it. `ball_id` is the tracker's frame
number (-1: no ball seen); a frame is logged once per robot cycle, so it repeats.

Kept per episode: every ball frame once (the first line of each frame number), from the
first frame the ball is seen to 15 frames after its first bounce on the table (the first
local minimum of the height below 0.9 m that the height then leaves upward by over 5 mm
within two frames). Written: episode (1-50), frame (the tracker's frame number), t_ns
(the frame's time stamp less the episode's first one), x_m, y_m, z_m (the tracker's
frame, z up, rounded to 0.01 mm). The velocity columns and the robot's state are dropped.

    python examples/convert_tennicam.py o80_robot_ball.zip tests/data/tabletennis_tennicam/flights.csv.gz
"""

from __future__ import annotations

import argparse
import ast
import csv
import gzip
import io
import re
import sys
import zipfile
from pathlib import Path

AFTER_BOUNCE = 15  # frames kept after the first bounce (so that a test can cut it or not)
TABLE_BELOW_M = 0.9  # [m] a bounce's lowest ball centre is below this height


def episode_frames(text: str, name: str) -> list[tuple[int, int, float, float, float]]:
    """The ball frames of one episode: (frame, time stamp [ns], x, y, z [m]), each frame
    once, in order; lines that are not the logger's tuple are an error naming the line."""
    out: list[tuple[int, int, float, float, float]] = []
    seen: set[int] = set()
    for n, line in enumerate(text.splitlines(), 1):
        if not line.strip():
            continue
        try:
            ball = ast.literal_eval(line)[0]
            fid, stamp, pos = int(ball[0]), int(ball[1]), [float(c) for c in ball[2]]
        except (ValueError, SyntaxError, TypeError, IndexError) as exc:
            raise SystemExit(f"{name}: line {n}: not a logged (ball, robot) tuple: {exc}") from exc
        if fid < 0 or fid in seen:
            continue
        seen.add(fid)
        out.append((fid, stamp, pos[0], pos[1], pos[2]))
    return out


def first_bounce(z: list[float]) -> int | None:
    """Index of the first bounce on the table (module docstring), or None."""
    for j in range(1, len(z) - 2):
        if z[j] < TABLE_BELOW_M and z[j] <= z[j - 1] and z[j] <= z[j + 1]:
            if max(z[j + 1], z[j + 2]) > z[j] + 0.005:
                return j
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("zip", type=Path, help="o80_robot_ball.zip from pam_configuration")
    ap.add_argument("out", type=Path, help="flights.csv.gz to write")
    args = ap.parse_args(argv)
    rows = []
    with zipfile.ZipFile(args.zip) as zf:
        names = sorted(n for n in zf.namelist() if re.fullmatch(r"o80_robot_ball_\d+", n))
        for name in names:
            frames = episode_frames(zf.read(name).decode(), name)
            j = first_bounce([f[4] for f in frames])
            if j is None:
                print(f"{name}: no bounce on the table found, left out", file=sys.stderr)
                continue
            t0 = frames[0][1]
            ep = int(name.rsplit("_", 1)[1])
            for fid, stamp, x, y, z in frames[: j + 1 + AFTER_BOUNCE]:
                rows.append((ep, fid, stamp - t0, f"{x:.5f}", f"{y:.5f}", f"{z:.5f}"))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["episode", "frame", "t_ns", "x_m", "y_m", "z_m"])
    w.writerows(rows)
    with open(args.out, "wb") as raw, gzip.GzipFile("", "wb", fileobj=raw, mtime=0) as fh:
        fh.write(buf.getvalue().encode())  # no name, no time: the same bytes every run
    print(f"{args.out}: {len(rows)} samples of {len({r[0] for r in rows})} episodes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
