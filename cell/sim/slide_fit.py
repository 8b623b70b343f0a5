"""A bounce's slide as the scene world measures it (`cell.gap.world_scene`): each law of the
bounce's family (`cell.model.effects_bounce`) fitted to the world's own slides (rest point
− crossing of the landing plane, against the crossing's velocity), the parameters a scene
case expects of the law the diagnosis chose. The laws are written here again, apart from
the model's (`cell.model.effects_apply`): the world shares no code with the fit."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "G",
    "extents_and_balls",
    "impact_fit",
    "drop_along",
    "drop_fit",
    "roll_along",
    "roll_fit",
    "slide_truth",
]

G = 9.81  # [m/s²]


def extents_and_balls(object_ids: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """The scene's objects of these ids (the catalogue's): their true extents (n, 3) [m]
    and which are balls (n,) (the roll law rolls those alone)."""
    from cell.sim.items import resolve_object

    objs = [resolve_object(o)[0] for o in object_ids]
    return (np.array([o.size for o in objs], float),
            np.array([o.shape == "sphere" for o in objs], bool))  # fmt: skip


def impact_fit(d: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """The impact law (`cell.model.effects.BounceImpact`) fitted to slides d (n, 2) [m]
    from impact velocities v (n, 3) [m/s]: (1/μ [-] minimising the squared 2-D residual of
    (v_h − μ |v_z|)₊² / (2 μ g) along v_h, a bounded 1-D search; the RMS 2-D residual [m])."""
    from scipy.optimize import minimize_scalar

    vh, vz = v[:, :2], np.abs(v[:, 2])
    speed = np.linalg.norm(vh, axis=1)
    u = vh / np.maximum(speed, 1e-12)[:, None]

    def ss(inv_mu: float) -> float:
        left = np.maximum(speed - vz / max(inv_mu, 1e-12), 0.0)
        r = d - u * (left**2 * inv_mu / (2 * G))[:, None]
        return float(np.sum(r * r))

    res = minimize_scalar(ss, bounds=(1e-3, 20.0), method="bounded", options={"xatol": 1e-4})
    return float(res.x), float(np.sqrt(ss(float(res.x)) / max(len(d), 1)))


def drop_along(v: np.ndarray, inv_mu: float, depth_m: float, size: np.ndarray) -> np.ndarray:
    """The drop law's slide along v_h (n,) [m] from the crossing's velocities v (n, 3)
    [m/s]: the fall from the plane until the object's centre is its smallest half-extent
    (of size (n, 3) [m]) above a floor depth_m below the plane, at v_h, then the impact at
    v_z' (μ v_z' off v_h) and the slide (v_h')² / (2 μ g)."""
    speed, vz = np.linalg.norm(v[:, :2], axis=1), np.abs(v[:, 2])
    h = np.maximum(depth_m - np.min(size, axis=1) / 2, 0.0)
    vz_floor = np.sqrt(vz * vz + 2 * G * h)
    left = np.maximum(speed - vz_floor / max(inv_mu, 1e-12), 0.0)
    return speed * (vz_floor - vz) / G + left * left * inv_mu / (2 * G)


def drop_fit(d: np.ndarray, v: np.ndarray, size: np.ndarray) -> tuple[float, float, float]:
    """The drop law (`cell.model.effects_bounce.BounceDrop`) fitted to slides d (n, 2) [m]
    from the crossing's velocities v (n, 3) [m/s] of objects of extents size (n, 3) [m]:
    (1/μ [-], the floor's depth below the plane [m]) minimising the squared 2-D residual
    (bounded least squares from 1/μ 2, a depth of 0.25 m: the law's own start), and the RMS
    2-D residual [m]."""
    from scipy.optimize import least_squares

    u = v[:, :2] / np.maximum(np.linalg.norm(v[:, :2], axis=1), 1e-12)[:, None]

    def res(x: np.ndarray) -> np.ndarray:
        return (d - u * drop_along(v, x[0], x[1], size)[:, None]).reshape(-1)

    fit = least_squares(res, [2.0, 0.25], bounds=([1e-3, 0.0], [20.0, 1.0]), x_scale=[0.1, 0.01])
    rms = float(np.sqrt(np.mean(np.sum(res(fit.x).reshape(-1, 2) ** 2, axis=1))))
    return float(fit.x[0]), float(fit.x[1]), rms


def roll_along(v: np.ndarray, mu_r_m: float, depth_m: float, size: np.ndarray) -> np.ndarray:
    """The roll law's move along v_h (n,) [m] from the crossing's velocities v (n, 3)
    [m/s] of balls of extents size (n, 3) [m] (radius r the smallest half-extent) on a
    floor depth_m below the plane, of rolling resistance length mu_r_m [m]: the fall at
    v_h, then the impact's angular impulse about the contact point (the friction's acts
    through it, the rolling resistance's μ_r m v_z' against the roll) leaving
    L = m r v_h − μ_r m v_z' = (7/5) m r v' (rolling, I = 2/5 m r² about the centre),
    and the roll to rest under the torque μ_r m g, (7/5) m r v' / (μ_r m g) long, at
    v' / 2 on average."""
    r = np.min(size, axis=1) / 2
    speed, vz = np.linalg.norm(v[:, :2], axis=1), np.abs(v[:, 2])
    t_fall = (np.sqrt(vz * vz + 2 * G * np.maximum(depth_m - r, 0.0)) - vz) / G
    vz_floor = vz + G * t_fall
    v_roll = np.maximum(r * speed - mu_r_m * vz_floor, 0.0) / (1.4 * r)
    t_roll = 1.4 * r * v_roll / (mu_r_m * G)
    return speed * t_fall + 0.5 * v_roll * t_roll


def roll_fit(d: np.ndarray, v: np.ndarray, size: np.ndarray, ball: np.ndarray | None = None,
             depth_m: float | None = None) -> tuple[float, float, float]:  # fmt: skip
    """The roll law (`cell.model.effects_bounce.BounceRoll`) fitted to moves d (n, 2) [m]
    from the crossing's velocities v (n, 3) [m/s] of balls of extents size (n, 3) [m]:
    (1/μ_r [1/m], the floor's depth below the plane [m]) minimising the squared 2-D
    residual (bounded least squares in log μ_r from μ_r 0.01 m, the law's own start, and
    a depth of 0.25 m), and the RMS 2-D residual [m]. `ball` (n,) marks the balls: the law
    rolls those alone and leaves the others at the crossing (None: all balls). With
    `depth_m` [m] the depth is that (the plane's height above the floor) and 1/μ_r alone
    is fitted."""
    from scipy.optimize import least_squares

    u = v[:, :2] / np.maximum(np.linalg.norm(v[:, :2], axis=1), 1e-12)[:, None]
    if ball is not None:
        u = u * np.asarray(ball, bool)[:, None]

    def res(x: np.ndarray) -> np.ndarray:
        depth = x[1] if depth_m is None else depth_m
        return (d - u * roll_along(v, float(np.exp(x[0])), depth, size)[:, None]).reshape(-1)

    lo, hi = np.log(5e-4), np.log(1.0)
    if depth_m is None:
        fit = least_squares(
            res, [np.log(0.01), 0.25], bounds=([lo, 0.0], [hi, 1.0]), x_scale=[0.1, 0.01]
        )
    else:
        fit = least_squares(res, [np.log(0.01)], bounds=([lo], [hi]), x_scale=[0.1])
        fit.x = np.r_[fit.x, depth_m]
    rms = float(np.sqrt(np.mean(np.sum(res(fit.x).reshape(-1, 2) ** 2, axis=1))))
    return float(np.exp(-fit.x[0])), float(fit.x[1]), rms


def slide_truth(xy_rest: np.ndarray, xy_cross: np.ndarray, v: np.ndarray, size: np.ndarray,
                ball: np.ndarray | None = None, plane_z_m: float = 0.0
                ) -> dict[str, float]:  # fmt: skip
    """The bounce's slide measured in the world: least squares of (rest − crossing) on
    v_h (tau_s [s]), on v_h |v_h| / (2 g) (inv_mu [-]), on the impact law's slide
    (inv_mu_imp [-], `impact_fit`) and on the drop law's (inv_mu_drop [-] and depth_m [m],
    `drop_fit`, size (n, 3) [m] the objects' extents) and on the roll law's
    (inv_mu_r_per_m [1/m], `roll_fit`, the fall from the plane at plane_z_m [m] to the
    floor at z = 0, as the model's roll law takes it from the log; `ball` (n,) the balls:
    with none, no roll is measured and it is left out)."""
    ok = np.all(np.isfinite(xy_rest), axis=1) & np.all(np.isfinite(xy_cross), axis=1)
    d, vh = xy_rest[ok] - xy_cross[ok], v[ok, :2]
    q = vh * (np.linalg.norm(vh, axis=1) / (2 * G))[:, None]
    out = {"tau_s": float(np.sum(d * vh) / np.sum(vh * vh)),
           "inv_mu": float(np.sum(d * q) / np.sum(q * q)),
           "inv_mu_imp": impact_fit(d, v[ok])[0],
           **dict(zip(("inv_mu_drop", "depth_m"), drop_fit(d, v[ok], size[ok])[:2], strict=True))}  # fmt: skip
    balls = None if ball is None else np.asarray(ball, bool)[ok]
    if balls is None or balls.any():  # no ball, no roll to measure
        out["inv_mu_r_per_m"] = roll_fit(d, v[ok], size[ok], balls, plane_z_m)[0]
    return out
