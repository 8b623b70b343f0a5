"""A camera's radial distortion as a term of the proposal's library (`cell.gap.propose`).

Landings measured by a camera whose lens is not corrected are moved along the radius from
the point under its axis, c: x' = c + (x − c)(1 + k r²), r = |x − c| (Brown's radial term,
its first coefficient). The landing moves by k r² (x − c): no effect of the vocabulary and
no other term of the library is radial about a point of the landing area (a tracker's
scale is about the world's origin and linear in r; a landing plane's slope moves a landing
along its own flight). The centre enters the landings non-linearly, so it is fitted first:
for each centre the best k is a closed form, and the centre is the one (from the logged
landings' median, by Nelder-Mead) that leaves the least misses on the throws fitted; the
column is then k's, about that centre, and the sparse law takes it or not as any other
term (its phase `measurement`; its bound in `cell.gap.propose_bounds`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import minimize

__all__ = ["RADIAL", "radial_term"]

RADIAL = "landing radial distortion [1/m²]"


def _column(xy: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = xy - c
    r2 = np.sum(d * d, axis=1)
    return d * r2[:, None], r2


def radial_term(xy: np.ndarray, logged: np.ndarray, resid: np.ndarray, keep: np.ndarray
                ) -> tuple[dict[str, Any], np.ndarray, np.ndarray]:  # fmt: skip
    """The radial distortion's term, its column (2n,) [m per unit k] and r² [m²] over the
    throws.

    xy (n, 2): the model's landings [m, W]; logged (n, 2): the logged landings (their
    median starts the centre's search); resid (n, 2): the misses to explain; keep (n,):
    the throws the centre is fitted on."""
    ok = keep & np.all(np.isfinite(xy), axis=1) & np.all(np.isfinite(resid), axis=1)
    x, y = xy[ok], resid[ok]

    def left(c: np.ndarray) -> float:
        g, _ = _column(x, c)
        gg = float(np.sum(g * g))
        k = float(np.sum(g * y)) / gg if gg > 0 else 0.0
        return float(np.sum((y - k * g) ** 2))

    start = np.nanmedian(logged, axis=0)
    c = start
    if ok.sum() >= 3 and np.all(np.isfinite(start)):
        got = minimize(left, start, method="Nelder-Mead",
                       options={"xatol": 1e-3, "fatol": 1e-9, "maxiter": 400})  # fmt: skip
        c = got.x if np.all(np.isfinite(got.x)) else start
    col, r2 = _column(np.nan_to_num(xy), c)
    term = {
        "phase": "measurement",
        "term": f"{RADIAL} = k · r² d, r from ({c[0]:.3f}, {c[1]:.3f}) m",
        "centre_m": [float(c[0]), float(c[1])],
    }
    return term, col.reshape(-1), r2
