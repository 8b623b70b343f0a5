"""Two-stage parameter identification (thesis §4.1, Algorithm 1).

    η_ee ← η_ee,init; η_o^(j) ← η_o,init^(j) (CAD values, i.e. those the log carries)
    repeat
        stage 1: η_ee = argmin Σ_i ‖p_m(L_s^(i); η_o^(o_i), η_ee) − p_obs^(i)‖²     (all throws)
        stage 2: for each object j: η_o^(j) = argmin Σ_{i∈N_j} ‖p_m(L_s^(i); η_o^(j), η_ee) − p_obs^(i)‖²
    until the change of η_ee and of every η_o is below a threshold

Both stages are bounded nonlinear least squares (scipy's trust-region
reflective solver) on the landing points (x and y), each residual divided by its
expected spread under the documented noise (`cell.synth.NoiseModel`: a far throw
spreads more along its direction than a near one), so that the fit is the
maximum-likelihood one; the weights follow the model's own predicted reach and
are renewed every outer iteration. From landing data alone the parameters are
strongly correlated (the launch depends on the impulse f_o·Δt, the band length
only through l1 + r_r φ, a heavier object and a stronger band compensate each
other), so each stage adds a Gaussian prior toward the start values (a MAP
estimate): η_ee with 1 σ = prior_rel of each parameter's scale.

Object factors by evidence (`cell.identify.select`): after a first fit, each
object's prior width is chosen by K-fold cross-validation over its throws from
a grid whose first entry, 0, keeps the catalogue values; the fit is then run
again with the chosen widths. Degenerate directions (`cell.identify.directions`):
at the solution, the SVD of the whitened joint Jacobian in units of the priors
says which combinations of parameters the data determine; the others are held
at their priors (a truncated-SVD step). Stage 2 solves the K objects' problems
together: they are independent given η_ee, so the joint minimiser is each
object's own; the joint solve shares the Jacobian evaluations.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.optimize import least_squares

from cell.errors import InvalidParameter, plural
from cell.identify.directions import Analysis, Direction, analyse, intervals, parameter_names
from cell.identify.objective import keep_better
from cell.identify.problem import (
    EE_NAMES,
    ThrowData,
    ee_bounds,
    ee_from_vector,
    ee_to_vector,
)
from cell.identify.stages import joint_jacobian, stage1_problem, stage2_problem
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch
from cell.params import ModelParams
from cell.synth import NoiseModel

if TYPE_CHECKING:
    from cell.identify.select import ObjectChoice

__all__ = [
    "IdentifyOptions",
    "IdentifyResult",
    "identify",
    "joint_jacobian",
    "stage1_problem",
    "stage2_problem",
]

log = logging.getLogger(__name__)


OBJECT_PRIORS = (0.0, 0.02, 0.05, 0.1, 0.3)


@dataclass(frozen=True)
class IdentifyOptions:
    """How identification runs.

    Attributes:
        max_iter: most outer (stage 1 + stage 2) iterations.
        tol: stop when no parameter changed by more than this between iterations,
            relative to its scale (η_ee: its reference magnitude; η_o: its start value).
        object_bound: η_o factors stay within 1 ± this (mass and extents).
        noise: the landing noise each residual is weighed by (maximum likelihood).
        prior_rel: 1 σ of the Gaussian prior of η_ee, relative to each parameter's scale
            (and of the objects' factors in the first pass).
        stage_nfev: most model evaluations of the solver per stage.
        stage_tol: the solver's relative cost and step tolerances within a stage.
        fit_objects: run stage 2 (False = identify η_ee only).
        object_priors: the prior widths (1 σ of each factor) cross-validation chooses
            from per object; 0 keeps the catalogue values. Empty: no selection, every
            object's factors with prior_rel.
        cv_folds: folds of the per-object cross-validation.
        determined_ratio: a combination of parameters counts as determined when the data
            pin it this many times tighter than its prior does; the others are held at
            the prior.
    """

    max_iter: int = 30
    tol: float = 2e-3
    object_bound: float = 0.3
    noise: NoiseModel = field(default_factory=NoiseModel)
    prior_rel: float = 0.3
    stage_nfev: int = 30
    stage_tol: float = 1e-6
    fit_objects: bool = True
    object_priors: tuple[float, ...] = OBJECT_PRIORS
    cv_folds: int = 5
    determined_ratio: float = 1.0

    def __post_init__(self) -> None:
        if self.max_iter < 1 or self.stage_nfev < 1:
            raise InvalidParameter(
                f"max_iter={self.max_iter} and stage_nfev={self.stage_nfev} must be ≥ 1"
            )
        for name in ("tol", "prior_rel", "stage_tol", "determined_ratio"):
            if not getattr(self, name) > 0:
                raise InvalidParameter(f"identify option {name}={getattr(self, name)} must be > 0")
        if not 0 < self.object_bound < 1:
            raise InvalidParameter(
                f"identify option object_bound={self.object_bound} must be in (0, 1)"
            )
        if any(not (np.isfinite(p) and p >= 0) for p in self.object_priors):
            raise InvalidParameter(
                f"identify option object_priors={self.object_priors}: each must be ≥ 0"
            )
        if self.cv_folds < 2:
            raise InvalidParameter(f"identify option cv_folds={self.cv_folds} must be ≥ 2")


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
        objects: per object, which factors were kept and why (empty with fit_objects off).
        directions: the parameter combinations and whether the data determine them.
        intervals: parameter name -> (value, 95 % half-width) in the parameter's units
            (η_ee: SI; objects: "<id>.mass" etc. as factors of the start values).
        chi2_fit: sum of squared whitened residuals on the fitted throws (-2 log L + c).
        n_params: parameters free in the final fit (determined combinations).
        objective_start, objective_fit: the objective minimised (`cell.identify.objective`)
            at the start and at the result, under the final step's weights and widths.
        kept_start: the fit ended worse on it than the start, which is kept.
        chi2_by_object: id -> (throws, whitened squared residual a throw; 2 expected).
    """

    params: ModelParams
    iterations: int
    converged: bool
    rmse_start_m: float
    rmse_fit_m: float
    history: list[tuple[float, float, float]] = field(default_factory=list)
    n_throws: int = 0
    seconds: float = 0.0
    objects: list[ObjectChoice] = field(default_factory=list)
    directions: list[Direction] = field(default_factory=list)
    intervals: dict[str, tuple[float, float]] = field(default_factory=dict)
    chi2_fit: float = float("nan")
    n_params: int = 0
    objective_start: float = float("nan")
    objective_fit: float = float("nan")
    kept_start: bool = False
    chi2_by_object: dict[str, tuple[int, float]] = field(default_factory=dict)


def _rmse(res: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(res**2, axis=1))))


def _stage1(
    data: ThrowData,
    batch: ThrowBatch,
    ee: EndEffectorParams,
    anchor: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
) -> EndEffectorParams:
    """η_ee given η_o: bounded least squares with the chained push Jacobian."""
    fun, jac = stage1_problem(data, batch, ee, anchor, 1.0 / opt.prior_rel)
    z0 = np.clip(ee_to_vector(ee), bounds[0], bounds[1])
    return ee_from_vector(_solve_stage(1, fun, jac, z0, bounds, opt), ee)


def _solve_stage(
    stage: int,
    fun: Callable[[np.ndarray], np.ndarray],
    jac: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
) -> np.ndarray:
    """The bounded least-squares solution of one stage (trust-region reflective, the
    stage's evaluation budget and tolerances from `opt`), logged at debug level."""
    sol = least_squares(
        fun,
        x0,
        jac=jac,
        bounds=bounds,
        method="trf",
        max_nfev=opt.stage_nfev,
        x_scale=1.0,
        ftol=opt.stage_tol,
        xtol=opt.stage_tol,
    )
    log.debug("stage %d: %d evaluations, %d Jacobians, %s", stage, sol.nfev, sol.njev, sol.message)
    return np.asarray(sol.x)


def _stage2(
    data: ThrowData,
    ee: EndEffectorParams,
    factors: np.ndarray,
    opt: IdentifyOptions,
    prior_std: np.ndarray | None = None,
) -> np.ndarray:
    """All objects' factors given η_ee: one block-diagonal bounded least-squares solve.

    prior_std: 1 σ of each factor's prior (None: prior_rel for all); 0 holds a factor
    at 1 (the catalogue value).
    """
    _, k = data.factor_columns()
    std = np.full(k, opt.prior_rel) if prior_std is None else np.asarray(prior_std, float)
    free = std > 0
    x = np.where(free, factors, 1.0)
    if not free.any():
        return x
    w = np.where(free, 1.0 / np.where(free, std, 1.0), 0.0)
    fun, jac = stage2_problem(data, ee, w, 1 + opt.object_bound)
    rows = np.r_[np.ones(2 * len(data), bool), free]

    def f(xf: np.ndarray) -> np.ndarray:
        full = x.copy()
        full[free] = xf
        return fun(full)[rows]

    def j(xf: np.ndarray) -> np.ndarray:
        full = x.copy()
        full[free] = xf
        return jac(full)[rows][:, free]

    nf = int(free.sum())
    lo, hi = np.full(nf, 1 - opt.object_bound), np.full(nf, 1 + opt.object_bound)
    x[free] = _solve_stage(2, f, j, np.clip(x[free], lo, hi), (lo, hi), opt)
    return x


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
        prior: what the Gaussian prior is centred on (None = the start). η_o priors
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


@dataclass
class _State:
    """The fit in progress: η_ee, the factors, and the iteration record."""

    ee: EndEffectorParams
    factors: np.ndarray
    history: list[tuple[float, float, float]] = field(default_factory=list)
    converged: bool = False


def _alternate(
    data: ThrowData,
    st: _State,
    anchor: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
    prior_std: np.ndarray,
    progress: Callable[[int, float], None] | None,
) -> None:
    """Stage 1 and stage 2 in turn, the weights renewed each time, until nothing moves."""
    st.converged = False
    for _ in range(opt.max_iter):
        z_old, f_old = ee_to_vector(st.ee), st.factors.copy()
        batch = data.batch_with(data.objects_from_factors(st.factors))
        data.weigh(batch, st.ee, opt.noise)
        st.ee = _stage1(data, batch, st.ee, anchor, bounds, opt)
        r1 = _rmse(data.residual(batch, st.ee))
        if opt.fit_objects:
            st.factors = _stage2(data, st.ee, st.factors, opt, prior_std)
            batch = data.batch_with(data.objects_from_factors(st.factors))
        r2 = _rmse(data.residual(batch, st.ee))
        change = float(
            max(np.max(np.abs(ee_to_vector(st.ee) - z_old)), np.max(np.abs(st.factors - f_old)))
        )
        st.history.append((r1, r2, change))
        it = len(st.history)
        log.info("iteration %d: rmse %.4f m (stage 1 %.4f m), change %.2e", it, r2, r1, change)
        if progress is not None:
            progress(it, r2)
        if change < opt.tol:
            st.converged = True
            return


def _hold_step(
    data: ThrowData,
    st: _State,
    ana: Analysis,
    prior_std: np.ndarray,
    theta_prior: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
) -> None:
    """The truncated-SVD step: from the projected point, refit η_ee and the factors
    jointly with the undetermined combinations held at the prior (stiff rows on
    V_uᵀ D⁻¹ (θ − θ_prior)), so the determined ones take up the model's curvature."""
    n_ee = len(EE_NAMES)
    free = prior_std > 0
    d = prior_std[free]
    vu = np.array([v for v, det in zip(ana.vectors, ana.determined, strict=True) if not det])
    vu = vu.reshape(-1, d.size)
    hold = 1e3
    theta = np.r_[ana.z, ana.factors]
    lo = np.r_[bounds[0], np.full(theta.size - n_ee, 1 - opt.object_bound)][free]
    hi = np.r_[bounds[1], np.full(theta.size - n_ee, 1 + opt.object_bound)][free]

    def split(t: np.ndarray) -> tuple[EndEffectorParams, np.ndarray]:
        full = theta.copy()
        full[free] = t
        return ee_from_vector(full[:n_ee], st.ee), full[n_ee:]

    def fun(t: np.ndarray) -> np.ndarray:
        ee, x = split(t)
        res = data.wres(data.batch_with(data.objects_from_factors(x)), ee)
        dev = (t - theta_prior[free]) / d
        return np.concatenate([res.ravel(), dev, hold * (vu @ dev)])

    def jac(t: np.ndarray) -> np.ndarray:
        ee, x = split(t)
        j = joint_jacobian(data, ee, x)[:, free]
        return np.vstack([j, np.diag(1 / d), hold * vu / d[None, :]])

    t0 = np.clip(theta[free], lo, hi)
    sol = least_squares(
        fun, t0, jac=jac, bounds=(lo, hi), method="trf", max_nfev=opt.stage_nfev,
        x_scale=1.0, ftol=opt.stage_tol, xtol=opt.stage_tol,
    )  # fmt: skip
    st.ee, st.factors = split(sol.x)


def _select(
    data: ThrowData,
    st: _State,
    anchor: np.ndarray,
    bounds: tuple[np.ndarray, np.ndarray],
    opt: IdentifyOptions,
    progress: Callable[[int, float], None] | None,
) -> tuple[list[ObjectChoice], np.ndarray]:
    """Choose each object's prior width by cross-validation (η_ee as fitted so far),
    then fit again with those widths. Returns the choices and the per-factor prior σ."""
    from cell.identify.select import choose_object_priors, column_priors

    _, k = data.factor_columns()
    data.weigh(data.batch_with(data.objects_from_factors(st.factors)), st.ee, opt.noise)
    ee_cv, x_cv = st.ee, st.factors.copy()

    def solve(sub: ThrowData, p: np.ndarray) -> np.ndarray:
        # warm start at the all-throw fit (the prior, centred at 1, decides the optimum)
        return _stage2(sub, ee_cv, x_cv, opt, p)

    choices = choose_object_priors(
        data, st.ee, opt.object_priors, opt.cv_folds, solve, opt.prior_rel
    )
    std = column_priors(data, choices)
    st.factors = np.where(std > 0, st.factors, 1.0)
    _alternate(data, st, anchor, bounds, opt, std, progress)
    return choices, std


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
    bounds = ee_bounds(prior.ee)
    anchor = np.clip(ee_to_vector(prior.ee), bounds[0], bounds[1])
    _, k = data.factor_columns()
    rmse_start = _rmse(data.residual(data.batch, start.ee))
    st = _State(ee=start.ee, factors=np.ones(k))
    std = np.full(k, opt.prior_rel if opt.fit_objects else 0.0)
    _alternate(data, st, anchor, bounds, opt, std, progress)
    choices: list[ObjectChoice] = []
    if opt.fit_objects and opt.object_priors:
        choices, std = _select(data, st, anchor, bounds, opt, progress)
    # degenerate directions: hold them at the prior; intervals
    batch = data.batch_with(data.objects_from_factors(st.factors))
    data.weigh(batch, st.ee, opt.noise)
    names = parameter_names(data)
    jac = joint_jacobian(data, st.ee, st.factors)
    theta = np.r_[ee_to_vector(st.ee), st.factors]
    ee_std = np.full(len(EE_NAMES), opt.prior_rel)
    ana = analyse(
        jac,
        np.r_[ee_std, std],
        np.r_[ee_std, np.where(std > 0, std, opt.prior_rel)],
        theta,
        np.r_[anchor, np.ones(k)],
        names,
        opt.determined_ratio,
    )
    if not all(ana.determined):
        _hold_step(data, st, ana, np.r_[ee_std, std], np.r_[anchor, np.ones(k)], bounds, opt)
    st.ee, st.factors, cmp = keep_better(  # never worse on the objective than the start
        data, start.ee, st.ee, st.factors, anchor, opt.prior_rel, std
    )
    start_kept = cmp.start_better
    batch = data.batch_with(data.objects_from_factors(st.factors))
    res = data.residual(batch, st.ee)
    rmse_fit = _rmse(res)
    chi2 = float(np.sum(data.whitened(res) ** 2))
    objects: dict[str, ObjectParams] = data.objects_from_factors(st.factors)
    it = len(st.history)
    kept = sum(c.kept for c in choices)
    note = (
        f"identified by two-stage maximum-likelihood least squares (Algorithm 1, residuals "
        f"weighted by the documented landing noise) from {len(data)} throws of "
        f"{plural(len(objects), 'object')}: {plural(it, 'iteration')}, "
        f"{'converged' if st.converged else 'stopped at max_iter'}; landing RMSE on the fitted "
        f"throws {rmse_start:.4f} m -> {rmse_fit:.4f} m; identified: "
        + ", ".join(EE_NAMES)
        + (
            f" and the objects' mass and extents where cross-validation supports it "
            f"({len(choices) - kept} fitted, {kept} kept at their start values)"
            if choices
            else (" and each object's mass and extents" if opt.fit_objects else "")
        )
        + f"; {ana.n_determined} of {len(ana.directions)} parameter combinations determined, "
        "the others held at the prior"
        + ("; the fit ended worse on its objective than the start: the start kept" * start_kept)
    )
    return IdentifyResult(
        params=ModelParams(ee=st.ee, objects=objects, effects={}, note=note),
        iterations=it,
        converged=st.converged,
        rmse_start_m=rmse_start,
        rmse_fit_m=rmse_fit,
        history=st.history,
        n_throws=len(data),
        seconds=time.perf_counter() - t0,
        objects=choices,
        directions=ana.directions,
        intervals=intervals(names, ee_to_vector(st.ee), st.factors, ana),
        chi2_fit=chi2,
        n_params=ana.n_determined,
        objective_start=cmp.start,
        objective_fit=min(cmp.start, cmp.end),
        kept_start=start_kept,
        chi2_by_object=cmp.chi2_by_object,
    )
