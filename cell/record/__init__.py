"""Rerun recordings of runs: a replay a person can scrub through (`rerun run.rrd`).

The recording is optional: nothing here imports `rerun` until a recording is
opened (`cell.record.stream.Recording`), so a command without `--record` never
loads it. Layers:

- `stream`: a `.rrd` file written through a dedicated `rerun.RecordingStream`,
  fed plain data (arrays, dicts): scene boxes, poses, line strips, scalars, text.
- `bodies`: what a PyBullet body looks like (visual shapes, meshes) and where
  its links are, as plain data.
- `flight`: the model's predicted flight of a planned throw, sampled in time.
- `run`: the sort-run recorder, an observer the sort loop calls at scene set-up,
  item start, release, flight and item done.
- `gap`, `calibrate`: recordings of `cell gap` and `cell calibrate`.

Timelines: `sim_time` (simulated seconds, a duration) and `item` (a sequence:
the item's index in the job, or the throw's row in a log).
"""

from __future__ import annotations

__all__ = ["RECORD_EXTRA"]

RECORD_EXTRA = "pip install 'cell[record]'  (rerun-sdk>=0.41,<0.42)"
