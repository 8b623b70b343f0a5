"""The throw NLP of thesis eq. 4.1 in CasADi, solved with IPOPT.

Decision variables: σ (10, SIGMA_COLUMNS order) and the flight time T after
the push [s]. Eq. 4.1 minimises the landing miss ‖p_m(σ) - p_g‖² subject to
the object dynamics (eq. 4.4) and the bounds (eq. 4.5). The miss of a
reachable target has the minimum zero, reached by a whole family of σ; this
NLP imposes that minimum as constraints and spends the remaining freedom on
the secondary objective:

    min   E(L_s) / E_max + W_POSE ‖p0 - p_ref‖² / (0.1 m)²
    s.t.  x(T) = x_g,  y(T) = y_g,  z(T) = z_g (the landing plane),
          ż(T) ≤ -V_DESCENT (the crossing is the descending one),
          σ_L ≤ σ ≤ σ_U,  T_MIN ≤ T ≤ T_MAX,

with E the stored band energy [J] (E_max its value at the smallest stroke):
least stored energy first, and among equally low energies the release point
nearest the reference p_ref (the current grip centre, else the fast path's
nominal release point). The dynamics are the fixed-step RK4 of
`casadi_model`. IPOPT's status is not trusted (it can report success for an
unreachable target): the caller judges every result with
`cell.model.predict_landing`.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.band import band_state
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import drag_constant
from cell.optimize.casadi_model import N_FLIGHT_STEPS, symbolic_throw

__all__ = ["NlpResult", "W_POSE", "build_nlp", "solve_nlp"]

log = logging.getLogger(__name__)

W_POSE = 1e-5  # weight of the release-point term against the normalised energy
V_DESCENT = 1e-3  # [m/s] the crossing's vertical velocity is at most -V_DESCENT
T_MIN = 0.01  # [s] shortest flight after the push
T_MAX = 10.0  # [s] longest flight after the push
_POSE_SCALE = 0.1  # [m]


@dataclass(frozen=True)
class NlpResult:
    """What IPOPT returned (not yet judged by the NumPy model).

    Attributes:
        sigma: release state, shape (10,), SIGMA_COLUMNS order.
        t_flight: flight time after the push [s].
        status: IPOPT's return status text.
        success: IPOPT's own success flag (not to be trusted alone).
        iterations: IPOPT iterations.
    """

    sigma: np.ndarray
    t_flight: float
    status: str
    success: bool
    iterations: int


@functools.lru_cache(maxsize=8)
def build_nlp(ee: EndEffectorParams, n_steps: int = N_FLIGHT_STEPS) -> Any:
    """The IPOPT solver of the throw NLP, built once per end-effector.

    Parameters of the solver (p): width [m], mass [kg], k_drag [1/m], target
    x, y, z [m, W], reference release point x, y, z [m, W], E_max [J].
    """
    import casadi as ca

    w = ca.SX.sym("w", 11)
    p = ca.SX.sym("p", 10)
    sigma, t = w[0:10], w[10]
    th = symbolic_throw(sigma, t, p[0], p[1], p[2], ee, n_steps)
    d_ref = sigma[0:3] - p[6:9]
    objective = th.energy / p[9] + W_POSE * ca.dot(d_ref, d_ref) / _POSE_SCALE**2
    g = ca.vertcat(
        th.position[0] - p[3], th.position[1] - p[4], th.position[2] - p[5], th.velocity[2]
    )
    opts: dict[str, Any] = {
        "expand": True,
        "print_time": False,
        "ipopt.print_level": 0,
        "ipopt.sb": "yes",
        # the NumPy model polishes the landing afterwards: 1e-8 is ample here
        "ipopt.tol": 1e-8,
        "ipopt.constr_viol_tol": 1e-8,
        "ipopt.mu_strategy": "adaptive",
        "ipopt.max_iter": 200,
    }
    return ca.nlpsol("throw_nlp", "ipopt", {"x": w, "p": p, "f": objective, "g": g}, opts)


def solve_nlp(
    obj: ObjectParams,
    target: np.ndarray,
    ee: EndEffectorParams,
    lower: np.ndarray,
    upper: np.ndarray,
    guess: np.ndarray,
    t_guess: float,
    reference: np.ndarray,
) -> NlpResult:
    """Solve the throw NLP for one object and target.

    Args:
        obj: the object.
        target: goal (x, y, z) [m, W]; z is the landing plane's height.
        ee: end-effector parameters.
        lower: σ_L, shape (10,).
        upper: σ_U, shape (10,).
        guess: initial σ, shape (10,) (moved inside the bounds).
        t_guess: initial flight time after the push [s].
        reference: the release point the pose term pulls toward [m, W], shape (3,).

    Returns:
        IPOPT's answer, to be judged by the caller.
    """
    solver = build_nlp(ee)
    k = float(drag_constant(np.array([obj.code]), np.array([obj.mass]), np.array([obj.size]))[0])
    e_max = float(band_state(lower[9], obj.width, ee).energy)
    params = np.r_[obj.width, obj.mass, k, np.asarray(target, float), reference, max(e_max, 1e-9)]
    x0 = np.r_[np.clip(guess, lower, upper), np.clip(t_guess, T_MIN, T_MAX)]
    sol = solver(
        x0=x0,
        p=params,
        lbx=np.r_[lower, T_MIN],
        ubx=np.r_[upper, T_MAX],
        lbg=[0.0, 0.0, 0.0, -np.inf],
        ubg=[0.0, 0.0, 0.0, -V_DESCENT],
    )
    stats = solver.stats()
    x = np.asarray(sol["x"], float).ravel()
    log.debug("throw NLP: %s in %d iterations", stats["return_status"], stats["iter_count"])
    return NlpResult(
        sigma=np.clip(x[:10], lower, upper),
        t_flight=float(x[10]),
        status=str(stats["return_status"]),
        success=bool(stats["success"]),
        iterations=int(stats["iter_count"]),
    )
