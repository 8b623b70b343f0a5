"""The stage problems of identification: residual and Jacobian functions.

Stage 1 (η_ee's stage-1 vector) chains the analytic ∂f_o/∂θ with one finite difference
in every throw's push at once plus one in Δt; stage 2 (all objects' factors) perturbs
factor slot s of every object at once (the Jacobian is block diagonal). The joint
Jacobian of both blocks is what the degenerate-direction analysis reads.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Any

import numpy as np

from cell.identify.problem import (
    ThrowData,
    ee_from_vector,
    ee_to_vector,
    push_jacobian,
)
from cell.model.band import push_force
from cell.model.flight_batch import together
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch

__all__ = ["Problem", "joint_jacobian", "stage1_problem", "stage2_problem"]

Problem = tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]


def stage1_problem(
    data: ThrowData, batch: ThrowBatch, ee: EndEffectorParams, anchor: np.ndarray, w: float
) -> Problem:
    """Stage-1 residual and Jacobian functions of the stage-1 vector z.

    Residuals: predicted minus observed landings (x, y per throw) in units of their
    noise σ (`ThrowData.wres`; metres when no weights are set), then the prior rows
    w · (z − anchor). The Jacobian chains the analytic ∂f_o/∂θ with
    one finite difference in the push of every throw at once, plus one in Δt.
    """
    n = len(data)
    cache: dict[str, Any] = {}

    def fun(z: np.ndarray) -> np.ndarray:
        e = ee_from_vector(z, ee)
        f_o = np.asarray(push_force(batch.stroke, batch.size[:, 0], e))
        res = data.wres(batch, e, push=f_o)
        cache.update(z=z.copy(), e=e, f_o=f_o, res=res)
        return np.concatenate([res.ravel(), w * (z - anchor)])

    def jac(z: np.ndarray) -> np.ndarray:
        if cache.get("z") is None or not np.array_equal(cache["z"], z):
            fun(z)
        e: EndEffectorParams = cache["e"]
        f_o: np.ndarray = cache["f_o"]
        res: np.ndarray = cache["res"]
        h_f = 1e-4 * np.maximum(np.abs(f_o), 1.0)  # [N]
        h_dt = 1e-4 * z[7]
        e_dt = ee_from_vector(z + np.eye(8)[7] * h_dt, ee)
        # the two perturbed predictions side by side (their flights as one batch)
        r_push, r_dt = together(
            [
                partial(data.wres, batch, e, push=f_o + h_f),
                partial(data.wres, batch, e_dt, push=f_o),
            ]
        )
        d_push = (r_push - res) / h_f[:, None]
        j = d_push[:, :, None] * push_jacobian(batch, e)[:, None, :]
        j[:, :, 7] = (r_dt - res) / h_dt
        return np.vstack([j.reshape(2 * n, 8), w * np.eye(8)])

    return fun, jac


def stage2_problem(
    data: ThrowData, ee: EndEffectorParams, w: float | np.ndarray, upper: float
) -> Problem:
    """Stage-2 residual and Jacobian functions of the vector of all objects' factors.

    Residuals: predicted minus observed landings (`ThrowData.wres`), then
    w · (factors − 1) (w a number or one per factor). The
    Jacobian is block diagonal; slot s of every object is perturbed at once (a
    throw sees only its own object's factors), backwards where a factor is within
    a step of `upper`.
    """
    col, k = data.factor_columns()
    n = len(data)
    nslot = int((col >= 0).sum(axis=1).max())
    cache: dict[str, Any] = {}

    def fun(x: np.ndarray) -> np.ndarray:
        res = data.wres(data.batch_with(data.objects_from_factors(x)), ee)
        cache.update(x=x.copy(), res=res)
        return np.concatenate([res.ravel(), w * (x - 1.0)])

    def jac(x: np.ndarray) -> np.ndarray:
        if cache.get("x") is None or not np.array_equal(cache["x"], x):
            fun(x)
        res: np.ndarray = cache["res"]
        j = np.zeros((n, 2, k))
        h = 1e-5
        rows = np.arange(n)
        steps = []
        for s in range(nslot):
            cols = col[:, s]
            has = cols >= 0
            step = np.zeros(k)
            # step backwards where a factor sits at its upper bound
            sign = np.where(x[cols[has]] + h > upper, -1.0, 1.0)
            step[cols[has]] = h * sign
            steps.append(step)
        # the slots' perturbed predictions side by side (their flights as one batch)
        got = together(
            [partial(_wres_at, data, ee, x + step) for step in steps]  # fmt: skip
        )
        for s, (step, r2) in enumerate(zip(steps, got, strict=True)):
            cols = col[:, s]
            c_row = cols[data.obj]
            ok = c_row >= 0
            d = (r2 - res) / np.where(ok, step[np.maximum(c_row, 0)], 1.0)[:, None]
            j[rows[ok], :, c_row[ok]] = d[ok]
        return np.vstack([j.reshape(2 * n, k), np.diag(np.broadcast_to(w, (k,)).astype(float))])

    return fun, jac


def _wres_at(data: ThrowData, ee: EndEffectorParams, factors: np.ndarray) -> np.ndarray:
    """The whitened residuals (n, 2) with the objects' factors `factors`."""
    return data.wres(data.batch_with(data.objects_from_factors(factors)), ee)


def joint_jacobian(data: ThrowData, ee: EndEffectorParams, factors: np.ndarray) -> np.ndarray:
    """Jacobian of the whitened landing residuals in η_ee's stage-1 vector and all
    factors together, shape (2n, 8 + k)."""
    batch = data.batch_with(data.objects_from_factors(factors))
    z = ee_to_vector(ee)
    _, jac1 = stage1_problem(data, batch, ee, z, 0.0)
    _, jac2 = stage2_problem(data, ee, 0.0, np.inf)
    n2 = 2 * len(data)
    return np.hstack([jac1(z)[:n2], jac2(factors)[:n2]])
