"""The proposal's covariates of a log's order and sessions, and a wind per session.

`log_covariates` gives the throw order over the log and an indicator of each session but
the first: of the `session` column where the log has one, else of the sessions of the
log's clock (`time_s` in clusters hours apart, `cell.gap.noise_sessions.time_sessions`),
named by their first throw's time (`[session = time_s ≥ 50402]`). `session_winds` gives,
for each session indicator, air moving along world x or y in that session only: a wind
or a draught that changed between two sessions moves each throw's landing by its own
drag, which no constant force of the library takes up (a light cube's landing moves
three times a heavy block's).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from cell.gap.problem import GapProblem

__all__ = ["MAX_SESSIONS", "H_WIND", "log_covariates", "time_session_names", "session_winds"]

MAX_SESSIONS = 6  # a log of more sessions than this has no session terms (its order terms stay)
H_WIND = 0.1  # [m/s] the wind terms' finite-difference step


def log_covariates(prob: GapProblem) -> dict[str, np.ndarray]:
    """The throw-order and session covariates of a log (name -> values over its throws).

    `order` runs from 0 at the first throw to 1 at the last: by `time_s` where every
    diagnosed row has one (and they differ), else by the rows' order in the log. A
    `session = s` indicator is there for each session but the first (in order of
    appearance) where the log has 2 to MAX_SESSIONS sessions, each of 2 throws or more;
    without a `session` column, the sessions of the log's clock (`time_session_names`)."""
    t = prob.table
    n = len(prob)
    out: dict[str, np.ndarray] = {}
    if n < 2:
        return out
    order = np.arange(n, dtype=float)
    if "time_s" in t.columns:
        ts = np.asarray(t.num("time_s"), float)
        if np.all(np.isfinite(ts)) and np.ptp(ts) > 0:
            order = ts
    out["order"] = (order - order.min()) / np.ptp(order)
    sess = t.text("session") if "session" in t.columns else time_session_names(prob)
    if sess is not None:
        names = list(dict.fromkeys(sess))
        counts = [sess.count(s) for s in names]
        if 2 <= len(names) <= MAX_SESSIONS and min(counts) >= 2:
            for s in names[1:]:
                out[f"[session = {s}]"] = np.array([x == s for x in sess], float)
    return out


def time_session_names(prob: GapProblem) -> list[str] | None:
    """Each throw's session by the log's clock (`cell.gap.noise_sessions.time_sessions`)
    as a name, `time_s ≥ T` (T its first throw's `time_s` [s]), or None."""
    from cell.gap.noise_sessions import time_sessions

    label = time_sessions(prob)
    if label is None:
        return None
    ts = np.asarray(prob.table.num("time_s"), float)
    first = {int(s): f"time_s ≥ {ts[label == s].min():.0f}" for s in np.unique(label)}
    return [first[int(s)] for s in label]


def session_winds(in_log: dict[str, np.ndarray]
                  ) -> list[tuple[str, Callable[..., np.ndarray], float]]:  # fmt: skip
    """Where the log has sessions (`[session = s]` covariates), air moving at `H_WIND`
    along world x and along y on every throw (the first session's wind) and on each
    session's throws only (its change): (the term, the air velocity (p, v, idx) -> (m, 3)
    [m/s], its step); none without sessions (a steady wind is the vocabulary's)."""
    out: list[tuple[str, Callable[..., np.ndarray], float]] = []
    sessions = [c for c in in_log if c.startswith("[session = ")]
    for c in [""] + sessions:
        on = in_log[c] if c else None
        for j, axis in enumerate("xy"):
            unit = H_WIND * np.eye(3)[j]
            out.append((f"wind {axis} [m/s] = k{' · ' + c if c else ''}",
                        lambda p, v, i, u=unit, s=on: (1.0 if s is None else s[i][:, None]) * u,
                        H_WIND))  # fmt: skip
    return out if sessions else []
