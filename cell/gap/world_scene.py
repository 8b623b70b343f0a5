"""Worlds from the PyBullet scene, with each effect applied physically.

A campaign of this world is thrown in the cell's scene (`cell.sim.scene.CellScene`
without an arm, the end-effector held at each release pose as `cell calibrate`'s campaign
holds it: `cell.workflows.campaign.ReleasePose`), and the effects act on the flying
item as forces and contacts, never as a formula on the landing:

| kind | how it acts in the scene | forms |
|---|---|---|
| wind | the item's air drag is taken on its velocity relative to a steady air flow (x_mps, y_mps): a force −c_f·|v − w|·(v − w) each physics step | const, throw (each throw's flow drawn around the mean with sd) |
| drag_scale | the drag force is c_f = factor · ½ ρ C_d A of the object's own C_d and area | const, object (a factor per object id), stroke (factor = k · stroke), throw (each throw's factor drawn around the value with sd) |
| downwash | the air under a drone's rotors moves down: a round jet from the release point whose centre speed w_mps · rpm / 5000 falls as 1 / (1 + depth / core_m) and whose radius grows as radius_m + 0.2 · depth | const |
| launch | as the item leaves the pads its velocity is turned by yaw_k · stroke about the vertical and scaled by 1 + speed_k · stroke (outside the vocabulary) | stroke |
| side_force | a constant horizontal force m · (x_mps2, y_mps2) on the item in flight (outside the vocabulary) | const |
| bounce | the landing is where the item comes to rest on the floor, whose restitution and lateral friction are set (changeDynamics) | contact |
| tracker | the tracker's recorded positions (the landings, and the flights' samples where tracks are logged) are `scale` times the true ones about the origin and `latency_s` late | const |

The scene applies its own drag −c·|v|·v to every item (c = ½ ρ C_d A, `cell.sim.drag`);
this world adds, before each physics step, the force that turns it into the effect's:
−c_f·|v − w|·(v − w) + c·|v|·v, plus any side force.

A landing with bounce is logged where the item rests, or where it still rolls 3 s
after it crossed the landing plane. A tracker's landing scatter (`noise_m` per axis) and, optionally, outliers (landings
moved 0.3–1 m, mis-logged) are added to the logged landings. Optionally
(`track_noise_m`), the tracker's samples of each flight are logged too: the item's position
at 100 Hz from the release down to the landing plane, with a scatter per axis per sample.

The launcher does not repeat to the bit: each throw's true stroke is the logged one
times (1 + ε), ε ~ N(0, `JITTER_REL`) drawn per throw (the same draw with and without
the effect; the log keeps the nominal stroke). PyBullet itself repeats a configuration
to the bit, so without it repeats would not see what a chaotic contact scatters.

The campaign's floor is the world's own, what a perfect account of the effect would
still leave: F0, the same throws (same jitter) made again without the effect, logged with
the same tracker scatter, against the model as configured; combined with the scatter the
effect itself adds between repeats, F² = F0² + max(0, V_effect − V_none), V the pooled
within-configuration variance of the true logged points (2-D, unbiased; `repeat_var`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cell.catalogue import catalogue
from cell.errors import NoLanding
from cell.sim.effect_scene import EffectScene
from cell.sim.scene import item_linear_xyz, item_xyz
from cell.sim.slide_fit import extents_and_balls, slide_truth

__all__ = ["EffectScene", "SceneCampaign", "draw_plan", "throw_plan", "draw_scene_campaign"]

LAND_Z_M = 0.1  # [m] the campaign's landing plane (the crossing logged without bounce)
REST_SPEED = 0.01  # [m/s] an item slower than this for REST_STEPS steps is at rest
REST_STEPS = 30
REST_WAIT_S = 3.0  # [s] after the crossing, a still rolling item is logged where it is
# [-] the sd of a throw's true stroke about the logged one, relative. Far inside the
# thesis' repeatability (§5.3.1, Table 5.2: reach 1.345 ± 0.1086 m, 8.07 % of the reach,
# i.e. about 4 % of the launch speed): the free flights scatter by 0.2 % of the reach,
# well under the tracker's 25 mm, while a tumbling block's rest point scatters as much
# as at ten times the jitter (docs/gap_scene.md, "Repeats").
JITTER_REL = 0.001


def _find(effs: list[dict[str, Any]], kind: str) -> dict[str, Any] | None:
    return next((e for e in effs if e["kind"] == kind), None)


@dataclass(frozen=True)
class Throw:
    """One throw's configuration (plain values, so a plan ships to a worker)."""

    object_id: str
    stroke: float
    p0: tuple[float, float, float]
    elevation: float
    azimuth: float
    platform: str
    rpm: float


def draw_plan(n: int, rng: np.random.Generator, *, repeats: int = 2, drone_share: float = 0.0,
              objects: tuple[str, ...] | None = None) -> list[Throw]:  # fmt: skip
    """n throws of the catalogue's thesis14 objects (or `objects`), each configuration
    thrown `repeats` times (shuffled): strokes 35–105 mm, elevations 15–50°, any azimuth,
    released within ±0.8 m of the origin in x and y (a tracker's scale, about the origin,
    then differs from a slide along the flight) from 0.5–0.9 m high (arm) or 1.2–2.0 m
    under a drone at 3000–9000 rpm."""
    ids = sorted(objects or (k for k, e in catalogue().items() if e.set == "thesis14"))
    cfg: list[Throw] = []
    for _ in range(-(-n // repeats)):
        drone = rng.uniform() < drone_share
        z = rng.uniform(1.2, 2.0) if drone else rng.uniform(0.5, 0.9)
        t = Throw(
            object_id=str(ids[int(rng.integers(len(ids)))]),
            stroke=float(rng.uniform(0.035, 0.105)),
            p0=(float(rng.uniform(-0.8, 0.8)), float(rng.uniform(-0.8, 0.8)), float(z)),
            elevation=math.radians(float(rng.uniform(15.0, 50.0))),
            azimuth=float(rng.uniform(-math.pi, math.pi)),
            platform="drone" if drone else "arm",
            rpm=float(np.round(rng.uniform(3000, 9000), -2)) if drone else 0.0,
        )
        cfg += [t] * repeats
    return [cfg[i] for i in rng.permutation(len(cfg))[:n]]


def _one(sc: EffectScene, ee: Any, th: Throw, rest: bool, kick: dict[str, Any] | None = None,
         path: list[tuple[float, float, float, float]] | None = None
         ) -> tuple[np.ndarray, float, np.ndarray]:  # fmt: skip
    """Throw once: (logged point xy [m] — the crossing of LAND_Z_M, or the rest point with
    `rest` —, the crossing time [s since release], the crossing's velocity [m/s]). `kick`
    (a launch effect) turns and scales the item's velocity as it leaves the pads. `path`,
    if given, receives (t [s since release], x, y, z [m]) after every physics step of the
    flight, up to the step that crosses the landing plane."""
    from cell.workflows.campaign import ReleasePose

    pf = ReleasePose(sc, ee, th.object_id, th.stroke, th.p0, th.elevation, th.azimuth)
    item = pf.present(0, None)  # type: ignore[arg-type]
    try:
        pf.pick(pf.decide(0, item.obj, None), item.obj, item)
        t0 = sc.t
        pf.release(None)  # type: ignore[arg-type]
        # the tracker the release started (`PyBulletEndEffector.throw`) is never read here:
        # stopped, so the flight's steps do not sample it (a sample only reads the item's
        # state and contacts from PyBullet: the same physics, to the bit, without it)
        sc._trackers.pop(item.body, None)
        if kick:
            yaw = float(kick.get("yaw_k", 0.0)) * th.stroke
            sc.launch_error(item, yaw, float(kick.get("speed_k", 0.0)) * th.stroke)
        sc.set_timestep(sc.dt_s)
        # the item's state read as PyBullet's tuples of floats each step (NumPy only at the
        # crossing and for the rest test, the operations the arrays did), its velocity only
        # once it is used: at the crossing and, with `rest`, after it
        prev = item_xyz(sc, item)
        cross: tuple[np.ndarray, float, np.ndarray] | None = None
        slow = 0
        while sc.t - t0 < 8.0:
            sc.step()
            p = item_xyz(sc, item)
            if path is not None and cross is None:
                path.append((sc.t - t0, *p))
            if cross is None and prev[2] > LAND_Z_M >= p[2]:
                s = (prev[2] - LAND_Z_M) / (prev[2] - p[2])
                a, b = np.asarray(prev[:2], float), np.asarray(p[:2], float)
                v = np.asarray(item_linear_xyz(sc, item), float)
                cross = (a + s * (b - a), sc.t - sc.dt_s * (1 - s) - t0, v)
                if not rest:
                    return cross
            if cross is not None:
                v = np.asarray(item_linear_xyz(sc, item), float)
                slow = slow + 1 if np.linalg.norm(v) < REST_SPEED else 0
                if slow >= REST_STEPS or sc.t - t0 > cross[1] + REST_WAIT_S:
                    return np.asarray(p[:2], float), cross[1], cross[2]
            if p[2] < -1.0:
                break
            prev = p
        raise NoLanding(f"scene world: {th.object_id} did not land (or rest) within 8 s")
    finally:
        pf.finish(None)
        sc.remove_item(item)


def throw_plan(plan: list[Throw], effects: list[dict[str, Any]], seed: int,
               jitter_rel: float = JITTER_REL, *, rows: np.ndarray | None = None,
               paths: dict[int, np.ndarray] | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """Throw every planned throw (or the `rows` of it, a mask; NaN for the others) in a
    fresh EffectScene with `effects` on: (true logged points (n, 2) [m], crossing times
    (n,) [s], crossing velocities (n, 3) [m/s]); NaN for a throw that did not land. The
    tracker is not applied here. Each throw's stroke is jittered by a relative sd
    `jitter_rel`, drawn from `seed` alone (the same draws whatever the effects and rows).
    `paths`, if given, receives each landed throw's flight by row (`_one`'s `path`, (k, 4)):
    recording it moves nothing."""
    from cell.endeffector.factory import make_end_effector

    rng = np.random.default_rng(seed)
    n = len(plan)
    jit = 1.0 + jitter_rel * np.random.default_rng([seed, 57]).normal(size=n)
    xy, tl, vc = np.full((n, 2), np.nan), np.full(n, np.nan), np.full((n, 3), np.nan)
    wd, dr = _find(effects, "wind"), _find(effects, "drag_scale")
    dw, sf, bo = _find(effects, "downwash"), _find(effects, "side_force"), _find(effects, "bounce")
    kick = _find(effects, "launch")
    sc = EffectScene()
    try:
        ee = make_end_effector("pybullet", plant=sc)
        if bo:
            sc.set_floor(bo["restitution"], bo["friction"], float(bo.get("rolling_m", 0.0)))
        if sf:
            sc.side_mps2 = np.array([float(sf["x_mps2"]), float(sf["y_mps2"]), 0.0])
        for i, th in enumerate(plan):
            sc.wind = np.zeros(3)
            if wd:
                sc.wind[:2] = float(wd["x_mps"]), float(wd["y_mps"])
                if wd.get("form") == "throw":
                    sc.wind[:2] += rng.normal(0.0, float(wd["sd"]), 2)
            sc.drag_factor = 1.0
            if dr:
                per = dr.get("per_object", {})
                sc.drag_factor = float(per.get(th.object_id, dr.get("value", 1.0)))
                if dr.get("form") == "stroke":
                    sc.drag_factor = float(dr["k"]) * th.stroke
                if dr.get("form") == "throw":  # drawn for each throw, never below 0.1
                    sc.drag_factor = max(0.1, sc.drag_factor + rng.normal(0.0, float(dr["sd"])))
            sc.jet = (np.array(th.p0), th.rpm, dw) if dw and th.rpm > 0 else None
            if rows is not None and not rows[i]:
                continue
            try:
                thj = replace(th, stroke=th.stroke * float(jit[i]))
                pth: list[tuple[float, float, float, float]] | None = (
                    [] if paths is not None else None
                )
                xy[i], tl[i], vc[i] = _one(sc, ee, thj, rest=bo is not None, kick=kick, path=pth)
                if paths is not None and pth:
                    paths[i] = np.asarray(pth, float)
            except NoLanding:
                continue
    finally:
        sc.close()
    return xy, tl, vc


@dataclass(frozen=True)
class SceneCampaign:
    """A campaign of this world: log records, the world's own floor, the outlier rows.

    Attributes:
        records: one dict per logged throw (docs/throw_log.md columns).
        floor_m: the world's floor [m]: sqrt(F0² + max(0, V_effect − V_none)), F0 the RMS
            distance between the model as configured and the same throws made again in
            the scene without the effect, logged with the same scatter; V the repeats'
            pooled variance of the true logged points with and without the effect.
        floor0_m: F0 alone [m].
        repeat_sd_m: sqrt(V_effect), sqrt(V_none) [m]: what repeats scatter in the world.
        noise_m: the tracker's scatter alone (RMS 2-D distance) [m].
        outliers: row numbers (0-based, in records) of the moved landings.
        truth: quantities measured in the world itself (a bounce's slide per impact
            speed, tau_s and inv_mu), for the parameters a case expects.
        effect_m: how far the effects move the logged points [m]: the RMS 2-D distance
            between the true points with the effects (scaled by a tracker's scale) and
            the same throws without them, over the inlier rows (no tracker scatter).
        tracks: the tracker's samples of each logged flight {throw_id: (k, 4) t, x, y, z}
            (`_tracks`), or None where the campaign logs landings only.
        rows: what the floor is counted from, per record (`FloorRows`), for the floor on
            a subset of the rows (`floors`).
    """

    records: list[dict[str, Any]]
    floor_m: float
    noise_m: float
    outliers: tuple[int, ...]
    truth: dict[str, float]
    floor0_m: float = float("nan")
    repeat_sd_m: tuple[float, float] = (float("nan"), float("nan"))
    effect_m: float = float("nan")
    tracks: dict[str, np.ndarray] | None = None
    rows: FloorRows | None = None

    def floors(self, keep: np.ndarray | None = None) -> tuple[float, float]:
        """(F, F0) [m] counted on the logged rows `keep` (a mask over `records`; every row
        when None), as `floor_m` and `floor0_m` are on every row: F0 over those rows, the
        repeats' variances over the configurations with two or more of them left (a
        row left out takes its repeat out of V). An injected outlier is never counted."""
        if self.rows is None:
            raise ValueError("floors: the campaign carries no rows of its floor")
        use = ~np.isin(np.arange(len(self.records)), self.outliers)
        if keep is not None:
            use &= np.asarray(keep, bool)
        return self.rows.floors(use)


@dataclass(frozen=True)
class FloorRows:
    """A scene world's floor, per logged record: `miss_sq` [m²] the squared 2-D miss of
    the same throw made without the effect (logged with the same scatter) from the model
    as configured; `configs` its configuration (repeats share one); `with_xy`, `without_xy`
    [m] the true logged points with the effect (scaled by a tracker's scale) and without."""

    miss_sq: np.ndarray
    configs: tuple[Throw, ...]
    with_xy: np.ndarray
    without_xy: np.ndarray

    def floors(self, use: np.ndarray) -> tuple[float, float]:
        """(F, F0) [m] over the rows `use`: F² = F0² + max(0, V_effect − V_none)."""
        if not use.any():
            return float("nan"), float("nan")
        f0 = float(np.sqrt(np.mean(self.miss_sq[use])))
        cfg = list(self.configs)
        v_eff, v_none = repeat_var(cfg, self.with_xy, use), repeat_var(cfg, self.without_xy, use)
        extra = v_eff - v_none if np.isfinite(v_eff) and np.isfinite(v_none) else 0.0
        return float(np.sqrt(f0**2 + max(0.0, extra))), f0


TRACK_RATE_HZ = 100.0  # [Hz] the tracker's samples of a flight (as `cell.gap.world_tracks`)


def _tracks(paths: dict[int, np.ndarray], ok: np.ndarray, scale: float, lat: float,
            noise_m: float, seed: int) -> dict[str, np.ndarray]:  # fmt: skip
    """The tracker's samples of each logged throw's flight {throw_id: (k, 4) t [s since
    the push began], x, y, z [m]}: the scene's positions at TRACK_RATE_HZ from the release
    to the landing plane, `scale` times the true ones about the origin, `lat` late, with a
    scatter `noise_m` per axis per sample (drawn from `seed` alone)."""
    rng = np.random.default_rng([seed, 58])
    out: dict[str, np.ndarray] = {}
    for i in np.flatnonzero(ok):
        pth = paths.get(int(i))
        if pth is None:
            continue
        pth = pth[pth[:, 3] > LAND_Z_M]
        if len(pth) < 2:
            continue
        grid = np.arange(np.ceil(pth[0, 0] * TRACK_RATE_HZ), pth[-1, 0] * TRACK_RATE_HZ + 1e-9)
        k = np.searchsorted(pth[:, 0], grid / TRACK_RATE_HZ).clip(0, len(pth) - 1)
        smp = pth[np.unique(k)]
        xyz = scale * smp[:, 1:] + rng.normal(0.0, noise_m, smp[:, 1:].shape)
        out[f"s{i:04d}"] = np.c_[smp[:, 0] + lat, xyz]
    return out


def repeat_var(plan: list[Throw], xy: np.ndarray, use: np.ndarray) -> float:
    """The pooled within-configuration variance of points xy [m²] (2-D: the mean squared
    distance from the configuration's mean, unbiased, Σ(n_g − 1) degrees of freedom) over
    the rows `use`; NaN without a repeat."""
    groups: dict[Throw, list[int]] = {}
    for i in np.flatnonzero(use):
        groups.setdefault(plan[i], []).append(int(i))
    ss, dof = 0.0, 0
    for rows in groups.values():
        if len(rows) > 1:
            p = xy[rows]
            ss += float(np.sum((p - p.mean(axis=0)) ** 2))
            dof += len(rows) - 1
    return ss / dof if dof else float("nan")


def _records(plan: list[Throw], xy: np.ndarray, tl: np.ndarray, ok: np.ndarray) -> list[dict]:
    from cell.log.records import throw_record
    from cell.sim.items import resolve_object

    recs = []
    for i in np.flatnonzero(ok):
        th = plan[i]
        obj, _ = resolve_object(th.object_id)
        recs.append(throw_record(
            f"s{i:04d}", obj, stroke_m=th.stroke, position_m=th.p0,
            elevation_rad=th.elevation, azimuth_rad=th.azimuth, platform=th.platform,
            rotor_rpm=th.rpm, land_z_m=LAND_Z_M, landed_xy_m=xy[i], t_flight_s=float(tl[i]),
            session="scene",
        ))  # fmt: skip
    return recs


def _model_xy(recs: list[dict[str, Any]], params: Any) -> np.ndarray:
    """The configured model's landings of logged throws (the floor's reference)."""
    from cell.log.table import ThrowTable
    from cell.model.throw import predict_landing

    batch = ThrowTable.from_records(recs).to_batch(objects=params.objects)
    return np.asarray(predict_landing(batch, params.ee).xy, float)


def _untouched(plan: list[Throw], effects: list[dict[str, Any]]) -> np.ndarray:
    """The throws (mask) that no effect acts on in the scene: with a downwash and a
    tracker alone, the arm's throws (no rotor); with a tracker alone, every throw."""
    kinds = {e["kind"] for e in effects}
    if not kinds <= {"downwash", "tracker"}:
        return np.zeros(len(plan), bool)
    if "downwash" in kinds:
        return np.array([t.rpm <= 0 for t in plan], bool)
    return np.ones(len(plan), bool)


def draw_scene_campaign(effects: list[dict[str, Any]], rng: np.random.Generator, params: Any,
                        *, n: int = 160, noise_m: float = 0.025, outliers: float = 0.0,
                        repeats: int = 2, drone_share: float = 0.0,
                        objects: tuple[str, ...] | None = None,
                        track_noise_m: float | None = None) -> SceneCampaign:  # fmt: skip
    """Throw a campaign in the scene with `effects` on (see the module table), and the same
    throws without them for the floor. `params` is the model as configured
    (`cell.params.ModelParams`). With `track_noise_m` [m] the campaign also logs the
    tracker's samples of every flight (`SceneCampaign.tracks`, `_tracks`); without it, none
    (the scene check's campaigns log landings only)."""
    plan = draw_plan(n, rng, repeats=repeats, drone_share=drone_share, objects=objects)
    seed = int(rng.integers(2**31))
    paths: dict[int, np.ndarray] | None = {} if track_noise_m is not None else None
    xy, tl, vc = throw_plan(plan, effects, seed, paths=paths)
    # a throw no effect acts on in the scene (a jet on an arm's throw; a tracker acts on
    # the logged points only) is the same throw without the effects: thrown once (PyBullet
    # repeats a throw to the bit, wherever it comes in a scene's sequence)
    same = _untouched(plan, effects)
    xy0, tl0, vc0 = throw_plan(plan, [], seed, rows=~same)
    xy0[same], tl0[same], vc0[same] = xy[same], tl[same], vc[same]
    truth: dict[str, float] = {}
    if _find(effects, "bounce"):
        # the slide from where the item crosses the plane in the same air (the effects
        # without the floor's contact) to where it rests
        air = [e for e in effects if e["kind"] not in ("bounce", "tracker")]
        xyc, _, vcc = throw_plan(plan, air, seed) if air else (xy0, tl0, vc0)
        sizes, balls = extents_and_balls([th.object_id for th in plan])
        truth = slide_truth(xy, xyc, vcc, sizes, balls, LAND_Z_M)
    tr = _find(effects, "tracker")
    scale = float(tr["scale"]) if tr else 1.0
    lat = float(tr.get("latency_s", 0.0)) if tr else 0.0
    noise = rng.normal(0.0, noise_m, (len(plan), 2))
    obs = scale * xy + noise
    ok = np.all(np.isfinite(obs), axis=1) & np.all(np.isfinite(xy0), axis=1)
    out = np.zeros(len(plan), bool)
    if outliers > 0:
        pick = rng.choice(np.flatnonzero(ok), int(round(outliers * ok.sum())), replace=False)
        ang = rng.uniform(-np.pi, np.pi, pick.size)
        obs[pick] += rng.uniform(0.3, 1.0, pick.size)[:, None] * np.c_[np.cos(ang), np.sin(ang)]
        out[pick] = True
    recs = _records(plan, obs, tl + lat, ok)
    free = _records(plan, xy0 + noise, tl0, ok)
    inl = ~out[ok]
    d = xy0[ok] + noise[ok] - _model_xy(free, params)
    rows = FloorRows(miss_sq=np.sum(d * d, axis=1), configs=tuple(plan[i] for i in np.flatnonzero(ok)),
                     with_xy=(scale * xy)[ok], without_xy=xy0[ok])  # fmt: skip
    floor, f0 = rows.floors(inl)
    use = ok & ~out
    v_eff, v_none = repeat_var(plan, scale * xy, use), repeat_var(plan, xy0, use)
    moved = (scale * xy - xy0)[use]
    return SceneCampaign(
        records=recs,
        floor_m=floor,
        noise_m=float(np.sqrt(np.mean(np.sum(noise[ok] ** 2, axis=1)))),
        outliers=tuple(int(k) for k in np.flatnonzero(out[ok])),
        truth=truth,
        floor0_m=f0,
        repeat_sd_m=(float(np.sqrt(v_eff)), float(np.sqrt(v_none))),
        effect_m=float(np.sqrt(np.mean(np.sum(moved**2, axis=1)))),
        tracks=(
            _tracks(paths, ok, scale, lat, track_noise_m, seed)
            if paths is not None and track_noise_m is not None
            else None
        ),
        rows=rows,
    )


def matched_objects(params: Any, tol: float = 0.1) -> tuple[str, ...]:
    """The thesis14 objects whose drag constant under the configured parameters (its
    identified mass and size, `params.objects`) is within `tol` of the scene's own
    (the catalogue's): the objects a flight effect can be measured on without the
    configured model's own drag error scaling it."""
    from cell.sim.items import resolve_object

    out = []
    for k, e in sorted(catalogue().items()):
        if e.set != "thesis14" or k not in params.objects:
            continue
        true, _ = resolve_object(k)
        conf = params.objects[k]
        ratio = (conf.cd * conf.area / conf.mass) / (true.cd * true.area / true.mass)
        if abs(ratio - 1.0) <= tol:
            out.append(k)
    return tuple(out)
