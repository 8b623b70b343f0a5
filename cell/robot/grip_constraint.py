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

    dirs, cover = _sphere_directions()
    rows = [np.r_[hold.mass_kg * d / (cover * hold.force_n), sg] for d in dirs for sg in (1, -1)]
    coef = np.array(rows)
    if hold.torque_nm > 0.0:
        coef[:, 3] /= hold.torque_nm
    else:
        coef[:, 3] *= 1e6  # [1/(N·m)]: no couple, no turn (a stiff stand-in for τ_x = 0)
    g = np.full(len(rows), bound)

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


@functools.cache
def _grip_constraint_class() -> type:
    """toppra's SecondOrderConstraint with its coefficients computed over all grid points
    at once (`inv_dyn_many`), where toppra calls the inverse dynamics once a grid point
    (three times over): the same a, b, c (tests/test_carry.py), a third of the time of a
    carry's planning shaped by the grip before (toppra 0.6's
    `compute_constraint_params`, whose discretisation this keeps)."""
    import toppra.constraint as constraint
    from toppra.constraint.linear_constraint import canlinear_colloc_to_interpolate

    class GripConstraint(constraint.SecondOrderConstraint):  # type: ignore[misc]
        def __init__(self, *args: Any, inv_dyn_many: Any, **kw: Any) -> None:
            super().__init__(*args, **kw)
            self.inv_dyn_many = inv_dyn_many

        def compute_constraint_params(self, path: Any, gridpoints: np.ndarray) -> Any:
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

    return GripConstraint
