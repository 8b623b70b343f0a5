"""The grip as a toppra path constraint (`grip_constraint`): the item's specific force and
couple at its centre of mass kept inside a polytope within the grip's bound."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from cell.robot.grip_hold import GripHold, _sphere_directions, item_motion
from cell.robot.model import Robot


def grip_constraint(robot: Robot, hold: GripHold, bound: float) -> Any:
    """The grip as a toppra path constraint: w = (f [m/s², ee_tcp], τ_x [N·m]) at the
    item's centre of mass, affine in q̈ and quadratic in q̇ as toppra's second-order
    constraints are, kept inside a polytope within m |f| / F + |τ_x| / T ≤ bound: for
    every direction n_k of `_sphere_directions` and sign σ,
    m (n_k·f) / (c F) + σ τ_x / T ≤ bound. Inner, so conservative: the couple the
    item's base adds when pressed onto the carriage is left out, and the force's share
    by the cover c (≈ 0.97). With no couple to count on (T = 0) the item must not be
    asked to turn at all, which no path does: toppra then finds no parameterisation.
    """
    import toppra.constraint as constraint

    coef = _coefficients(hold.mass_kg, hold.force_n, hold.torque_nm)
    g = np.full(len(coef), bound)

    def inv_dyn_many(qs: np.ndarray, dqs: np.ndarray, ddqs: np.ndarray) -> np.ndarray:
        f, alpha, _ = item_motion(robot, qs, dqs, ddqs, hold.offset_tcp_m)
        tau = -hold.lever_m * hold.mass_kg * f[:, 1] + hold.inertia_xx * alpha[:, 0]
        return np.c_[f, tau]

    def inv_dyn(q: np.ndarray, dq: np.ndarray, ddq: np.ndarray) -> np.ndarray:
        return inv_dyn_many(q[None], dq[None], ddq[None])[0]

    return _grip_constraint_class()(
        inv_dyn,
        lambda q: coef,
        lambda q: g,
        dof=robot.dof,
        discretization_scheme=constraint.DiscretizationType.Interpolation,
        inv_dyn_many=inv_dyn_many,
    )


@functools.lru_cache(maxsize=64)
def _coefficients(mass_kg: float, force_n: float, torque_nm: float) -> np.ndarray:
    """The polytope's rows (m n_k / (c F), σ / T) for every direction n_k of
    `_sphere_directions` and σ = +1, −1 in turn, shape (2 × 128, 4); read-only, shared by
    every carry of the same hold. Each entry is computed by the same operations, in the
    same order, as row by row (`np.r_` per direction and sign, as before 2026-11-29:
    3.4 ms a carry shaped by the grip), so the constraint is the same bit for bit
    (tests/test_grip_constraint_rows.py)."""
    dirs, cover = _sphere_directions()
    half = mass_kg * dirs / (cover * force_n)
    coef = np.empty((2 * len(dirs), 4))
    coef[:, :3] = np.repeat(half, 2, axis=0)
    coef[:, 3] = np.tile([1.0, -1.0], len(dirs))
    if torque_nm > 0.0:
        coef[:, 3] /= torque_nm
    else:
        coef[:, 3] *= 1e6  # [1/(N·m)]: no couple, no turn (a stiff stand-in for τ_x = 0)
    coef.setflags(write=False)
    return coef


@functools.cache
def _identity(n: int) -> np.ndarray:
    """The n × n identity, read-only (`GripConstraint.compute_constraint_params`)."""
    eye = np.eye(n)
    eye.setflags(write=False)
    return eye


class _TimesIdentity(np.ndarray):
    """F a, F b or F c of the grip constraint, a row per grid point, as toppra's seidel
    solver takes them with F the identity (`GripConstraint.compute_constraint_params`):
    its set-up multiplies each by Fᵀ (`a.dot(F.T)`), a dense product of (N + 1) × 512 by
    512 × 512, 5 ms of a carry's 15 ms shaped by the grip (tune layout 0: 274 carries,
    1.4 s). By the identity each entry is itself plus zeros, which BLAS sums from +0.0:
    the product is the array with -0.0 made +0.0, `a + 0.0`, bit for bit
    (tests/test_grip_constraint_rows.py: the same trajectories as toppra's own set-up).
    A row with a NaN or an infinity, or any other matrix, is multiplied as before."""

    def dot(self, b: Any, out: Any = None) -> Any:
        a = self.view(np.ndarray)
        if out is not None:
            return a.dot(b, out)
        if a.ndim == 2 and getattr(b, "base", None) is _identity(a.shape[1]):
            if b.shape == (a.shape[1], a.shape[1]) and np.isfinite(a).all():
                return a + 0.0
        return a.dot(b)


@functools.cache
def _grip_constraint_class() -> type:
    """toppra's SecondOrderConstraint with its coefficients computed over all grid points
    at once (`inv_dyn_many`), where toppra calls the inverse dynamics once a grid point
    (three times over): the same a, b, c (tests/test_carry.py), a third of the time of a
    carry's planning shaped by the grip before (toppra 0.6's
    `compute_constraint_params`, whose discretisation this keeps).

    Handed to toppra's seidel solver already multiplied out (`compute_constraint_params`,
    `identical`): the solver's set-up copied a constraint whose F differs by grid point
    into its arrays one number at a time through Python, 256 rows × 2 × 3 a grid point,
    20 ms of a carry's 49 ms shaped by the grip; given F a, F b, F c per grid point
    (`np.dot`, as the solver computes them) and F the identity, which it multiplies
    through exactly, it fills the same arrays, bit for bit, in 5 ms
    (tests/test_grip_constraint_rows.py: the same trajectories); with that product by
    the identity taken as what it is (`_TimesIdentity`) and F_i x_i by one stacked
    matmul, a carry shaped by the grip took 7.0 ms where it took 12.9 (tune layout 0's
    first 60, one BLAS thread)."""
    import toppra.constraint as constraint
    from toppra.constraint.linear_constraint import canlinear_colloc_to_interpolate

    class GripConstraint(constraint.SecondOrderConstraint):  # type: ignore[misc]
        def __init__(self, *args: Any, inv_dyn_many: Any, **kw: Any) -> None:
            super().__init__(*args, **kw)
            self.inv_dyn_many = inv_dyn_many
            self.identical = True  # F: the identity (`compute_constraint_params`)

        def colloc_params(self, path: Any, gridpoints: np.ndarray) -> Any:
            """toppra's own (a, b, c, F, g, ubound, xbound) of the interpolation scheme,
            F and g a grid point each (SecondOrderConstraint's)."""
            if path.dof != self.dof:
                raise ValueError(f"constraint dof {self.dof} is not the path's {path.dof}")
            p_vec = path(gridpoints)
            ps_vec = path(gridpoints, 1)
            pss_vec = path(gridpoints, 2)
            zeros = np.zeros_like(p_vec)
            f_vec = np.array(list(map(self.constraint_F, p_vec)))
            g_vec = np.array(list(map(self.constraint_g, p_vec)))
            c_vec = self.inv_dyn_many(p_vec, zeros, zeros)
            a_vec = self.inv_dyn_many(p_vec, zeros, ps_vec) - c_vec
            b_vec = self.inv_dyn_many(p_vec, ps_vec, pss_vec) - c_vec
            return canlinear_colloc_to_interpolate(
                a_vec, b_vec, c_vec, f_vec, g_vec, None, None, gridpoints
            )

        def compute_constraint_params(self, path: Any, gridpoints: np.ndarray, *_: Any) -> Any:
            """`colloc_params` multiplied out a grid point at a time, F_i a_i, F_i b_i,
            F_i c_i (each `np.dot`, as the seidel solver computes them for a constraint
            not `identical`), with F the identity and g the same at every grid point (the
            bound), as toppra takes an `identical` constraint."""
            a, b, c, f, g, ubound, xbound = self.colloc_params(path, gridpoints)
            if not np.all(g == g[0]):
                raise ValueError("the grip constraint's bound differs along the path")
            # F_i x_i for every grid point i by one stacked matmul: BLAS's gemv a grid
            # point, as np.dot(F_i, x_i) was called in a loop, bit for bit
            fa, fb, fc = (np.matmul(f, x[:, :, None])[:, :, 0] for x in (a, b, c))
            rows = (x.view(_TimesIdentity) for x in (fa, fb, fc))
            return *rows, _identity(fa.shape[1]), g[0], ubound, xbound

    return GripConstraint
