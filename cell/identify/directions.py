"""Which combinations of parameters the landings determine, and the fit's intervals.

At the solution, J is the Jacobian of the whitened landing residuals (units of the
documented noise σ) with respect to all free parameters together: η_ee's stage-1
vector and every object's factors. With D the diagonal of the parameters' prior σ,
the SVD  J D = U S Vᵀ  gives the combinations v_i (columns of V, in units of each
parameter's prior σ) and s_i, how many times tighter the data pin v_i than the
prior does. A combination with s_i ≥ `determined_ratio` is determined; the others
(the data know them no better than the prior: push time against stiffness and
the objects' masses, say) are held at the prior by the truncated-SVD step

    θ ← θ_prior + D V_d V_dᵀ D⁻¹ (θ − θ_prior)

(V_d the determined columns), which moves the fit only along directions the
landings barely see. The 95 % intervals come from the MAP covariance
D V (S² + I)⁻¹ Vᵀ D.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.identify.problem import EE_NAMES, EE_SCALE, ThrowData, factor_names

__all__ = ["Analysis", "Direction", "analyse", "parameter_names"]

Z95 = 1.959964  # two-sided 95 % of a Gaussian


@dataclass(frozen=True)
class Direction:
    """One combination of parameters.

    Attributes:
        strength: s, the prior's σ over the data's σ along it (≥ ratio: determined).
        determined: the data pin it tighter than the determined_ratio demands.
        components: (parameter, coefficient in units of its prior σ), largest first,
            those with |coefficient| ≥ 0.2 (at most five).
    """

    strength: float
    determined: bool
    components: list[tuple[str, float]]

    def text(self) -> str:
        """The combination and its strength, for a person."""
        terms = " ".join(f"{c:+.2f} {name}" for name, c in self.components)
        verdict = "determined" if self.determined else "held at the prior"
        return f"{terms}  (data {self.strength:.3g}x tighter than the prior: {verdict})"

    def as_dict(self) -> dict[str, Any]:
        """Plain numbers for JSON."""
        return {
            "strength": self.strength,
            "determined": self.determined,
            "components": {name: c for name, c in self.components},
        }


@dataclass(frozen=True)
class Analysis:
    """The directions at a solution, its projection and its intervals.

    Attributes:
        directions: every combination, strongest first.
        z, factors: the parameters with the undetermined combinations at the prior.
        std_z, std_factors: 1 σ of each parameter (stage-1 vector units; factors).
        vectors: each direction's v_i over the free parameters (prior-σ units), rows.
        determined: each direction's verdict, in the same order.
    """

    directions: list[Direction]
    z: np.ndarray
    factors: np.ndarray
    std_z: np.ndarray
    std_factors: np.ndarray
    vectors: np.ndarray
    determined: list[bool]

    @property
    def n_determined(self) -> int:
        """Determined combinations (the parameter count of the fit)."""
        return sum(d.determined for d in self.directions)


def parameter_names(data: ThrowData) -> list[str]:
    """η_ee's identifiable names, then "<object>.<factor>" in stage-2 vector order."""
    names = list(EE_NAMES)
    for oid in data.object_ids:
        names += [f"{oid}.{f}" for f in factor_names(data.start_objects[oid].shape)]
    return names


def _components(v: np.ndarray, names: list[str]) -> list[tuple[str, float]]:
    v = v * np.sign(v[np.argmax(np.abs(v))])
    order = np.argsort(-np.abs(v))
    return [(names[i], float(v[i])) for i in order[:5] if abs(v[i]) >= 0.2]


def _svd(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Singular values (descending) and right singular vectors (rows) of a, all of them
    (also when a has fewer rows than columns), from the eigenpairs of aᵀa."""
    ev, vec = np.linalg.eigh(a.T @ a)
    order = np.argsort(-ev)
    return np.sqrt(np.maximum(ev[order], 0.0)), vec[:, order].T


def analyse(
    jac: np.ndarray,
    prior_std: np.ndarray,
    interval_std: np.ndarray,
    theta: np.ndarray,
    theta_prior: np.ndarray,
    names: list[str],
    ratio: float,
) -> Analysis:
    """Classify the combinations at a solution, hold the weak ones, and give intervals.

    Args:
        jac: whitened landing residuals' Jacobian, shape (2n, 8 + k), columns as
            `parameter_names`.
        prior_std: each parameter's prior σ in the fit (0: held fixed, e.g. an object
            kept at the catalogue).
        interval_std: the prior σ the intervals use (fixed parameters: the width they
            would have had), same shape.
        theta, theta_prior: the solution and the prior, stage-1 vector then factors.
        names: parameter names.
        ratio: the determined_ratio.
    """
    free = prior_std > 0
    d = prior_std[free]
    s_full, vt = _svd(jac[:, free] * d[None, :])
    det = s_full >= ratio
    free_names = [n for n, f in zip(names, free, strict=True) if f]
    directions = [
        Direction(float(s_full[i]), bool(det[i]), _components(vt[i], free_names))
        for i in range(vt.shape[0])
    ]
    delta = (theta - theta_prior)[free] / d
    vd = vt[det].T
    kept = vd @ (vd.T @ delta)
    out = theta.copy()
    out[free] = theta_prior[free] + d * kept
    # intervals: MAP covariance with every parameter at its interval prior
    di = interval_std
    m = di > 0
    s2, vt2 = _svd(jac[:, m] * di[m][None, :])
    var = np.zeros(theta.size)
    var[m] = di[m] ** 2 * np.sum(vt2**2 / (s2**2 + 1.0)[:, None], axis=0)
    std = np.sqrt(var)
    n_ee = len(EE_NAMES)
    return Analysis(
        directions, out[:n_ee], out[n_ee:], std[:n_ee], std[n_ee:], vt, [bool(x) for x in det]
    )


def intervals(
    names: list[str], z: np.ndarray, factors: np.ndarray, analysis: Analysis
) -> dict[str, tuple[float, float]]:
    """name -> (value, 95 % half-width): η_ee in SI units, objects as factors."""
    vals = np.r_[z * EE_SCALE, factors]
    half = Z95 * np.r_[analysis.std_z * EE_SCALE, analysis.std_factors]
    return {n: (float(v), float(h)) for n, v, h in zip(names, vals, half, strict=True)}
