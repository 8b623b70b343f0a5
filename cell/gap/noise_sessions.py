"""Sessions in a log's clock: repeats that straddle them are no scatter (`cell.gap.noise`).

A lab that throws in the morning and again in the afternoon, with no `session` column,
writes its throws' wall time (`time_s`) in two clusters hours apart. What changed between
them (a wind, a band set up again) moves every landing of the second; a configuration
thrown once in each parts by that change, and a floor taken from such pairs holds it: a
wind that differed between two sessions made the floor 0.0185 m where the scatter gave
0.0146 m, and the log was called `none` (docs/HISTORY.md, the eleventh lab round's E5).

The clusters (`time_sessions`): where every row has a finite `time_s`, the log's times
sorted are split at every gap longer than `CLUSTER_GAP` times the median gap between
successive throws; 2 to `cell.gap.propose_sessions.MAX_SESSIONS` clusters of 2 throws or more each
are sessions, else there are none.

The test (`session_split`): the repeat groups (`cell.gap.noise.repeat_groups`) are split by
cluster; each group's misses part into their spread within its clusters (SS_w over
Σ (n_gc − 1) degrees of freedom) and the spread of its clusters' means about its own
(SS_b over Σ (k_g − 1), k_g its clusters). Without a change between sessions both mean
squares estimate the scatter's variance and their ratio F follows Fisher's F with
2 Σ (k_g − 1) and 2 Σ (n_gc − 1) degrees of freedom (two coordinates a throw). Where its
upper tail is below `SESSION_ALPHA`, and the within-cluster repeats alone have
`cell.gap.noise.MIN_REPEAT_DOF` degrees of freedom, the floor from repeats is theirs
alone; the throws of one cluster are then repeats of one another only, as those of two
`session` values are. The proposal is given the clusters as `[session = …]`
(`cell.gap.propose_sessions.log_covariates`) wherever the log has no `session` column.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.problem import GapProblem

__all__ = ["CLUSTER_GAP", "SESSION_ALPHA", "time_sessions", "session_split"]

CLUSTER_GAP = 20.0  # a gap this many times the median gap between throws parts two sessions
SESSION_ALPHA = 1e-3  # the F test's level: repeats across sessions part more than within


def time_sessions(prob: GapProblem) -> np.ndarray | None:
    """Each throw's session (0, 1, … in time order) by gaps in its `time_s`, or None
    where the log has no such clusters (see the module docstring)."""
    from cell.gap.propose_sessions import MAX_SESSIONS

    t = prob.table
    if "time_s" not in t.columns or len(prob) < 4:
        return None
    ts = np.asarray(t.num("time_s"), float)
    if not np.all(np.isfinite(ts)):
        return None
    order = np.argsort(ts, kind="stable")
    gaps = np.diff(ts[order])
    pos = gaps[gaps > 0]
    if pos.size == 0:
        return None
    cut = gaps > CLUSTER_GAP * float(np.median(pos))
    label = np.empty(len(ts), int)
    label[order] = np.r_[0, np.cumsum(cut)]
    counts = np.bincount(label)
    if not 2 <= counts.size <= MAX_SESSIONS or counts.min() < 2:
        return None
    return label


def session_split(prob: GapProblem, residual: np.ndarray) -> dict[str, Any] | None:
    """The repeats' account by time session (the report's `noise.time_sessions`), or
    None where the log has no clusters or no repeat straddles two: `sessions` (each one's
    first and last `time_s` and its throws), `within_m` and `within_dof` (the repeats'
    floor within sessions), `across_m` and `across_dof` (the root mean square of the
    sessions' means about their group's, per degree of freedom), `f`, `p` and `used`
    (the floor is taken within sessions)."""
    from scipy.stats import f as fisher

    from cell.gap.noise import MIN_REPEAT_DOF, repeat_groups

    label = time_sessions(prob)
    if label is None:
        return None
    r = np.asarray(residual, float)
    ss_w = ss_b = 0.0
    dof_w = dof_b = 0
    for ids in repeat_groups(prob):
        if len(ids) < 2:
            continue
        g = r[ids]
        parts = [np.flatnonzero(label[ids] == s) for s in np.unique(label[ids])]
        for p in parts:
            ss_w += float(np.sum((g[p] - g[p].mean(axis=0)) ** 2))
            dof_w += len(p) - 1
        if len(parts) > 1:
            mean = g.mean(axis=0)
            ss_b += float(sum(len(p) * np.sum((g[p].mean(axis=0) - mean) ** 2) for p in parts))
            dof_b += len(parts) - 1
    if dof_b == 0 or dof_w == 0:
        return None
    ms_w, ms_b = ss_w / dof_w, ss_b / dof_b
    f = ms_b / ms_w if ms_w > 0 else float("inf")
    p_value = float(fisher.sf(f, 2 * dof_b, 2 * dof_w))
    ts = np.asarray(prob.table.num("time_s"), float)
    sessions = [
        {"from_s": float(ts[label == s].min()), "to_s": float(ts[label == s].max()),
         "throws": int(np.sum(label == s))}
        for s in range(int(label.max()) + 1)
    ]  # fmt: skip
    return {
        "sessions": sessions,
        "within_m": float(np.sqrt(ms_w)),
        "within_dof": dof_w,
        "across_m": float(np.sqrt(ms_b)),
        "across_dof": dof_b,
        "f": float(f),
        "p": p_value,
        "alpha": SESSION_ALPHA,
        "used": bool(p_value < SESSION_ALPHA and dof_w >= MIN_REPEAT_DOF),
    }
