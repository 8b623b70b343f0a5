"""Two-stage parameter identification (thesis §4.1, Algorithm 1).

    η_ee ← η_ee,init; η_o^(j) ← η_o,init^(j) (CAD values, i.e. those the log carries)
    repeat
        stage 1: η_ee = argmin Σ_i ‖p_m(L_s^(i); η_o^(o_i), η_ee) − p_obs^(i)‖²     (all throws)
        stage 2: for each object j: η_o^(j) = argmin Σ_{i∈N_j} ‖p_m(L_s^(i); η_o^(j), η_ee) − p_obs^(i)‖²
    until the change of η_ee and of every η_o is below a threshold

Both stages are bounded nonlinear least squares (scipy's trust-region
reflective solver) on the landing points (x and y). From landing data alone
the parameters are strongly correlated (the launch depends on the impulse
f_o·Δt, the band length only through l1 + r_r φ, a heavier object and a
stronger band compensate each other), so each stage adds a small Tikhonov term
pulling the parameters toward a prior (by default the start values): it decides
the flat directions and moves nothing the data can see (its weight is 1 cm of
landing error per 100 % of parameter change). Stage 2 solves the K objects'
problems together: they are independent given η_ee (the objective is a sum of
per-object terms with no shared parameter), so the joint minimiser is each
object's own; the joint solve shares the Jacobian evaluations.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from cell.errors import InvalidParameter
from cell.identify.problem import (
    EE_NAMES,
    ThrowData,
    ee_bounds,
    ee_from_vector,
    ee_to_vector,
    push_jacobian,
)
from cell.log.table import ThrowTable
from cell.model.band import push_force
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch
from cell.params import ModelParams

__all__ = ["IdentifyOptions", "IdentifyResult", "identify"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class IdentifyOptions:
    """How identification runs.

    Attributes:
        max_iter: most outer (stage 1 + stage 2) iterations.
        tol: stop when no parameter changed by more than this between iterations,
            relative to its scale (η_ee: its reference magnitude; η_o: its start value).
        object_bound: η_o factors stay within 1 ± this (mass and extents).
        noise_m: the landing noise the prior is weighed against [m] (thesis §5.4: ~0.1 m).
        prior_rel: how far (relative, 1 σ) the parameters are believed to lie from the
            prior; the Tikhonov rows are noise_m / prior_rel · (relative change), a
            MAP estimate with Gaussian noise and prior.
        stage_nfev: most model evaluations of the solver per stage.
        stage_tol: the solver's relative cost and step tolerances within a stage.
        fit_objects: run stage 2 (False = identify η_ee only).
    """

    max_iter: int = 30
    tol: float = 2e-3
    object_bound: float = 0.3
    noise_m: float = 0.1
    prior_rel: float = 0.3
    stage_nfev: int = 30
    stage_tol: float = 1e-6
    fit_objects: bool = True

    def __post_init__(self) -> None:
        if self.max_iter < 1 or self.stage_nfev < 1:
            raise InvalidParameter(
                f"max_iter={self.max_iter} and stage_nfev={self.stage_nfev} must be ≥ 1"
            )
        for name in ("tol", "noise_m", "prior_rel", "stage_tol"):
            if not getattr(self, name) > 0:
                raise InvalidParameter(f"identify option {name}={getattr(self, name)} must be > 0")
        if not 0 < self.object_bound < 1:
            raise InvalidParameter(
                f"identify option object_bound={self.object_bound} must be in (0, 1)"
            )


@dataclass(frozen=True)
class IdentifyResult:
    """What identification found.

    Attributes:
        params: identified η_ee and η_o (for every object id of the log).
        iterations: outer iterations run.
        converged: the change fell below the threshold before max_iter.
        rmse_start_m: landing RMSE on the fitted throws with the start parameters [m].
        rmse_fit_m: landing RMSE on the fitted throws with the identified ones [m].
        history: per iteration (rmse_m after stage 1, rmse_m after stage 2, change).
        n_throws: throws fitted.
        seconds: wall time [s].
    """

    params: ModelParams
    iterations: int
    converged: bool
    rmse_start_m: float
    rmse_fit_m: float
    history: list[tuple[float, float, float]] = field(default_factory=list)
    n_throws: int = 0
    seconds: float = 0.0


def _rmse(res: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(res**2, axis=1))))


Problem = tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]


def stage1_problem(
    data: ThrowData, batch: ThrowBatch, ee: EndEffectorParams, anchor: np.ndarray, w: float
) -> Problem:
    """Stage-1 residual and Jacobian functions of the stage-1 vector z.

    Residuals: predicted minus observed landings (x, y per throw) [m], then the
    Tikhonov rows w · (z − anchor). The Jacobian chains the analytic ∂f_o/∂θ with
    one finite difference in the push of every throw at once, plus one in Δt.
    """
    n = len(data)
    cache: dict[str, Any] = {}

    def fun(z: np.ndarray) -> np.ndarray:
        e = ee_from_vector(z, ee)
        f_o = np.asarray(push_force(batch.stroke, batch.size[:, 0], e))
        res = data.residual(batch, e, push=f_o)
        cache.update(z=z.copy(), e=e, f_o=f_o, res=res)
        return np.concatenate([res.ravel(), w * (z - anchor)])

    def jac(z: np.ndarray) -> np.ndarray:
        if cache.get("z") is None or not np.array_equal(cache["z"], z):
            fun(z)
        e: EndEffectorParams = cache["e"]
        f_o: np.ndarray = cache["f_o"]
        res: np.ndarray = cache["res"]
        h_f = 1e-4 * np.maximum(np.abs(f_o), 1.0)  # [N]
        d_push = (data.residual(batch, e, push=f_o + h_f) - res) / h_f[:, None]
        j = d_push[:, :, None] * push_jacobian(batch, e)[:, None, :]
        h_dt = 1e-4 * z[7]
        e_dt = ee_from_vector(z + np.eye(8)[7] * h_dt, ee)
        j[:, :, 7] = (data.residual(batch, e_dt, push=f_o) - res) / h_dt
        return np.vstack([j.reshape(2 * n, 8), w * np.eye(8)])

    return fun, jac


def _stage1(
    data: ThrowData,
    batch: ThrowBatch,
    ee: EndEffectorParams,
    anchor: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
) -> EndEffectorParams:
    """η_ee given η_o: bounded least squares with the chained push Jacobian."""
    fun, jac = stage1_problem(data, batch, ee, anchor, opt.noise_m / opt.prior_rel)
    z0 = np.clip(ee_to_vector(ee), bounds[0], bounds[1])
    sol = least_squares(
        fun,
        z0,
        jac=jac,
        bounds=bounds,
        method="trf",
        max_nfev=opt.stage_nfev,
        x_scale=1.0,
        ftol=opt.stage_tol,
        xtol=opt.stage_tol,
    )
    log.debug("stage 1: %d evaluations, %d Jacobians, %s", sol.nfev, sol.njev, sol.message)
    return ee_from_vector(sol.x, ee)


def stage2_problem(data: ThrowData, ee: EndEffectorParams, w: float, upper: float) -> Problem:
    """Stage-2 residual and Jacobian functions of the vector of all objects' factors.

    Residuals: predicted minus observed landings [m], then w · (factors − 1). The
    Jacobian is block diagonal; slot s of every object is perturbed at once (a
    throw sees only its own object's factors), backwards where a factor is within
    a step of `upper`.
    """
    col, k = data.factor_columns()
    n = len(data)
    nslot = int((col >= 0).sum(axis=1).max())
    cache: dict[str, Any] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        res = data.residual(data.batch_with(data.objects_from_factors(x)), ee)
        cache.update(x=x.copy(), res=res)
        return np.concatenate([res.ravel(), w * (x - 1.0)])

    def jac(x: np.ndarray) -> np.ndarray:
        if cache.get("x") is None or not np.array_equal(cache["x"], x):
            fun(x)
        res: np.ndarray = cache["res"]
        j = np.zeros((n, 2, k))
        h = 1e-5
        rows = np.arange(n)
        for s in range(nslot):
            cols = col[:, s]
            has = cols >= 0
            step = np.zeros(k)
            # step backwards where a factor sits at its upper bound
            sign = np.where(x[cols[has]] + h > upper, -1.0, 1.0)
            step[cols[has]] = h * sign
            r2 = data.residual(data.batch_with(data.objects_from_factors(x + step)), ee)
            c_row = cols[data.obj]
            ok = c_row >= 0
            d = (r2 - res) / np.where(ok, step[np.maximum(c_row, 0)], 1.0)[:, None]
            j[rows[ok], :, c_row[ok]] = d[ok]
        return np.vstack([j.reshape(2 * n, k), w * np.eye(k)])

    return fun, jac


def _stage2(
    data: ThrowData,
    ee: EndEffectorParams,
    factors: np.ndarray,
    opt: IdentifyOptions,
) -> np.ndarray:
    """All objects' factors given η_ee: one block-diagonal bounded least-squares solve."""
    _, k = data.factor_columns()
    fun, jac = stage2_problem(data, ee, opt.noise_m / opt.prior_rel, 1 + opt.object_bound)
    lo = np.full(k, 1 - opt.object_bound)
    hi = np.full(k, 1 + opt.object_bound)
    sol = least_squares(
        fun,
        np.clip(factors, lo, hi),
        jac=jac,
        bounds=(lo, hi),
        method="trf",
        max_nfev=opt.stage_nfev,
        x_scale=1.0,
        ftol=opt.stage_tol,
        xtol=opt.stage_tol,
    )
    log.debug("stage 2: %d evaluations, %d Jacobians, %s", sol.nfev, sol.njev, sol.message)
    return sol.x


def identify(
    table: ThrowTable,
    start: ModelParams | None = None,
    *,
    prior: ModelParams | None = None,
    options: IdentifyOptions | None = None,
    progress: Callable[[int, float], None] | None = None,
) -> IdentifyResult:
    """Identify η_ee and every object's η_o from observed landings (Algorithm 1).

    Args:
        table: the throws to fit (rows without stroke or landing are left out).
        start: start η_ee and η_o (objects it does not name start from the values
            their rows log); None = reference defaults and the logged values.
        prior: what the Tikhonov term pulls toward (None = the start). η_o priors
            are always the start values of the objects.
        options: iteration and solver settings.
        progress: called after each outer iteration with (iteration, landing RMSE [m]).

    Returns:
        The identified parameters and how the fit went.

    Raises:
        InvalidInput: no usable throw in the table.
    """
    # The solver's small dense SVDs run far slower with BLAS threads fighting over
    # a busy machine's cores than on one thread.
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # optional: only a speed matter
        return _identify(table, start, prior, options, progress)
    with threadpool_limits(limits=1, user_api="blas"):
        return _identify(table, start, prior, options, progress)


def _identify(
    table: ThrowTable,
    start: ModelParams | None,
    prior: ModelParams | None,
    options: IdentifyOptions | None,
    progress: Callable[[int, float], None] | None,
) -> IdentifyResult:
    t0 = time.perf_counter()
    opt = options or IdentifyOptions()
    start = start or ModelParams()
    prior = prior or start
    data = ThrowData.from_table(table, start.objects)
    ee = start.ee
    bounds = ee_bounds(prior.ee)
    anchor = np.clip(ee_to_vector(prior.ee), bounds[0], bounds[1])
    _, k = data.factor_columns()
    factors = np.ones(k)
    batch = data.batch
    rmse_start = _rmse(data.residual(batch, ee))
    history: list[tuple[float, float, float]] = []
    converged = False
    it = 0
    for it in range(1, opt.max_iter + 1):
        z_old, f_old = ee_to_vector(ee), factors.copy()
        ee = _stage1(data, batch, ee, anchor, bounds, opt)
        r1 = _rmse(data.residual(batch, ee))
        if opt.fit_objects:
            factors = _stage2(data, ee, factors, opt)
            batch = data.batch_with(data.objects_from_factors(factors))
        r2 = _rmse(data.residual(batch, ee))
        change = float(
            max(np.max(np.abs(ee_to_vector(ee) - z_old)), np.max(np.abs(factors - f_old)))
        )
        history.append((r1, r2, change))
        log.info("iteration %d: rmse %.4f m (stage 1 %.4f m), change %.2e", it, r2, r1, change)
        if progress is not None:
            progress(it, r2)
        if change < opt.tol:
            converged = True
            break
    objects: dict[str, ObjectParams] = (
        data.objects_from_factors(factors) if opt.fit_objects else dict(data.start_objects)
    )
    note = (
        f"identified by two-stage least squares (Algorithm 1) from {len(data)} throws of "
        f"{len(objects)} objects: {it} iteration(s), "
        f"{'converged' if converged else 'stopped at max_iter'}; landing RMSE on the fitted "
        f"throws {rmse_start:.4f} m -> {history[-1][1]:.4f} m; identified: "
        + ", ".join(EE_NAMES)
        + " and each object's mass and extents"
    )
    return IdentifyResult(
        params=ModelParams(ee=ee, objects=objects, effects={}, note=note),
        iterations=it,
        converged=converged,
        rmse_start_m=rmse_start,
        rmse_fit_m=history[-1][1],
        history=history,
        n_throws=len(data),
        seconds=time.perf_counter() - t0,
    )
