"""A track's time beyond the release's range: milliseconds, or a clock's own time?

`t_s` is the time since the throw's release command, in seconds. A time far beyond any
flight was read as milliseconds wherever it would be a flight's time in them: a tracker
whose clock runs from its boot (3,600 s after an hour) was asked whether it wrote
milliseconds, which it had not. The step between the track's samples tells the two apart:
a tracker samples at tens to thousands of hertz, so in milliseconds its step is 0.5 or
more, in seconds under 0.5. The same step tells microseconds from milliseconds: a step of
`US_STEP` (500) or more would be a tracker sampling at 2 Hz or slower in milliseconds, where
in microseconds it is 2 kHz or slower (a tracker at 120 Hz steps 8,333 µs: 0.012 s written in
microseconds, 12,000, was asked whether it was 12 s in milliseconds). `track_time_problem`
reads the step where the track has a sample beside the one refused (`next_time` finds the
one after it in the file).
"""

from __future__ import annotations

import csv
import itertools
import math

__all__ = ["MAX_TRACK_TIME_S", "MS_STEP", "US_STEP", "track_time_problem", "next_time"]

# [s] a track's samples lie within this of the release command: no throw of a cell flies
# for minutes (from 100 m up a fall takes 4.5 s). Milliseconds or a clock's time lie beyond.
MAX_TRACK_TIME_S = 100.0
MS_STEP = 0.5  # a step between samples of this or more is milliseconds (a 2 Hz tracker in s)
US_STEP = 1000.0 * MS_STEP  # a step of this or more is microseconds (a 2 Hz tracker in ms)
PEEK_ROWS = 10000  # rows read past the refused one for the track's next sample


def track_time_problem(t: float, step: float | None = None) -> str:
    """What is wrong with a track sample's time `t` [s] ("" if nothing); `step`: the time
    to a neighbouring sample of its track, in the file's unit (None where it has none)."""
    if abs(t) <= MAX_TRACK_TIME_S:
        return ""
    clock = "a clock's time? t_s is the time since the throw's release command, in seconds"
    ms_fits = abs(t) / 1000.0 <= MAX_TRACK_TIME_S
    known = step is not None and math.isfinite(step) and step != 0.0
    us_fits = abs(t) / 1e6 <= MAX_TRACK_TIME_S and known and abs(step or 0.0) >= US_STEP
    if us_fits:
        unit = (
            f"its samples lie {abs(step or 0.0):g} apart, a tracker's step in microseconds: "
            f"is it {t / 1e6:g} s written in microseconds? (divide t_s by 1,000,000)"
        )
    elif ms_fits and (not known or abs(step or 0.0) >= MS_STEP):
        unit = f"is it {t / 1000.0:g} s written in milliseconds?"
    elif known:
        unit = (
            f"{clock}: its samples lie {abs(step or 0.0):g} apart, as seconds do, so subtract "
            "the release command's time on that clock (a tracker's time from its boot?)"
        )
    else:
        unit = clock
    return (
        f"{t:g} s is outside the valid range [{-MAX_TRACK_TIME_S:g}, {MAX_TRACK_TIME_S:g}]: {unit}"
    )


def next_time(path: str, row: int, throw_id: str) -> float | None:
    """The time of the next sample of track `throw_id` after data row `row` (1 = the first)
    of a tracks file, within `PEEK_ROWS` rows; None where there is none or it is no number."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            reader = csv.DictReader(fh)
            rows = (r for r in reader if r.get("throw_id") is not None)
            for rec in itertools.islice(rows, row, row + PEEK_ROWS):
                if (rec.get("throw_id") or "").strip() == throw_id:
                    return float((rec.get("t_s") or "").strip())
    except (OSError, UnicodeDecodeError, csv.Error, ValueError):
        return None
    return None
