"""The noise floor F: the held-out miss no model of the logged quantities could remove.

Three estimates of it:

* repeats: throws logged with the same object, stroke, pose, platform and
  plane, in the same session (`session`, where the log has it), are repeats;
  the pooled spread of their misses about each group's mean is the scatter
  itself (unbiased, with Σ(n_g - 1) degrees of freedom). When there are
  enough repeats, this is F.
* neighbours (the Gamma test): half the mean squared difference of the misses
  of the k-th nearest throws, against their mean squared distance, for
  k = 1…10, extrapolated to distance zero. The distance is taken in the space
  of the model's trajectory (landing point, impact and launch velocity, flight
  time): two throws on the same trajectory share whatever unmodelled effect
  acts on it, so their misses differ by the scatter alone.
* a flexible model: gradient-boosted trees of the misses (along and across the
  flight direction) on every logged quantity, the throw order and the model's
  trajectory, cross-validated; what they still leave on held-out throws.

Without repeats F is the smaller of the last two (each is biased up by what
it cannot resolve).

Throws of two sessions of the log's clock (`time_s` in clusters hours apart, no
`session` column) are repeats of each other too, unless those across the sessions part
significantly more than those within one: then the floor is the within-session
repeats' (`cell.gap.noise_sessions`).

Repeats see only what scatters between throws of one configuration (the
tracker). What the configured model misses on each configuration by its own
amount, not smooth in the logged quantities, is floor too, and repeats cannot
see it. A parameter file made by `cell calibrate --validate` knows it: its
model's RMS miss on held-out throws per object (`cell.params.Validation`). With
it, a floor from repeats takes it in quadrature:

    F² = F_rep² + mean over the throws of their object's validated misfit²

(an object the file does not validate adds nothing); the method is then
`repeats+validated`. Without repeats the other estimates already carry that
misfit, and nothing is added.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.gap.problem import GapProblem
from cell.kinds import PLATFORMS
from cell.model.throw import Landing

__all__ = ["NoiseFloor", "noise_floor", "features", "repeat_groups", "validated"]

log = logging.getLogger(__name__)

MIN_REPEAT_DOF = 30


@dataclass(frozen=True)
class NoiseFloor:
    """The noise floor and its estimates [m] (NaN where not available).

    `validated_m` is the RMS over the throws of their objects' held-out misfit (the
    parameter file's validation; unvalidated objects count 0), `validated_share` the
    share of throws whose object it validates.
    """

    floor_m: float
    repeats_m: float
    repeat_dof: int
    neighbours_m: float
    model_m: float
    method: str
    validated_m: float = float("nan")
    validated_share: float = 0.0
    time_sessions: dict[str, Any] | None = None


def features(prob: GapProblem) -> np.ndarray:
    """Every logged quantity per throw as a float matrix (n, q), plus the throw order."""
    t = prob.table
    cols = [
        "stroke_m", "x_m", "y_m", "z_m", "elevation_rad", "azimuth_rad", "roll_rad",
        "vx_mps", "vy_mps", "vz_mps", "rotor_rpm", "land_z_m", "mass_kg",
        "size_x_m", "size_y_m", "size_z_m",
    ]  # fmt: skip
    out = [t.num(c) for c in cols]
    out.append(np.asarray(prob.batch.shape, float))
    plat = t.text("platform")
    out.append(np.array([PLATFORMS.index(p) for p in plat], float))
    out.append(np.arange(len(prob), dtype=float))
    for c in ("time_s",):
        if c in t.columns:
            out.append(t.num(c))
    x = np.stack(out, axis=1)
    return np.where(np.isfinite(x), x, -1.0)


def _repeat_key(prob: GapProblem) -> list[tuple]:
    t = prob.table
    q = np.round(
        np.stack(
            [
                np.nan_to_num(t.num("stroke_m"), nan=-1.0) / 5e-4,
                t.num("x_m") / 5e-3,
                t.num("y_m") / 5e-3,
                t.num("z_m") / 5e-3,
                t.num("elevation_rad") / 2e-3,
                t.num("azimuth_rad") / 2e-3,
                t.num("vx_mps") / 1e-2,
                t.num("vy_mps") / 1e-2,
                t.num("vz_mps") / 1e-2,
                t.num("rotor_rpm") / 50.0,
                t.num("land_z_m") / 5e-3,
            ],
            axis=1,
        )
    ).astype(np.int64)
    oid = t.text("object_id")
    # throws of two sessions are no repeats: a band changed or a launcher set up again
    # between them moves every landing of the second, which is no scatter
    sess = t.text("session") if "session" in t.columns else [""] * len(prob)
    return [(oid[i], sess[i], *q[i].tolist()) for i in range(len(prob))]


def repeat_groups(prob: GapProblem) -> list[list[int]]:
    """The throws' row indices grouped by configuration (same object, stroke, pose,
    platform and plane, in the same session, `_repeat_key`), in order of first appearance."""
    groups: dict[tuple, list[int]] = {}
    for i, k in enumerate(_repeat_key(prob)):
        groups.setdefault(k, []).append(i)
    return list(groups.values())


def _repeats(prob: GapProblem, r: np.ndarray) -> tuple[float, int]:
    ss = 0.0
    dof = 0
    for ids in repeat_groups(prob):
        if len(ids) > 1:
            g = r[ids]
            ss += float(np.sum((g - g.mean(axis=0)) ** 2))
            dof += len(ids) - 1
    if dof < MIN_REPEAT_DOF:
        return float("nan"), dof
    return float(np.sqrt(ss / dof)), dof


def _trajectory(prob: GapProblem, land: Landing) -> np.ndarray:
    """The model's trajectory per throw, standardised: landing point, impact and launch
    velocity, flight time."""
    f = np.c_[land.xy, land.impact_velocity, land.t_flight, land.launch_velocity]
    f = np.where(np.isfinite(f), f, 0.0)
    return (f - f.mean(axis=0)) / np.maximum(f.std(axis=0), 1e-12)


def _neighbours(prob: GapProblem, r: np.ndarray, land: Landing, kmax: int = 10) -> float:
    from scipy.spatial import cKDTree

    z = _trajectory(prob, land)
    n = len(prob)
    if n < kmax + 2:
        return float("nan")
    dist, j = cKDTree(z).query(z, k=kmax + 1)
    own = np.arange(n)
    gam, delta = [], []
    for k in range(1, kmax + 1):
        # duplicates tie at distance 0: never pair a throw with itself
        other = np.where(j[:, k] != own, j[:, k], j[:, k - 1])
        gam.append(np.mean(np.sum((r - r[other]) ** 2, axis=1)) / 2)
        delta.append(np.mean(dist[:, k] ** 2))
    if np.ptp(delta) <= 0.0:
        # every throw's kmax nearest are repeats of it (distance 0): no slope to fit, the
        # pairs' mean is the value at distance 0 (a line through one x is singular)
        icpt = float(np.mean(gam))
    else:
        slope, icpt = np.polyfit(delta, gam, 1)
    # the intercept is noisy; keep it between half and all of the nearest-pair value
    return float(np.sqrt(np.clip(icpt, 0.5 * gam[0], gam[0])))


def _model(prob: GapProblem, r: np.ndarray, x: np.ndarray, land: Landing) -> float:
    n = len(prob)
    # along and across the flight direction: most effects act along it
    rel = np.nan_to_num(land.xy - prob.batch.position[:, :2])
    d = rel / np.maximum(np.linalg.norm(rel, axis=1), 1e-9)[:, None]
    r = np.c_[np.sum(r * d, axis=1), r[:, 1] * d[:, 0] - r[:, 0] * d[:, 1]]
    x = np.c_[
        x,
        np.cos(prob.batch.azimuth),
        np.sin(prob.batch.azimuth),
        np.nan_to_num(np.c_[land.xy, land.impact_velocity, land.t_flight, land.launch_velocity]),
    ]
    pred = np.zeros_like(r)
    fid = np.random.default_rng(prob.seed + 1).permutation(n) % 4
    # sklearn's OpenMP loaded before the limit (threadpoolctl limits loaded libraries)
    from sklearn.ensemble import HistGradientBoostingRegressor  # noqa: F401

    # one OpenMP thread: eight fits of a few hundred rows each; on a busy machine the
    # threads spin waiting for a core (a 60-throw world: 33.3 CPU-s with them, 12.1
    # without, the report the same); the fits' results do not depend on the threads
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="openmp"):
        _fit_folds(x, r, fid, pred, prob.seed)
    return float(np.sqrt(np.mean(np.sum((r - pred) ** 2, axis=1))))


def _fit_folds(x: np.ndarray, r: np.ndarray, fid: np.ndarray, pred: np.ndarray, seed: int) -> None:
    """Each fold's held-out misses predicted by boosted trees fitted on the others, into
    `pred` (along and across)."""
    from sklearn.ensemble import HistGradientBoostingRegressor

    for f in range(4):
        tr, te = fid != f, fid == f
        for j in range(2):
            m = HistGradientBoostingRegressor(
                max_iter=150, learning_rate=0.08, max_leaf_nodes=8, min_samples_leaf=8,
                random_state=seed,
            )  # fmt: skip
            m.fit(x[tr], r[tr, j])
            pred[te, j] = m.predict(x[te])


def noise_floor(prob: GapProblem, residual: np.ndarray, land: Landing) -> NoiseFloor:
    """Estimate the noise floor from the configured model's misses.

    Args:
        prob: the problem.
        residual: observed minus predicted landing [m], shape (n, 2).
        land: the configured model's landings (its trajectories).

    Returns:
        The floor (repeats when there are enough, else the smaller other estimate)
        and each estimate.
    """
    from cell.gap.noise_sessions import session_split

    x = features(prob)
    rep, dof = _repeats(prob, residual)
    split = session_split(prob, residual)
    if split is not None and split["used"]:
        # repeats across sessions of the log's clock part by what changed between them
        rep, dof = split["within_m"], split["within_dof"]
    nn = _neighbours(prob, residual, land)
    # the flexible model is slow and biased up: only when there are no repeats to go by
    need_model = not np.isfinite(rep) and len(prob) >= 50
    mod = _model(prob, residual, x, land) if need_model else float("nan")
    cands = {"repeats": rep, "neighbours": nn, "model": mod}
    if np.isfinite(rep):
        method = "repeats"
    else:
        ok = {k: v for k, v in cands.items() if np.isfinite(v)}
        method = min(ok, key=lambda k: ok[k])
    floor = cands[method]
    val, share = validated(prob)
    if method == "repeats" and share > 0:
        method = "repeats+validated"
        floor = float(np.hypot(rep, val))
    log.info("noise floor estimates: %s; validated misfit %.4f m", cands, val)
    return NoiseFloor(
        floor_m=floor,
        repeats_m=rep,
        repeat_dof=dof,
        neighbours_m=nn,
        model_m=mod,
        method=method,
        validated_m=val,
        validated_share=share,
        time_sessions=split,
    )


def validated(prob: GapProblem) -> tuple[float, float]:
    """The throws' validated misfit [m]: sqrt of the mean over the throws of their
    object's held-out misfit squared (0 for an object not validated), and the share of
    throws whose object is validated; (NaN, 0) without a validation."""
    v = prob.validated_m
    if v is None or len(v) == 0:
        return float("nan"), 0.0
    known = np.isfinite(v)
    if not known.any():
        return float("nan"), 0.0
    return float(np.sqrt(np.mean(np.where(known, v, 0.0) ** 2))), float(known.mean())
