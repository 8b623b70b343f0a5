"""The half fits of a track are the drag flight's own: on a flight with no effect, integrated
by scipy's solver (not the project's), each half's start state is the flight's and the
nominal flight from it ends where the half's fit ends (the tracks' bend is zero)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cell.gap.track_halves import halves

G = 9.81  # [m/s²], MODEL.md's


def _flight(p0: np.ndarray, v0: np.ndarray, k: float, t: np.ndarray) -> np.ndarray:
    """Positions [m] at times t of a ball under gravity and quadratic drag k |v| v [1/m]."""

    def rhs(_t: float, y: np.ndarray) -> np.ndarray:
        v = y[3:]
        return np.r_[v, -k * np.linalg.norm(v) * v - np.array([0.0, 0.0, G])]

    sol = solve_ivp(rhs, (0.0, float(t[-1])), np.r_[p0, v0], t_eval=t, rtol=1e-11, atol=1e-12)
    return sol.y[:3].T


# (drag [1/m], speed [m/s], elevation [rad], flight [s]): a light ball far out, a
# tennis-like ball, a foam ball. Drag evaluated off its own path (one pass) left their
# start velocities 14, 1.1 and 6.4 mm/s off and bends of 13.6, 1.0 and 6.4 mm; now
# 0.08, 0.006 and 0.05 mm/s, bends of 0.39, 0.012 and 0.09 mm
CASES = [(0.03, 8.0, 0.9, 1.2), (0.012, 7.0, 0.6, 0.9), (0.02, 8.0, 0.7, 1.1)]


@pytest.mark.parametrize(("k", "speed", "elev", "span"), CASES)
def test_the_halves_start_where_the_drag_flight_starts_and_bend_nothing(
    k: float, speed: float, elev: float, span: float
) -> None:
    p0 = np.array([0.3, -0.1, 1.0])
    v0 = speed * np.array([np.cos(elev) * 0.8, np.cos(elev) * 0.6, np.sin(elev)])
    t = np.arange(0.0, span, 1 / 300)
    tr = np.column_stack([t, _flight(p0, v0, k, t)])
    hv = halves(tr, k, 0)
    assert hv is not None
    for h in range(2):
        # both halves' states are at the track's first time (their fits share t - t[0])
        assert np.linalg.norm(hv[h, 0] - p0) < 5e-5  # [m]
        assert np.linalg.norm(hv[h, 1] - v0) < 5e-4  # [m/s]
        # the nominal flight from the half's first state against the half's own last state
        nom = _flight(hv[h, 0], hv[h, 1], k, np.array([0.0, t[-1] - t[0]]))[-1]
        assert np.linalg.norm(hv[h, 2] - nom) < 6e-4  # [m]
