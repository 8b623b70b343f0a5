"""Worlds from another implementation: throw campaigns written by code that shares nothing
with the diagnosis' model or fit (issue 57).

This module imports only NumPy. It implements MODEL.md from its text (the band law, the
launch push, the flight with quadratic drag, the landing crossing) with its own
integrator, and applies every effect with its own code, as a world would:

| effect (`kind`) | what this world does | law forms (`form`) |
|---|---|---|
| band_mass | the push drives m + m_b | const, stroke (m_b = k·L_s), mass (k·m), object, throw |
| release_pitch | the object leaves at e + δ | const, mass (δ = k·m), stroke, throw |
| release_yaw | the object leaves at azimuth a + δ (outside the vocabulary) | const, stroke |
| band_damping | the push is f_o (1 − c ΔL) | const |
| stroke_offset | the true stroke is L_s + δ | const |
| wind | air moving at w (horizontal) in the drag law | const, throw (w_i = w̄ + N(0, σ²)) |
| drag_scale | C_d times f | const, object, throw |
| downwash | air moving down at w (rpm/5000) in a Gaussian column about the release, decaying below it | const |
| side_force | a constant horizontal acceleration (outside the vocabulary) | const |
| slide | the object slides on after touchdown: τ·v_h (rolling) or v_h|v_h|/(2 μ g) (friction) | rolling, friction, friction_size (1/μ = k·size, a ball's rolling friction), object |
| tracking_scale | logged landings are s times the true ones | const |

An effect is a plain dict `{"kind": ..., "form": ..., parameters}` so a case can be
shipped to a worker. Outliers (`outliers` share of rows) are landings moved by 0.3–1 m in a
random direction (mis-logged or bounced off a rim); their row numbers are returned.

Each campaign carries its own noise floor: the RMS distance of the logged landings (outliers
left out) from the same world's landings with every effect at its deterministic part (a
throw-to-throw variation counts as noise) and no scatter.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "OBJECTS",
    "OtherCampaign",
    "draw_other_campaign",
    "draw_release_start",
    "landings",
    "band_push",
]

G = 9.81  # [m/s²]
RHO = 1.225  # [kg/m³]
# MODEL.md reference end-effector
R_R, L1, PHI, HOOP, L_T, L0 = 0.010, 0.030, np.pi / 2, 0.020, 0.160, 0.095
KE3, KE2, KE1, KC = 400.0, 150.0, 114.6, 0.0
PUSH_S = 0.012  # [s]
STROKES = np.linspace(0.03, 0.11, 9)
CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47, "mesh": 1.0}
# MODEL.md's golden objects and two more: name -> (shape, mass [kg], size [m])
OBJECTS: dict[str, tuple[str, float, tuple[float, float, float]]] = {
    "cube50": ("cube", 0.060, (0.05, 0.05, 0.05)),
    "cube30": ("cube", 0.020, (0.03, 0.03, 0.03)),
    "cuboid_c": ("cuboid", 0.110, (0.05, 0.05, 0.10)),
    "cyl50": ("cylinder", 0.075, (0.05, 0.05, 0.07)),
    "cyl70": ("cylinder", 0.120, (0.07, 0.07, 0.06)),
    "sphere40": ("sphere", 0.030, (0.04, 0.04, 0.04)),
    "sphere70": ("sphere", 0.090, (0.07, 0.07, 0.07)),
    "block40": ("cuboid", 0.045, (0.04, 0.06, 0.03)),
}
H_PUSH = PUSH_S / 24  # [s] steps of this world's integrator
H_FLIGHT = 0.002


def band_push(stroke: np.ndarray, width: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(ΔL [m], f_o [N]) of MODEL.md eqs. 3.1–3.9 for strokes and grip widths."""
    l2 = np.sqrt(((width - HOOP) / 2) ** 2 + (L_T - stroke) ** 2)
    dl = L1 + R_R * PHI + HOOP / 2 + l2 - L0
    fe = np.where(dl > 0, KE3 * dl**3 + KE2 * dl**2 + KE1 * dl + KC, 0.0)
    fe = np.clip(fe, 0.0, None)
    alpha = np.arctan2(width - HOOP, 2 * (L_T - stroke))
    return dl, 2 * fe * np.cos(alpha)


def _area(shape: str, size: tuple[float, float, float]) -> float:
    x, y, z = size
    if shape == "sphere":
        return np.pi * x**2 / 4
    if shape == "cylinder":
        return (2 * np.pi * (x / 2) ** 2 + 2 * np.pi * (x / 2) * z) / 4
    return (x * y + y * z + z * x) / 2


@dataclass
class Throws:
    """Throw configurations (arrays over n throws) and their objects."""

    obj: np.ndarray  # object names
    shape: np.ndarray
    mass: np.ndarray
    size: np.ndarray  # (n, 3)
    stroke: np.ndarray
    p0: np.ndarray  # (n, 3)
    elev: np.ndarray
    azim: np.ndarray
    vb: np.ndarray  # (n, 3)
    platform: np.ndarray
    rpm: np.ndarray
    land_z: np.ndarray
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.mass.size)


def draw_release_start(
    plat: str, rng: np.random.Generator
) -> tuple[list[float], np.ndarray, float]:
    """A random release for a platform: the grip centre [m, W] (under a drone at 1-2.5 m,
    else over the arm's table at 0.4-0.9 m), the base velocity [m/s, W] (a moving base's
    0.2-0.6 m/s in a random direction, else zero) and the drone's rotor speed [rpm]
    (3,000-9,000, else 0). The draws are made in this order, from `rng`."""
    vb = np.zeros(3)
    rpm = 0.0
    if plat == "drone":
        p0 = [rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(1.0, 2.5)]
        rpm = float(np.round(rng.uniform(3000, 9000), -2))
    else:
        p0 = [rng.uniform(-0.2, 0.4), rng.uniform(-0.3, 0.3), rng.uniform(0.4, 0.9)]
        if plat == "mobile":
            th = rng.uniform(-np.pi, np.pi)
            vb = rng.uniform(0.2, 0.6) * np.array([np.cos(th), np.sin(th), 0.0])
    return p0, vb, rpm


def draw_throws(n: int, rng: np.random.Generator, *, repeats: int = 2,
                drone_share: float = 0.3) -> Throws:  # fmt: skip
    """n throws (configurations thrown `repeats` times each, shuffled)."""
    names = list(OBJECTS)
    cfg = []
    plat_p = np.array([1.0 - drone_share - 0.2, 0.2, drone_share])
    for _ in range(-(-n // repeats)):
        o = names[int(rng.integers(len(names)))]
        plat = str(rng.choice(["arm", "mobile", "drone"], p=plat_p / plat_p.sum()))
        p0, vb, rpm = draw_release_start(plat, rng)
        c = (o, float(rng.choice(STROKES)), p0, float(np.radians(rng.choice([5, 20, 35, 50]))),
             float(rng.uniform(-np.pi, np.pi)), vb, plat, rpm,
             float(rng.choice([0.0, 0.25], p=[0.75, 0.25])))  # fmt: skip
        cfg += [c] * repeats
    cfg = [cfg[i] for i in rng.permutation(len(cfg))[:n]]
    return Throws(
        obj=np.array([c[0] for c in cfg]),
        shape=np.array([OBJECTS[c[0]][0] for c in cfg]),
        mass=np.array([OBJECTS[c[0]][1] for c in cfg]),
        size=np.array([OBJECTS[c[0]][2] for c in cfg], float),
        stroke=np.array([c[1] for c in cfg]),
        p0=np.array([c[2] for c in cfg], float),
        elev=np.array([c[3] for c in cfg]),
        azim=np.array([c[4] for c in cfg]),
        vb=np.array([c[5] for c in cfg], float),
        platform=np.array([c[6] for c in cfg]),
        rpm=np.array([c[7] for c in cfg]),
        land_z=np.array([c[8] for c in cfg]),
    )


def _value(eff: dict[str, Any], th: Throws, rng: np.random.Generator | None,
           name: str = "value") -> np.ndarray:  # fmt: skip
    """Per-throw size of a one-parameter effect under its form (deterministic part when
    rng is None)."""
    form = eff.get("form", "const")
    n = len(th)
    if form == "const":
        return np.full(n, float(eff[name]))
    if form in ("stroke", "mass"):
        cov = th.stroke if form == "stroke" else th.mass
        return float(eff["k"]) * cov
    if form == "object":
        table = eff["per_object"]
        return np.array([float(table.get(o, eff[name])) for o in th.obj])
    if form == "throw":
        base = np.full(n, float(eff[name]))
        if rng is None:
            return base
        return base + rng.normal(0.0, float(eff["sd"]), n)
    raise KeyError(form)


def _wind(eff: dict[str, Any], n: int, rng: np.random.Generator | None) -> np.ndarray:
    w = np.zeros((n, 3))
    w[:, 0], w[:, 1] = float(eff["x_mps"]), float(eff["y_mps"])
    if eff.get("form") == "throw" and rng is not None:
        w[:, :2] += rng.normal(0.0, float(eff["sd"]), (n, 2))
    return w


def _find(effs: list[dict[str, Any]], kind: str) -> dict[str, Any] | None:
    return next((e for e in effs if e["kind"] == kind), None)


def _launch(th: Throws, effs: list[dict[str, Any]], rng: np.random.Generator | None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(push force [N], pushed mass [kg], throw axis (n, 3)) under the launch effects."""
    n = len(th)
    so = _find(effs, "stroke_offset")
    stroke = th.stroke + (float(so["value"]) if so else 0.0)
    dl, f_o = band_push(stroke, th.size[:, 0])
    bd = _find(effs, "band_damping")
    if bd:
        f_o = f_o * np.clip(1.0 - float(bd["value"]) * dl, 0.0, None)
    bm = _find(effs, "band_mass")
    m_push = th.mass + (_value(bm, th, rng) if bm else np.zeros(n))
    rp, ry = _find(effs, "release_pitch"), _find(effs, "release_yaw")
    e = th.elev + (_value(rp, th, rng) if rp else 0.0)
    a = th.azim + (_value(ry, th, rng) if ry else 0.0)
    u = np.stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)], axis=1)
    return f_o, m_push, u


def _air(th: Throws, effs: list[dict[str, Any]], rng: np.random.Generator | None) -> Any:
    """The air velocity field w(p, idx) of the flight effects, (m, 3) [m/s]."""
    n = len(th)
    wd = _find(effs, "wind")
    steady = _wind(wd, n, rng) if wd else np.zeros((n, 3))
    dw = _find(effs, "downwash")

    def air(p: np.ndarray, idx: np.ndarray) -> np.ndarray:
        w = steady[idx].copy()
        if dw:
            c = th.p0[idx]
            r2 = (p[:, 0] - c[:, 0]) ** 2 + (p[:, 1] - c[:, 1]) ** 2
            depth = np.clip(c[:, 2] - p[:, 2], 0.0, None)
            speed = float(dw["w_mps"]) * th.rpm[idx] / 5000.0
            w[:, 2] -= (
                speed
                * np.exp(-r2 / float(dw["radius_m"]) ** 2)
                * np.exp(-depth / float(dw["depth_m"]))
            )
        return w

    return air


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
    reads_p = _find(effs, "downwash") is not None  # the air depends on where the object is
    # the air without a downwash: the same all along each flight
    steady = np.zeros((n, 3)) if reads_p else air(th.p0, np.arange(n))
    # per row: −(drag per unit |v|) in the push (the push drives m + m_b) and after it, the
    # push's acceleration; taken once, the same operations as at every stage
    neg_drag = {True: -(kd * th.mass / m_push)[:, None], False: -(kd * th.mass / th.mass)[:, None]}
    a_push = (f_o / m_push)[:, None] * u
    # the rows integrated, and their arrays (each row's arithmetic is its own: the rows
    # that have landed are dropped once they are over half of those integrated)
    at: dict[str, Any] = {}

    def rows(idx: np.ndarray) -> None:
        at.update(idx=idx, lz=th.land_z[idx], steady=steady[idx], push=a_push[idx],
                  drag={k: d[idx] for k, d in neg_drag.items()})  # fmt: skip

    def rate(t: float, p: np.ndarray, v: np.ndarray) -> np.ndarray:
        rel = v - (air(p, at["idx"]) if reads_p else at["steady"])
        pushed = t < PUSH_S
        # |rel|: ((x² + y²) + z², `np.add.reduce`'s sum over a row of three) from the
        # squares' columns, one call over the rows each, not a reduction row by row
        sq = rel * rel
        a = at["drag"][pushed] * np.sqrt((sq[:, 0] + sq[:, 1]) + sq[:, 2])[:, None] * rel
        a[:, 2] -= G
        a += a_side
        if pushed:
            a += at["push"]
        return a

    rows(np.arange(n))
    p, v = th.p0.copy(), th.vb.copy()
    t = 0.0
    done = np.zeros(n, bool)
    steps: list[tuple[np.ndarray, ...]] = []  # each crossing: its rows, states and step
    while t < 6.0 and not done.all():
        h = H_PUSH if t < PUSH_S - 1e-12 else H_FLIGHT
        k1v = rate(t, p, v)
        k2p = v + h / 2 * k1v
        k2v = rate(t + h / 2, p + h / 2 * v if reads_p else p, k2p)
        k3p = v + h / 2 * k2v
        k3v = rate(t + h / 2, p + h / 2 * k2p if reads_p else p, k3p)
        k4p = v + h * k3v
        k4v = rate(t + h - 1e-12, p + h * k3p if reads_p else p, k4p)
        p1 = p + h / 6 * (v + 2 * k2p + 2 * k3p + k4p)
        v1 = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
        cross = ~done & (v1[:, 2] < 0) & (p1[:, 2] <= at["lz"]) & (t + h > PUSH_S)
        if cross.any():
            k = np.flatnonzero(cross)
            steps.append((at["idx"][k], p[k], p1[k], v[k], v1[k], np.full(k.size, t),
                          np.full(k.size, h)))  # fmt: skip
            done |= cross
        p, v, t = p1, v1, t + h
        if np.count_nonzero(done) > done.size / 2:
            going = ~done
            rows(at["idx"][going])
            p, v, done = p[going], v[going], done[going]
    xy, tl, vimp = _crossings(th, n, steps)
    xy = _slide(th, xy, vimp, _find(effs, "slide"))
    ts = _find(effs, "tracking_scale")
    if ts:
        xy = xy * float(ts["value"])
    return xy, tl, vimp


def _crossings(th: Throws, n: int, steps: list[tuple[np.ndarray, ...]]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """(xy (n, 2), time (n,), velocity (n, 3)) where each throw crosses its landing plane
    within the step it crossed in (rows, p, p1, v, v1, t, h of each such step): a cubic
    Hermite in z over the step, its root by bisection, all crossings at once (each row's
    arithmetic its own); NaN for a throw that never crossed."""
    xy, tl, vimp = np.full((n, 2), np.nan), np.full(n, np.nan), np.full((n, 3), np.nan)
    if not steps:
        return xy, tl, vimp
    rows, pp, pv, vv0, vv1, t, h = (np.concatenate(a) for a in zip(*steps, strict=True))
    z0, z1 = pp[:, 2] - th.land_z[rows], pv[:, 2] - th.land_z[rows]
    d0, d1 = vv0[:, 2] * h, vv1[:, 2] * h
    lo, hi = np.zeros(z0.size), np.ones(z0.size)
    for _ in range(40):
        s = 0.5 * (lo + hi)
        z = ((2 * s**3 - 3 * s**2 + 1) * z0 + (s**3 - 2 * s**2 + s) * d0
             + (-2 * s**3 + 3 * s**2) * z1 + (s**3 - s**2) * d1)  # fmt: skip
        above = z > 0
        lo, hi = np.where(above, s, lo), np.where(above, hi, s)
    s = 0.5 * (lo + hi)[:, None]
    hc = h[:, None]
    xy[rows] = ((2 * s**3 - 3 * s**2 + 1) * pp[:, :2] + (s**3 - 2 * s**2 + s) * hc
                * vv0[:, :2] + (-2 * s**3 + 3 * s**2) * pv[:, :2]
                + (s**3 - s**2) * hc * vv1[:, :2])  # fmt: skip
    vimp[rows] = (1 - s) * vv0 + s * vv1
    tl[rows] = t + s[:, 0] * h
    return xy, tl, vimp


def _slide(th: Throws, xy: np.ndarray, vimp: np.ndarray, sl: dict[str, Any] | None
           ) -> np.ndarray:  # fmt: skip
    if not sl:
        return xy
    vh = vimp[:, :2]
    if sl.get("form") == "friction":
        return xy + vh * (np.linalg.norm(vh, axis=1) / (2 * float(sl["mu"]) * G))[:, None]
    if sl.get("form") == "friction_size":  # 1/μ = k · size across the throw (a rolling ball's)
        inv_mu = float(sl["k"]) * th.size[:, 0]
        return xy + vh * (np.linalg.norm(vh, axis=1) * inv_mu / (2 * G))[:, None]
    tau = _value(sl, th, None, "tau_s")
    return xy + vh * tau[:, None]


@dataclass(frozen=True)
class OtherCampaign:
    """A campaign of this world: log records, the world's own floor and the outlier rows.

    Attributes:
        records: one dict per logged throw (docs/throw_log.md columns).
        floor_m: RMS distance [m] of the logged inlier landings from the deterministic
            world (the same world with no scatter and no throw-to-throw variation): every
            row but the injected outliers (`floor_on`).
        outliers: row numbers (0-based, in records) of the moved landings.
        scatter_m: the injected 2-D landing scatter [m] (RMS).
        reference_xy: per record, the deterministic world's landing [m] (world frame),
            shape (len(records), 2): what the floor measures each logged landing from.
    """

    records: list[dict[str, Any]]
    floor_m: float
    outliers: tuple[int, ...]
    scatter_m: float
    reference_xy: np.ndarray | None = None

    def floor_on(self, keep: np.ndarray | None = None) -> float:
        """The world's floor [m] counted on the logged rows `keep` (a mask over
        `records`; every row when None): the RMS distance of their logged landings from
        the deterministic world. An injected outlier (mis-logged, no part of the world's
        noise) is never counted; NaN where no row is left."""
        if self.reference_xy is None:
            raise ValueError("floor_on: the campaign carries no reference landings")
        landed = np.array([[r["landed_x_m"], r["landed_y_m"]] for r in self.records], float)
        use = np.ones(len(self.records), bool) if keep is None else np.asarray(keep, bool).copy()
        use[list(self.outliers)] = False
        if not use.any():
            return float("nan")
        d = landed[use] - self.reference_xy[use]
        return float(np.sqrt(np.mean(np.sum(d * d, axis=1))))


def throw_record(th: Throws, i: int, landed_xy: np.ndarray, t_flight_s: float) -> dict[str, Any]:
    """Throw i of `th` as a throw-log record (docs/throw_log.md columns), landed at
    landed_xy [m] (world frame) after t_flight_s [s]."""
    return {
        "throw_id": f"o{i:04d}", "object_id": str(th.obj[i]), "shape": str(th.shape[i]),
        "mass_kg": float(th.mass[i]), "size_x_m": float(th.size[i, 0]),
        "size_y_m": float(th.size[i, 1]), "size_z_m": float(th.size[i, 2]),
        "stroke_m": float(th.stroke[i]), "x_m": float(th.p0[i, 0]),
        "y_m": float(th.p0[i, 1]), "z_m": float(th.p0[i, 2]),
        "elevation_rad": float(th.elev[i]), "azimuth_rad": float(th.azim[i]),
        "roll_rad": 0.0, "vx_mps": float(th.vb[i, 0]), "vy_mps": float(th.vb[i, 1]),
        "vz_mps": float(th.vb[i, 2]), "platform": str(th.platform[i]),
        "rotor_rpm": float(th.rpm[i]), "land_z_m": float(th.land_z[i]),
        "landed_x_m": float(landed_xy[0]), "landed_y_m": float(landed_xy[1]),
        "session": "other", "t_flight_s": float(t_flight_s),
    }  # fmt: skip


def draw_other_campaign(effects: list[dict[str, Any]], rng: np.random.Generator, *,
                        n: int = 400, noise_m: float = 0.012, outliers: float = 0.0,
                        repeats: int = 2, drone_share: float = 0.3) -> OtherCampaign:  # fmt: skip
    """Draw a campaign of this world with `effects` applied (see the module table)."""
    th = draw_throws(n, rng, repeats=repeats, drone_share=drone_share)
    xy, tl, _ = landings(th, effects, np.random.default_rng(int(rng.integers(2**31))))
    ref, _, _ = landings(th, effects, None)
    ok = np.all(np.isfinite(xy), axis=1) & np.all(np.isfinite(ref), axis=1)
    noise = rng.normal(0.0, noise_m, (n, 2))
    obs = xy + noise
    out_rows = np.zeros(n, bool)
    if outliers > 0:
        pick = rng.choice(np.flatnonzero(ok), int(round(outliers * ok.sum())), replace=False)
        ang = rng.uniform(-np.pi, np.pi, pick.size)
        dist = rng.uniform(0.3, 1.0, pick.size)
        obs[pick] += dist[:, None] * np.c_[np.cos(ang), np.sin(ang)]
        out_rows[pick] = True
    recs: list[dict[str, Any]] = []
    rows_out: list[int] = []
    for i in np.flatnonzero(ok):
        if out_rows[i]:
            rows_out.append(len(recs))
        recs.append(throw_record(th, int(i), obs[i], float(tl[i])))
    inl = ok & ~out_rows
    d = obs[inl] - ref[inl]
    return OtherCampaign(
        records=recs,
        floor_m=float(np.sqrt(np.mean(np.sum(d * d, axis=1)))),
        outliers=tuple(rows_out),
        scatter_m=float(np.sqrt(np.mean(np.sum(noise[ok] ** 2, axis=1)))),
        reference_xy=ref[ok],
    )
