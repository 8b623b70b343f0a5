"""Band kinematics and forces (thesis eqs. 3.1-3.9, MODEL.md "Launch").

Every function takes stroke L_s [m] and grip width a [m] as scalars or arrays
(broadcast together) and an `Ops` back-end, so that the NumPy model and the
CasADi planner evaluate one formula source.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.model.ops import NUMPY, Ops
from cell.model.params import EndEffectorParams

__all__ = [
    "BandState",
    "band_state",
    "band_stretch",
    "band_force",
    "band_angle",
    "push_force",
    "grip_force",
    "stored_energy",
]


def band_stretch(stroke: Any, width: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """ΔL = L - L0, the band's stretch [m] (eqs. 3.1, 3.2).

    Args:
        stroke: stroke length L_s [m].
        width: grip width a = object size_x [m].
        ee: end-effector parameters.
        ops: array back-end.
    """
    l2 = ops.sqrt(((width - ee.d) / 2) ** 2 + (ee.L_t - stroke) ** 2)
    length = ee.l1 + ee.r_r * ee.phi + ee.d / 2 + l2
    return length - ee.L0


def band_force(stretch: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """f_e, the band's axial force [N] (eq. 3.9); zero for a slack band, never negative."""
    f = ((ee.Ke3 * stretch + ee.Ke2) * stretch + ee.Ke1) * stretch + ee.C
    return ops.where(stretch > 0, ops.fmax(f, 0.0), 0.0 * stretch)


def band_angle(stroke: Any, width: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """α = atan2(a - d, 2 (L_t - L_s)) [rad], the band's angle to the throw axis."""
    return ops.atan2(width - ee.d, 2 * (ee.L_t - stroke))


def push_force(stroke: Any, width: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """f_o = 2 f_e cos α [N], the push along the throw axis u."""
    f_e = band_force(band_stretch(stroke, width, ee, ops), ee, ops)
    return 2 * f_e * ops.cos(band_angle(stroke, width, ee, ops))


def grip_force(stroke: Any, width: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """f_g = f_e sin α [N], the grip force (eq. 3.6)."""
    f_e = band_force(band_stretch(stroke, width, ee, ops), ee, ops)
    return f_e * ops.sin(band_angle(stroke, width, ee, ops))


def stored_energy(stretch: Any, ee: EndEffectorParams, ops: Ops = NUMPY) -> Any:
    """V_e = ∫_0^ΔL f_e dΔL [J] of one band half (eq. 3.4), zero for a slack band.

    The cubic law is integrated in closed form. Where C < 0 makes the force
    clamp at zero near ΔL = 0 the clamped part contributes nothing, which the
    closed form would miss; that case is integrated from the force's root.
    """
    s = ops.fmax(stretch, 0.0)

    def prim(x: Any) -> Any:
        return ((ee.Ke3 / 4 * x + ee.Ke2 / 3) * x + ee.Ke1 / 2) * x * x + ee.C * x

    if ee.C >= 0:
        return prim(s)
    roots = np.roots([ee.Ke3, ee.Ke2, ee.Ke1, ee.C])
    real = [float(r.real) for r in roots if abs(r.imag) < 1e-12 and r.real > 0]
    x0 = min(real) if real else 0.0
    return ops.where(s > x0, prim(s) - prim(x0), 0.0 * s)


@dataclass(frozen=True)
class BandState:
    """The band at one stroke, for one or many throws (arrays broadcast).

    Attributes:
        stretch: ΔL [m].
        force: f_e [N].
        angle: α [rad].
        push: f_o [N] along the throw axis.
        grip: f_g [N].
        energy: stored energy of both band halves [J].
    """

    stretch: np.ndarray
    force: np.ndarray
    angle: np.ndarray
    push: np.ndarray
    grip: np.ndarray
    energy: np.ndarray


def band_state(stroke: Any, width: Any, ee: EndEffectorParams) -> BandState:
    """Every band quantity at once, in NumPy."""
    stretch = np.asarray(band_stretch(np.asarray(stroke, float), np.asarray(width, float), ee))
    force = np.asarray(band_force(stretch, ee))
    angle = np.asarray(band_angle(np.asarray(stroke, float), np.asarray(width, float), ee))
    return BandState(
        stretch=stretch,
        force=force,
        angle=angle,
        push=2 * force * np.cos(angle),
        grip=force * np.sin(angle),
        energy=2 * np.asarray(stored_energy(stretch, ee)),
    )
