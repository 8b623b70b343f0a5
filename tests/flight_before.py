"""The flight integrators and the flight effects' callback as they were before they were
made faster (`cell.model.flight3d`, `cell.model.planar.flight_planar`,
`cell.model.integrate`'s crossing, `cell.model.effects_apply`, `cell.gap.track_ode._simulate`
and `cell.gap.world_laws._accel` at f56b63f), kept frozen
for tests/test_flight_same.py to compare the fast ones against on random batches. Tests
only; nothing in `cell` imports it."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from cell.model.effects import (
    DOWNWASH_EDGE_M,
    DOWNWASH_REF_RPM,
    Downwash,
    DownwashDecay,
    DragScale,
    Effect,
    Spin,
    Wind,
    _find,
)
from cell.model.integrate import rk4_step
from cell.model.params import G, aero_factor_kg_per_m
from cell.model.planar import rk4_planar
from cell.model.throw import ThrowBatch, drag_constant


def hermite_root(z0, z1, w0, w1, level):  # type: ignore[no-untyped-def]
    a = 2 * z0 - 2 * z1 + w0 + w1
    b = -3 * z0 + 3 * z1 - 2 * w0 - w1
    c = w0
    d = z0 - level
    lo = np.zeros_like(z0)
    hi = np.ones_like(z0)
    s = np.clip(d / np.maximum(z0 - z1, 1e-300), 0.0, 1.0)
    for _ in range(8):
        f = ((a * s + b) * s + c) * s + d
        lo = np.where(f > 0, s, lo)
        hi = np.where(f > 0, hi, s)
        df = (3 * a * s + 2 * b) * s + c
        with np.errstate(divide="ignore", invalid="ignore"):
            s_new = s - f / df
        bad = ~np.isfinite(s_new) | (s_new < lo) | (s_new > hi)
        s = np.where(bad, 0.5 * (lo + hi), s_new)
    return s


def hermite(y0, y1, w0, w1, s):  # type: ignore[no-untyped-def]
    s2 = s * s
    s3 = s2 * s
    return (
        (2 * s3 - 3 * s2 + 1) * y0
        + (s3 - 2 * s2 + s) * w0
        + (-2 * s3 + 3 * s2) * y1
        + (s3 - s2) * w1
    )


def plane_crossing(p0, p1, v0, v1, step, level):  # type: ignore[no-untyped-def]
    z = p0.shape[1] - 1
    s = hermite_root(p0[:, z], p1[:, z], step * v0[:, z], step * v1[:, z], level)
    pos = np.empty(p0.shape)
    vel = np.empty(p0.shape)
    for j in range(p0.shape[1]):
        pos[:, j] = hermite(p0[:, j], p1[:, j], step * v0[:, j], step * v1[:, j], s)
        vel[:, j] = v0[:, j] + (v1[:, j] - v0[:, j]) * s
    return s, pos, vel


def _rates(p, v, k, idx, accel):  # type: ignore[no-untyped-def]
    if accel is None:
        w, extra = None, None
    else:
        w, extra = accel(p, v, idx)
    rel = v if w is None else v - w
    a = -k[:, None] * np.sqrt(np.einsum("ij,ij->i", rel, rel))[:, None] * rel
    a[:, 2] -= G
    if extra is not None:
        a += extra
    return a


def _rk4(p, v, k, idx, accel, h):  # type: ignore[no-untyped-def]
    def rates(ps, vs):  # type: ignore[no-untyped-def]
        return [_rates(ps[0], vs[0], k, idx, accel)]

    (p1,), (v1,) = rk4_step(rates, [p], [v], h, reads_position=True)
    return p1, v1


def fly(position, velocity, k, land_z, *, accel=None, t0=0.0, step=0.01, t_max=30.0):  # type: ignore[no-untyped-def]
    """(position, velocity, t, landed) of each throw's crossing."""
    n = position.shape[0]
    out_p = np.full((n, 3), np.nan)
    out_v = np.full((n, 3), np.nan)
    out_t = np.full(n, np.nan)
    t_start = np.broadcast_to(np.asarray(t0, float), (n,))
    idx = np.arange(n)
    p = np.asarray(position, float).copy()
    v = np.asarray(velocity, float).copy()
    kk = np.asarray(k, float)
    lz = np.asarray(land_z, float)
    t = 0.0
    while idx.size and t < t_max:
        p1, v1 = _rk4(p, v, kk[idx], idx, accel, step)
        cross = (p[:, 2] > lz[idx]) & (p1[:, 2] <= lz[idx])
        if np.any(cross):
            c = cross
            s, out_p[idx[c]], out_v[idx[c]] = plane_crossing(
                p[c], p1[c], v[c], v1[c], step, lz[idx][c]
            )
            out_t[idx[c]] = t_start[idx[c]] + t + s * step
        keep = ~cross & ~((p1[:, 2] <= lz[idx]) & (v1[:, 2] < 0))
        idx, p, v = idx[keep], p1[keep], v1[keep]
        t += step
    return out_p, out_v, out_t, np.isfinite(out_t)


def sample_path(position, velocity, k, t_rel, *, accel=None, step=0.01):  # type: ignore[no-untyped-def]
    n, m = t_rel.shape
    out = np.full((n, m, 3), np.nan)
    t_end = np.nanmax(np.where(np.isfinite(t_rel), t_rel, -1.0), axis=1)
    idx = np.arange(n)[t_end >= 0]
    p = np.asarray(position, float)[idx].copy()
    v = np.asarray(velocity, float)[idx].copy()
    kk = np.asarray(k, float)
    t = 0.0
    while idx.size:
        p1, v1 = _rk4(p, v, kk[idx], idx, accel, step)
        tr = t_rel[idx]
        inside = (tr >= t) & (tr < t + step)
        if np.any(inside):
            rows, cols = np.nonzero(inside)
            s = (tr[rows, cols] - t) / step
            for j in range(3):
                out[idx[rows], cols, j] = hermite(
                    p[rows, j], p1[rows, j], step * v[rows, j], step * v1[rows, j], s
                )
        t += step
        keep = t_end[idx] >= t
        idx, p, v = idx[keep], p1[keep], v1[keep]
    return out


def flight_accel(batch: ThrowBatch, effects: Sequence[Effect], rotor_rpm: np.ndarray) -> Any:
    """The callback of `cell.model.effects_apply._flight_accel` (no permutation)."""
    wind = _find(effects, Wind)
    dw = _find(effects, Downwash) or _find(effects, DownwashDecay)
    sp = _find(effects, Spin)
    ds = _find(effects, DragScale)
    if wind is None and dw is None and sp is None and ds is None:
        return None
    decay = isinstance(dw, DownwashDecay)
    w_const = np.array([wind.x_mps, wind.y_mps, wind.z_mps], float) if wind else np.zeros(3)
    centre = batch.position[:, :2]
    release_z = batch.position[:, 2]
    if dw is not None:
        w_dw = dw.speed_mps * (np.clip(rotor_rpm, 0.0, None) / DOWNWASH_REF_RPM) ** dw.exponent
    if sp is not None:
        from cell.model.objects import drag_area

        area = np.asarray(drag_area(batch.shape, batch.size))
        kl = aero_factor_kg_per_m(1.0, area) / batch.mass
        radius = batch.size.max(axis=1) / 2
    if ds is not None:
        k_extra = (ds.factor - 1.0) * drag_constant(batch.shape, batch.mass, batch.size)

    def accel(p, v, idx):  # type: ignore[no-untyped-def]
        w = np.empty_like(p)
        w[:] = w_const
        if dw is not None:
            rho = np.hypot(p[:, 0] - centre[idx, 0], p[:, 1] - centre[idx, 1])
            inside = 0.5 * (1.0 + np.tanh((dw.radius_m - rho) / DOWNWASH_EDGE_M))
            if decay:
                depth = np.clip(release_z[idx] - p[:, 2], 0.0, None)
                inside = inside * np.exp(-depth / dw.depth_m)
            w[:, 2] -= w_dw[idx] * inside
        extra = None
        if sp is not None:
            rel = v - w
            speed = np.maximum(np.linalg.norm(rel, axis=1), 1e-9)
            nz = 1.0 - (rel[:, 2] / speed) ** 2
            n = -rel * (rel[:, 2] / speed**2)[:, None]
            n[:, 2] += 1.0
            n /= np.sqrt(np.maximum(nz, 1e-12))[:, None]
            s_ratio = sp.spin_rad_s * radius[idx] / speed
            c_l = sp.lift_max * np.tanh(s_ratio / sp.lift_max)
            extra = (kl[idx] * c_l * speed**2)[:, None] * n
        if ds is not None:
            rel = v - w
            drag = -(k_extra[idx] * np.linalg.norm(rel, axis=1))[:, None] * rel
            extra = drag if extra is None else extra + drag
        return w, extra

    return accel


def flight_planar(z, vh, vz, k, land_z, max_step, t_max=30.0):  # type: ignore[no-untyped-def]
    """`cell.model.planar.flight_planar` before: each crossing located at its step."""
    n = z.shape[0]
    out_h = np.full(n, np.nan)
    out_t = np.full(n, np.nan)
    out_vh = np.full(n, np.nan)
    out_vz = np.full(n, np.nan)
    idx = np.arange(n)
    h_pos = np.zeros(n)
    t = 0.0
    z, vh, vz, k, lz = z.copy(), vh.copy(), vz.copy(), k.copy(), land_z.copy()
    while idx.size and t < t_max:
        step = min(max_step, float(0.5 / max(np.max(k * np.sqrt(vh * vh + vz * vz)), 1e-9)))
        h1, z1, vh1, vz1 = rk4_planar(h_pos, z, vh, vz, k, step, np.sqrt)
        cross = (z > lz) & (z1 <= lz)
        if np.any(cross):
            c = cross
            s = hermite_root(z[c], z1[c], step * vz[c], step * vz1[c], lz[c])
            ids = idx[c]
            out_h[ids] = hermite(h_pos[c], h1[c], step * vh[c], step * vh1[c], s)
            out_t[ids] = t + s * step
            out_vh[ids] = vh[c] + (vh1[c] - vh[c]) * s
            out_vz[ids] = vz[c] + (vz1[c] - vz[c]) * s
        keep = ~cross & ~((z1 <= lz) & (vz1 < 0))
        t += step
        if not np.all(keep):
            idx = idx[keep]
            h_pos, z, vh, vz, k, lz = h1[keep], z1[keep], vh1[keep], vz1[keep], k[keep], lz[keep]
        else:
            h_pos, z, vh, vz = h1, z1, vh1, vz1
    return out_h, out_t, np.isfinite(out_t), out_vh, out_vz


TRACK_STEP_S = 0.01  # `cell.gap.track_ode.STEP_S`


def _ode_acc(v: np.ndarray, th: np.ndarray, k: np.ndarray) -> np.ndarray:
    """v̇ for states v (n, P, 3) under parameters th (n, P, 12), drag constants k (n,)."""
    w = np.zeros_like(v)
    w[..., :2] = th[..., 10:12]
    rel = v - w
    kk = k[:, None, None] * np.exp(th[..., 9:10])
    acc = th[..., 6:9] - kk * np.linalg.norm(rel, axis=-1, keepdims=True) * rel
    acc[..., 2] -= G
    return acc


def track_simulate(th: np.ndarray, k: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Positions [m] at times tau (n, m) (NaN: no sample), shape (n, P, m, 3), of the
    flights with parameters th (n, P, 12)."""
    n, n_p, _ = th.shape
    ok = np.isfinite(tau)
    t_end = float(np.nanmax(tau)) if ok.any() else 0.0
    n_steps = max(int(np.ceil(t_end / TRACK_STEP_S)), 1)
    h = t_end / n_steps if t_end > 0 else TRACK_STEP_S
    ti, si = np.nonzero(ok)
    x = tau[ti, si] / h
    node = np.minimum(np.floor(x).astype(int), n_steps - 1)
    s = (x - node)[:, None, None]
    order = np.argsort(node, kind="stable")
    bounds = np.searchsorted(node[order], np.arange(n_steps + 1))
    out = np.full((n, n_p, tau.shape[1], 3), np.nan)
    p = th[..., 0:3].copy()
    v = th[..., 3:6].copy()
    for i in range(n_steps):
        k1v = _ode_acc(v, th, k)
        k2p, k2v = v + 0.5 * h * k1v, _ode_acc(v + 0.5 * h * k1v, th, k)
        k3p, k3v = v + 0.5 * h * k2v, _ode_acc(v + 0.5 * h * k2v, th, k)
        k4p, k4v = v + h * k3v, _ode_acc(v + h * k3v, th, k)
        p1 = p + h / 6 * (v + 2 * k2p + 2 * k3p + k4p)
        v1 = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        sel = order[bounds[i] : bounds[i + 1]]
        if sel.size:
            tt, ss, sv = ti[sel], si[sel], s[sel]
            h00 = 2 * sv**3 - 3 * sv**2 + 1
            h10 = sv**3 - 2 * sv**2 + sv
            h01 = -2 * sv**3 + 3 * sv**2
            h11 = sv**3 - sv**2
            out[tt, :, ss] = h00 * p[tt] + h10 * h * v[tt] + h01 * p1[tt] + h11 * h * v1[tt]
        p, v = p1, v1
        if not np.all(np.isfinite(p)):
            p = np.where(np.isfinite(p), p, 1e6)
            v = np.where(np.isfinite(v), v, 0.0)
    return out


WORLD_REF_RPM = 5000.0  # `cell.gap.world_laws.REF_RPM`


def _law(laws: list[dict[str, Any]], name: str) -> dict[str, Any] | None:
    return next((w for w in laws if w["law"] == name), None)


def world_accel(batch: ThrowBatch, laws: list[dict[str, Any]], rpm: np.ndarray) -> Any:
    """`cell.gap.world_laws._accel`: the other implementation's air flow."""
    jet = _law(laws, "jet")
    breeze = _law(laws, "breeze")
    if jet is None and breeze is None:
        return None
    centre = batch.position.copy()
    w0 = np.zeros(len(batch))
    if jet is not None:
        w0 = jet["w_mps"] * (np.clip(rpm, 0, None) / WORLD_REF_RPM) ** jet["p"]
    flow = np.zeros(3)
    if breeze is not None:
        flow[:2] = breeze["x_mps"], breeze["y_mps"]

    def accel(p: np.ndarray, v: np.ndarray, idx: np.ndarray) -> tuple[Any, Any]:
        w = np.broadcast_to(flow, p.shape).copy()
        if jet is not None:
            rho2 = (p[:, 0] - centre[idx, 0]) ** 2 + (p[:, 1] - centre[idx, 1]) ** 2
            depth = np.clip(centre[idx, 2] - p[:, 2], 0.0, None)
            prof = np.exp(-rho2 / jet["radius_m"] ** 2) * np.exp(-depth / jet["depth_m"])
            w[:, 2] -= w0[idx] * prof
        return w, None

    return accel
