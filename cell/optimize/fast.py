"""The fast inverse: a validated table of reach against stroke, height and elevation.

With a fixed base the throw starts at rest, gravity is vertical and drag acts
along the velocity, so the whole flight stays in the vertical plane through
the release point p0 along the azimuth. The landing point is therefore
p0 + R (cos a, sin a) on the landing plane, where the reach R [m] depends only
on the object, the stroke L_s, the elevation e and the drop h = z0 - land_z
[m] (the dynamics do not depend on absolute height). R falls strictly with
L_s (the band is stretched less; f_o falls).

`ReachTable` holds R on a grid (elevation × drop × stroke) computed once per
object with `cell.model.predict_landing`, checks that R falls with L_s on
every row, and measures its own interpolation error against `predict_landing`
at every cell's centre; a cell whose error exceeds TABLE_TOL is never used
(near-zero drops at low elevations, where R ~ √h is not smooth). A query
interpolates R over the drop with a cubic and inverts the cubic in stroke for
every candidate elevation at once: about 0.1 ms per target.
"""

from __future__ import annotations

import functools
import logging
from dataclasses import dataclass

import numpy as np

from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, predict_landing

__all__ = ["ReachTable", "FastSolution", "reach_table", "N_STROKES", "DROPS"]

log = logging.getLogger(__name__)

N_STROKES = 33  # stroke grid points over the stroke range
DROPS = np.round(np.arange(-0.4, 1.6001, 0.1), 10)  # [m] drop h = z0 - land_z grid


def _lagrange4(t: np.ndarray) -> np.ndarray:
    """Cubic Lagrange weights for nodes at -1, 0, 1, 2 evaluated at t, shape (..., 4)."""
    t = np.asarray(t, float)
    return np.stack(
        [
            -t * (t - 1) * (t - 2) / 6,
            (t + 1) * (t - 1) * (t - 2) / 2,
            -(t + 1) * t * (t - 2) / 2,
            (t + 1) * t * (t - 1) / 6,
        ],
        axis=-1,
    )


# Power-basis coefficients (t³, t², t, 1) of the cubic through nodes at t = -1, 0, 1, 2:
# coefficients = node values @ _POWER.
_POWER = np.array(
    [
        [-1 / 6, 1 / 2, -1 / 3, 0.0],
        [1 / 2, -1.0, -1 / 2, 1.0],
        [-1 / 2, 1 / 2, 1.0, 0.0],
        [1 / 6, 0.0, -1 / 6, 0.0],
    ]
)
_OFFSETS = np.arange(-1, 3)
TABLE_TOL = 2e-4  # [m] a table cell is used only if its validated interpolation error is below


@dataclass(frozen=True)
class FastSolution:
    """The table's answer for one target.

    Attributes:
        elevation: chosen elevation [rad].
        stroke: stroke L_s [m].
        slope: dR/dL_s at the answer [m/m] (negative).
        feasible: per candidate elevation, whether it reaches the distance, shape (n_e,).
        strokes: per candidate elevation the stroke that reaches it [m] (NaN if none).
    """

    elevation: float
    stroke: float
    slope: float
    feasible: np.ndarray
    strokes: np.ndarray


@dataclass(frozen=True)
class ReachTable:
    """Reach R [m] of one object on an (elevation × drop × stroke) grid.

    Attributes:
        elevations: candidate elevations [rad], shape (n_e,).
        drops: drops h = z0 - land_z [m], uniform, shape (n_h,).
        strokes: strokes L_s [m], uniform, shape (n_s,).
        reach: R [m], NaN where the throw never lands, shape (n_e, n_h, n_s).
        error: interpolation error against predict_landing at each cell's centre [m],
            shape (n_e, n_h - 1, n_s - 1); NaN where not checkable.
        valid: cells whose error is below TABLE_TOL, shape (n_e, n_h - 1, n_s - 1).
    """

    elevations: np.ndarray
    drops: np.ndarray
    strokes: np.ndarray
    reach: np.ndarray
    error: np.ndarray
    valid: np.ndarray

    @property
    def max_error_m(self) -> float:
        """The largest validated interpolation error over the cells in use [m]."""
        used = self.error[self.valid]
        return float(used.max()) if used.size else float("nan")

    def _drop_cell(self, drop: float) -> tuple[int, int, np.ndarray] | None:
        x = (drop - self.drops[0]) / (self.drops[1] - self.drops[0])
        n_h = len(self.drops)
        if not 0.0 <= x <= n_h - 1:
            return None
        cell = min(int(x), n_h - 2)
        base = min(max(cell, 1), n_h - 3)
        t = x - base
        w = np.array(
            [
                -t * (t - 1) * (t - 2) / 6,
                (t + 1) * (t - 1) * (t - 2) / 2,
                -(t + 1) * t * (t - 2) / 2,
                (t + 1) * t * (t - 1) / 6,
            ]
        )
        return cell, base, w

    def reach_at(self, drop: float) -> np.ndarray:
        """R on the stroke grid for every elevation at one drop [m], shape (n_e, n_s).

        NaN where the drop is outside the table or a node never lands.
        """
        found = self._drop_cell(drop)
        if found is None:
            return np.full((len(self.elevations), len(self.strokes)), np.nan)
        _, base, w = found
        return np.tensordot(w, self.reach[:, base - 1 : base + 3, :], axes=([0], [1]))

    def invert(self, distance: float, drop: float) -> FastSolution | None:
        """The elevation and stroke that reach a distance with the least stored energy.

        Every candidate elevation's stroke is found by inverting the cubic
        interpolant of R in L_s (Newton on the cubic); the largest stroke (least
        stored energy, as the energy falls with L_s) wins. Only validated cells
        are used.

        Args:
            distance: horizontal distance from the release point to the target [m].
            drop: release height minus landing-plane height [m].

        Returns:
            The solution, or None when no candidate elevation reaches the distance.
        """
        found = self._drop_cell(drop)
        if found is None:
            return None
        cell, base_h, w = found
        r = np.tensordot(w, self.reach[:, base_h - 1 : base_h + 3, :], axes=([0], [1]))
        n_s = r.shape[1]
        with np.errstate(invalid="ignore", divide="ignore"):
            br = (r[:, :-1] >= distance) & (r[:, 1:] < distance)
            j = br.argmax(axis=1)
            rows = np.arange(r.shape[0])
            ok = br[rows, j] & self.valid[rows, cell, j]
            if not ok.any():
                return None
            base = np.clip(j, 1, n_s - 3)
            nodes = np.take_along_axis(r, base[:, None] + _OFFSETS[None, :], axis=1)
            ok &= np.isfinite(nodes).all(axis=1)
            if not ok.any():
                return None
            coef = np.where(ok[:, None], nodes, 0.0) @ _POWER
            a, b, c, d = coef[:, 0], coef[:, 1], coef[:, 2], coef[:, 3] - distance
            lo_t = (j - base).astype(float)
            r0 = r[rows, j]
            r1 = r[rows, j + 1]
            t = lo_t + np.clip((r0 - distance) / (r0 - r1), 0.0, 1.0)
            t = np.where(ok, t, lo_t)
            for _ in range(3):
                f = ((a * t + b) * t + c) * t + d
                df = (3 * a * t + 2 * b) * t + c
                t = np.clip(t - f / df, lo_t, lo_t + 1.0)
        ds = self.strokes[1] - self.strokes[0]
        strokes = np.where(ok, self.strokes[base] + t * ds, np.nan)
        best = int(np.nanargmax(strokes))
        tb = t[best]
        slope = float(((3 * a[best] * tb + 2 * b[best]) * tb + c[best]) / ds)
        return FastSolution(
            elevation=float(self.elevations[best]),
            stroke=float(strokes[best]),
            slope=slope,
            feasible=ok,
            strokes=strokes,
        )

    def reach_range(self, drop: float) -> tuple[float, float]:
        """(smallest, largest) reach over the candidate elevations at a drop [m].

        NaN, NaN when the drop is outside the table or nothing lands.
        """
        r = self.reach_at(drop)
        if not np.isfinite(r).any():
            return float("nan"), float("nan")
        return float(np.nanmin(r)), float(np.nanmax(r))


def _flat_batch(
    obj: ObjectParams, elevations: np.ndarray, drops: np.ndarray, strokes: np.ndarray
) -> ThrowBatch:
    e, h, s = np.meshgrid(elevations, drops, strokes, indexing="ij")
    n = e.size
    return ThrowBatch.build(
        stroke=s.ravel(),
        position=np.c_[np.zeros(n), np.zeros(n), h.ravel()],
        elevation=e.ravel(),
        azimuth=0.0,
        shape=obj.code,
        mass=obj.mass,
        size=obj.size,
        land_z=0.0,
    )


@functools.lru_cache(maxsize=64)
def reach_table(
    obj: ObjectParams,
    ee: EndEffectorParams,
    elevations: tuple[float, ...],
    stroke_range: tuple[float, float],
) -> ReachTable:
    """Build (once per object, end-effector, elevations and stroke range) and validate.

    Rows whose reach does not fall strictly with the stroke are dropped (set to
    NaN), so the inverse never uses them. Every cell is checked at its centre
    against predict_landing; cells whose interpolation error exceeds TABLE_TOL
    are not used.
    """
    elev = np.asarray(elevations, float)
    strokes = np.linspace(stroke_range[0], stroke_range[1], N_STROKES)
    shape = (len(elev), len(DROPS), len(strokes))
    reach = predict_landing(_flat_batch(obj, elev, DROPS, strokes), ee, strict=False).x
    reach = reach.reshape(shape)
    with np.errstate(invalid="ignore"):
        bad_rows = (np.diff(reach, axis=2) >= 0).any(axis=2)
    reach[bad_rows] = np.nan
    mid_h = DROPS[:-1] + 0.5 * (DROPS[1] - DROPS[0])
    mid_s = strokes[:-1] + 0.5 * (strokes[1] - strokes[0])
    exact = predict_landing(_flat_batch(obj, elev, mid_h, mid_s), ee, strict=False).x
    exact = exact.reshape(len(elev), len(mid_h), len(mid_s))
    table = ReachTable(elev, DROPS.copy(), strokes, reach, np.zeros(0), np.zeros(0, bool))
    base = np.clip(np.arange(len(mid_s)), 1, len(strokes) - 3)
    w = _lagrange4(np.arange(len(mid_s)) + 0.5 - base)  # (n_mid, 4)
    idx = base[:, None] + _OFFSETS[None, :]
    error = np.empty_like(exact)
    for ih, h in enumerate(mid_h):
        r = table.reach_at(float(h))  # (n_e, n_s)
        error[:, ih, :] = np.abs(np.einsum("mk,emk->em", w, r[:, idx]) - exact[:, ih, :])
    with np.errstate(invalid="ignore"):
        valid = error <= TABLE_TOL
    table = ReachTable(elev, DROPS.copy(), strokes, reach, error, valid)
    for a in vars(table).values():  # cached and shared by every plan in the process
        a.setflags(write=False)
    log.debug(
        "reach table %s: %d of %d cells valid, max error %.2e m",
        obj.name,
        valid.sum(),
        valid.size,
        table.max_error_m,
    )
    return table
