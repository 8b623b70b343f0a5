"""The flight effects' callback (`cell.model.flight3d.Accel`): the air velocity (a wind, a
rotor's downwash) and the extra acceleration (a spin's lift, a drag factor) at each
integrated row, from the effects' parameters (each a scalar, or one value per throw) and
per-throw arrays (`cell.model.effects_apply.flight_accel` makes them).

Callbacks of one kind (the same effects present) can be stacked into one over their rows
put end to end (`stack_accels`): each row reads its own values, so each gives its rows
what its own callback gives, bit for bit (a scalar parameter given to every row of its
throws is that scalar to each of them). `cell.model.flight_batch` integrates stacked
flights with them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from cell.model.effects import DOWNWASH_EDGE_M, JET_SPREAD
from cell.model.flight3d import Rows, column_fraction

__all__ = ["AirKind", "make_accel", "stack_accels"]


class AirKind(NamedTuple):
    """Which flight effects a callback has (a downwash's decay and jet are its laws)."""

    wind: bool
    downwash: bool
    decay: bool
    jet: bool
    spin: bool
    drag: bool


def _norm(x: np.ndarray) -> np.ndarray:
    """|x| of each row of x (m, 3): `np.linalg.norm(x, axis=1)`'s arithmetic ((x² + y²) + z²),
    without its per-call checks, from x's columns (contiguous in the integrator's
    column-major states): the squares in one call, summed column by column."""
    sq = x * x
    return np.sqrt((sq[:, 0] + sq[:, 1]) + sq[:, 2])


def make_accel(kind: AirKind, par: dict[str, Any], per_throw: dict[str, np.ndarray], n: int) -> Any:
    """The callback of the flight effects of `kind` over n throws: `par` the parameters
    (scalars; the air velocity "w" (3,)), `per_throw` the arrays of one value per throw
    (n,) (the air velocity (n, 3)), read at the integrated rows. Its `stack` attribute
    holds what `stack_accels` reads."""
    dw, decay, jet = kind.downwash, kind.decay, kind.jet
    rows = Rows(per_throw)
    # made once per set of rows (`Rows`' rule: the integrator hands the same idx object
    # while its rows stay the same): the parameters at those rows, and, without a
    # downwash (which varies along the path), the air velocity, the same at every stage
    held: dict[str, Any] = {"idx": None}
    # no wind and no downwash: the air is still (the nominal drag's and the spin's and drag
    # factor's relative velocity is v itself)
    still = not kind.wind and not dw

    def accel(p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[Any, Any]:
        if idx is not held["idx"]:
            held["idx"], held["r"], held["w"] = idx, {**par, **rows(idx)}, None
        r = held["r"]
        w = held["w"]  # None while the air is still
        if w is None and not still:
            w = np.empty_like(p)
            w[:] = r["w"]
            if not dw:  # never written below: handed out again at the next stage
                held["w"] = w
        if dw:
            rho = np.hypot(p[:, 0] - r["cx"], p[:, 1] - r["cy"])
            if jet:
                depth = np.maximum(r["release_z"] - p[:, 2], 0.0)
                width = r["radius"] + JET_SPREAD * depth
                inside = np.exp(-((rho / width) ** 2)) * (r["radius"] / width)
                inside = np.where(p[:, 2] < r["release_z"], inside, 0.0)
            else:
                inside = column_fraction(rho, r["radius"], DOWNWASH_EDGE_M)
            if decay:
                depth = np.maximum(r["release_z"] - p[:, 2], 0.0)
                inside = inside * np.exp(-depth / r["depth"])
            w[:, 2] -= r["w_dw"] * inside
        if not kind.spin and not kind.drag:
            return w, None
        rel = v if still else v - w  # v − 0 is v to the bit
        speed = _norm(rel)
        extra = None
        if kind.spin:
            speed_sp = np.maximum(speed, 1e-9)
            # normal to v in its vertical plane, pointing up for backspin
            nz = 1.0 - (rel[:, 2] / speed_sp) ** 2
            n_v = -rel * (rel[:, 2] / speed_sp**2)[:, None]
            n_v[:, 2] += 1.0
            n_v /= np.sqrt(np.maximum(nz, 1e-12))[:, None]
            s_ratio = r["spin"] * r["size_radius"] / speed_sp
            c_l = r["lift_max"] * np.tanh(s_ratio / r["lift_max"])
            extra = (r["kl"] * c_l * speed_sp**2)[:, None] * n_v
        if kind.drag:
            drag = (r["neg_k_extra"] * speed)[:, None] * rel
            extra = drag if extra is None else extra + drag
        return w, extra

    # only a downwash's column reads where the object is (`flight3d._rk4`)
    accel.reads_position = dw  # type: ignore[attr-defined]
    accel.stack = (kind, par, per_throw, n)  # type: ignore[attr-defined]
    return accel


def _rows_of(stack: tuple, key: str) -> np.ndarray:
    """One callback's value of `key` at each of its throws: its per-throw array, or its
    parameter given to every throw."""
    _, par, per_throw, n = stack
    if key in per_throw:
        return np.asarray(per_throw[key])
    return np.broadcast_to(np.asarray(par[key], float), (n, 3) if key == "w" else (n,))


def stack_accels(accels: Sequence[Any]) -> Any:
    """One callback over the throws of `accels` (callbacks of one kind from `make_accel`)
    put end to end, each row with its own callback's values."""
    stacks = [a.stack for a in accels]
    kind = stacks[0][0]
    keys = dict.fromkeys(k for s in stacks for k in (*s[1], *s[2]))
    per = {k: np.concatenate([_rows_of(s, k) for s in stacks]) for k in keys}
    return make_accel(kind, {}, per, sum(s[3] for s in stacks))
