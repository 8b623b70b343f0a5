"""`cell.gap.world_other.landings` as it was before its integrator dropped the throws that
have landed and took each throw's drag and push once (at a44dc94), kept frozen for
tests/test_gap_world_rows.py to compare the faster one against, to the bit. Tests only;
nothing in `cell` imports it."""

from __future__ import annotations

from typing import Any

import numpy as np

from cell.gap.world_other import (
    CD,
    H_FLIGHT,
    H_PUSH,
    PUSH_S,
    RHO,
    G,
    Throws,
    _air,
    _area,
    _crossings,
    _find,
    _launch,
    _slide,
    _value,
)


def landings(th: Throws, effs: list[dict[str, Any]], rng: np.random.Generator | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Where the throws come to rest, as logged: (xy (n, 2) [m], flight time (n,) [s],
    impact velocity (n, 3) [m/s]); NaN where a throw never lands within 6 s.

    With rng None every effect takes its deterministic part (a floor's reference)."""
    n = len(th)
    f_o, m_push, u = _launch(th, effs, rng)
    cd = np.array([CD[s] for s in th.shape])
    area = np.array([_area(s, tuple(z)) for s, z in zip(th.shape, th.size, strict=True)])
    dr = _find(effs, "drag_scale")
    if dr:
        cd = cd * _value(dr, th, rng)
    kd = 0.5 * RHO * cd * area / th.mass  # [1/m]
    sf = _find(effs, "side_force")
    a_side = np.zeros(3)
    if sf:
        a_side[:2] = float(sf["x_mps2"]), float(sf["y_mps2"])
    air = _air(th, effs, rng)
    idx = np.arange(n)

    def rate(t: float, p: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = v - air(p, idx)
        drag = (kd * th.mass / np.where(t < PUSH_S, m_push, th.mass))[:, None]
        a = -drag * np.linalg.norm(rel, axis=1)[:, None] * rel
        a[:, 2] -= G
        a += a_side
        if t < PUSH_S:
            a += (f_o / m_push)[:, None] * u
        return v, a

    p, v = th.p0.copy(), th.vb.copy()
    t = 0.0
    done = np.zeros(n, bool)
    steps: list[tuple[np.ndarray, ...]] = []  # each crossing: its rows, states and step
    while t < 6.0 and not done.all():
        h = H_PUSH if t < PUSH_S - 1e-12 else H_FLIGHT
        k1p, k1v = rate(t, p, v)
        k2p, k2v = rate(t + h / 2, p + h / 2 * k1p, v + h / 2 * k1v)
        k3p, k3v = rate(t + h / 2, p + h / 2 * k2p, v + h / 2 * k2v)
        k4p, k4v = rate(t + h - 1e-12, p + h * k3p, v + h * k3v)
        p1 = p + h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p)
        v1 = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        cross = ~done & (v1[:, 2] < 0) & (p1[:, 2] <= th.land_z) & (t + h > PUSH_S)
        if cross.any():
            k = np.flatnonzero(cross)
            steps.append((k, p[k], p1[k], v[k], v1[k], np.full(k.size, t), np.full(k.size, h)))
            done |= cross
        p, v, t = p1, v1, t + h
    xy, tl, vimp = _crossings(th, n, steps)
    xy = _slide(th, xy, vimp, _find(effs, "slide"))
    ts = _find(effs, "tracking_scale")
    if ts:
        xy = xy * float(ts["value"])
    return xy, tl, vimp
