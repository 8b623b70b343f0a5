"""`cell gap check --worlds scene`: the diagnosis on campaigns thrown in the PyBullet scene
with each effect applied physically (`cell.gap.world_scene`).

Each case is a world (effects as forces, contacts or a tracker), the verdict it should get,
the phase of each effect and the parameters the diagnosis should find. The model as
configured is the scene's calibrated parameter file (robots/cell_scene/ee_params.yaml, its
identified objects and its validation on held-out throws included). A bounce's parameter is the one measured in the world
(the slide from the crossing to the rest point per impact speed), compared in the law the
tool chose. Judged as `cell.gap.check_other` judges (`judge_campaign`): diagonal, phase,
parameters within 30 % (a scale within 0.5 %), robust held-out RMSE within 1.3 × the
world's own floor (the same throws without the effect, against the configured model,
with the scatter the effect itself adds between repeats: `cell.gap.world_scene`) counted
on the rows that RMSE was counted on (a flagged row and its repeat's share of the repeats'
scatter out; an injected outlier never counted).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from cell.gap.check_other import judge_campaign, kept_rows
from cell.gap.world_scene import draw_scene_campaign, matched_objects

__all__ = ["SCENE_CASES", "FAST_SCENE", "scene_cases", "check_scene_case", "run_scene_check"]

_PER_OBJ_CD = {"cube30": 2.6, "cube40": 2.2, "cube50": 1.8, "cube60": 1.6, "cuboid_a": 2.0,
               "cuboid_b": 2.4, "cuboid_c": 1.5, "cyl40": 2.8, "cyl50": 2.3, "cyl60": 1.9,
               "cyl70": 1.6, "sphere40": 3.0, "sphere55": 2.5, "sphere70": 2.0}  # fmt: skip


def _e(kind: str, form: str = "const", **kw: Any) -> dict[str, Any]:
    return {"kind": kind, "form": form, **kw}


FLIGHT_KINDS = ("wind", "drag_scale", "downwash", "side_force")
_JET: dict[str, Any] = {"w_mps": 9.0, "radius_m": 0.25, "core_m": 0.8}
# a jet wide and strong enough to move the drone throws' landings by about 2 floors
_JET_STRONG: dict[str, Any] = {"w_mps": 15.0, "radius_m": 1.5, "core_m": 2.0}
_SLIDE = {
    "one_of": [
        {"tau_s": "measured"},
        {"inv_mu": "measured"},
        {"inv_mu_imp": "measured"},
        {"inv_mu_drop": "measured", "depth_m": "measured"},
        {"inv_mu_r_per_m": "measured"},
    ]
}
W, B = "wind", "bounce"
_BLOCKS = ("cube30", "cube40", "cube50", "cube60", "cuboid_a", "cuboid_b", "cuboid_c")
_BALLS = ("sphere40", "sphere55", "sphere70")
TS, DS = "tracking_scale", "drag_scale"
_HOP = _e(B, "contact", restitution=0.6, friction=1.0, rolling_m=0.05)
_OUT = {"outliers": 0.05}

# name -> (effects, truth, {effect: phase}, {effect: {param: value}}, options)
SCENE_CASES: dict[
    str, tuple[list[dict[str, Any]], str, dict[str, str], dict[str, Any], dict[str, Any]]
] = {  # fmt: skip
    "s:none": ([], "none", {}, {}, {}),
    "s:none+outliers": ([], "none", {}, {}, {"outliers": 0.05}),
    "s:wind": (
        [_e(W, x_mps=2.5, y_mps=-1.2)],
        W,
        {W: "flight"},
        {W: {"x_mps": 2.5, "y_mps": -1.2}},
        {},
    ),  # fmt: skip
    "s:wind-all-objects": (
        [_e(W, x_mps=2.5, y_mps=-1.2)],
        W,
        {W: "flight"},
        {W: {"x_mps": 2.5, "y_mps": -1.2}},
        {"all_objects": True},
    ),
    "s:wind-throw": (
        [_e(W, "throw", x_mps=-1.5, y_mps=2.0, sd=0.5)],
        W,
        {W: "flight"},
        {W: {"x_mps": -1.5, "y_mps": 2.0}},
        {},
    ),  # fmt: skip
    "s:wind+outliers": (
        [_e(W, x_mps=-2.0, y_mps=-2.0)],
        W,
        {W: "flight"},
        {W: {"x_mps": -2.0, "y_mps": -2.0}},
        {"outliers": 0.05},
    ),  # fmt: skip
    "s:drag-const": (
        [_e("drag_scale", value=2.5)],
        "drag_scale",
        {"drag_scale": "flight"},
        {"drag_scale": {"factor": 2.5}},
        {},
    ),  # fmt: skip
    "s:drag-object": (
        [_e("drag_scale", "object", value=2.0, per_object=_PER_OBJ_CD)],
        "drag_scale",
        {"drag_scale": "flight"},
        {},
        {},
    ),  # fmt: skip
    # the narrow jet is in these two worlds but moves no landing: the throws leave it
    # (0.25 m wide at the rotor) soon after release, and it moves the logged points by
    # 0.2 mm RMS alone and 0.7 mm beside the wind (measured: the same throws with and
    # without it; the row's `world_effect_m`), against a tracker scatter of 25 mm. What
    # the campaign shows is `none` and `wind` (tests/test_gap_jet.py)
    "s:downwash": (
        [_e("downwash", **_JET)],
        "none",
        {},
        {},
        {"drone_share": 0.6},
    ),  # fmt: skip
    "s:downwash+wind": (
        [_e("downwash", **_JET), _e(W, x_mps=2.0, y_mps=1.0)],
        W,
        {W: "flight"},
        {W: {"x_mps": 2.0, "y_mps": 1.0}},
        {"drone_share": 0.6},
    ),  # fmt: skip
    "s:bounce-slide": (
        [_e(B, "contact", restitution=0.05, friction=1.0)],
        B,
        {B: "landing"},
        {B: _SLIDE},
        {"objects": _BLOCKS},
    ),  # fmt: skip
    "s:bounce-roll": (
        [_e(B, "contact", restitution=0.05, friction=1.0, rolling_m=0.05)],
        B,
        {B: "landing"},
        {B: _SLIDE},
        {"objects": _BALLS},
    ),  # fmt: skip
    "s:bounce-hop": (
        [_e(B, "contact", restitution=0.6, friction=1.0, rolling_m=0.05)],
        B,
        {B: "landing"},
        {B: _SLIDE},
        {},
    ),  # fmt: skip
    "s:wind+bounce": (
        [
            _e(W, x_mps=2.0, y_mps=-1.5),
            _e(B, "contact", restitution=0.05, friction=1.0, rolling_m=0.05),
        ],
        "bounce+wind",
        {W: "flight", B: "landing"},
        {W: {"x_mps": 2.0, "y_mps": -1.5}, B: _SLIDE},
        {},
    ),  # fmt: skip
    "s:scale": (
        [_e("tracker", scale=1.03)],
        "tracking_scale",
        {"tracking_scale": "measurement"},
        {"tracking_scale": {"scale_factor": 1.03}},
        {},
    ),  # fmt: skip
    "s:scale+latency": (
        [_e("tracker", scale=0.97, latency_s=0.03)],
        "tracking_scale",
        {"tracking_scale": "measurement"},
        {"tracking_scale": {"scale_factor": 0.97}},
        {},
    ),  # fmt: skip
    "s:side-force": ([_e("side_force", x_mps2=0.0, y_mps2=0.8)], "unknown", {}, {}, {}),
    # more laws per effect, each a sibling of a case above with other values
    "s:wind-low": ([_e(W, x_mps=1.0, y_mps=0.5)], W, {W: "flight"}, {W: {"x_mps": 1.0, "y_mps": 0.5}}, {}),
    "s:wind-y": ([_e(W, x_mps=0.0, y_mps=3.0)], W, {W: "flight"}, {W: {"y_mps": 3.0}}, {}),
    "s:wind-throw-wide": ([_e(W, "throw", x_mps=2.0, y_mps=0.0, sd=1.0)], W, {W: "flight"},
                          {W: {"x_mps": 2.0}}, {}),
    "s:drag-low": ([_e(DS, value=0.4)], DS, {DS: "flight"}, {DS: {"factor": 0.4}}, {}),
    "s:drag-high": ([_e(DS, value=1.8)], DS, {DS: "flight"}, {DS: {"factor": 1.8}}, {}),
    "s:drag-stroke": ([_e(DS, "stroke", k=30.0)], DS, {DS: "flight"}, {DS: {"k": 30.0}}, {}),
    "s:downwash-strong": ([_e("downwash", **_JET_STRONG)], "downwash", {"downwash": "flight"}, {},
                          {"drone_share": 0.6}),
    "s:none-drone": ([], "none", {}, {}, {"drone_share": 0.6}),
    "s:bounce-hop-mu05": ([_e(B, "contact", restitution=0.6, friction=0.5, rolling_m=0.05)], B,
                          {B: "landing"}, {B: _SLIDE}, {}),
    "s:bounce-roll-one": ([_e(B, "contact", restitution=0.05, friction=1.0, rolling_m=0.05)], B,
                          {B: "landing"}, {B: _SLIDE}, {"objects": ("sphere55",)}),
    "s:bounce-slide-mu03": ([_e(B, "contact", restitution=0.05, friction=0.3)], B,
                            {B: "landing"}, {B: _SLIDE}, {"objects": _BLOCKS}),
    "s:scale-1.02": ([_e("tracker", scale=1.02)], TS, {TS: "measurement"},
                     {TS: {"scale_factor": 1.02}}, {}),
    "s:scale-0.98": ([_e("tracker", scale=0.98)], TS, {TS: "measurement"},
                     {TS: {"scale_factor": 0.98}}, {}),
    "s:latency": ([_e("tracker", scale=1.0, latency_s=0.05)], "none", {}, {}, {}),
    # outliers with each effect
    "s:drag+outliers": ([_e(DS, value=1.8)], DS, {DS: "flight"}, {DS: {"factor": 1.8}}, _OUT),
    "s:scale+outliers": ([_e("tracker", scale=1.02)], TS, {TS: "measurement"},
                         {TS: {"scale_factor": 1.02}}, _OUT),
    "s:bounce-hop+outliers": ([_HOP], B, {B: "landing"}, {B: _SLIDE}, _OUT),
    # compounds across phases
    "s:wind+scale": ([_e(W, x_mps=2.0, y_mps=-1.0), _e("tracker", scale=1.02)], f"{TS}+{W}",
                     {W: "flight", TS: "measurement"},
                     {W: {"x_mps": 2.0, "y_mps": -1.0}, TS: {"scale_factor": 1.02}}, {}),
    "s:wind+hop": ([_e(W, x_mps=2.0, y_mps=-1.5), _HOP], f"{B}+{W}", {W: "flight", B: "landing"},
                   {W: {"x_mps": 2.0, "y_mps": -1.5}, B: _SLIDE}, {}),
    "s:drag+hop": ([_e(DS, value=1.8), _HOP], f"{B}+{DS}", {DS: "flight", B: "landing"},
                   {DS: {"factor": 1.8}, B: _SLIDE}, {}),
    "s:scale+hop": ([_e("tracker", scale=1.02), _HOP], f"{B}+{TS}",
                    {B: "landing", TS: "measurement"}, {TS: {"scale_factor": 1.02}, B: _SLIDE}, {}),
    "s:downwash-strong+wind": ([_e("downwash", **_JET_STRONG), _e(W, x_mps=2.0, y_mps=1.0)],
                               "downwash+wind", {"downwash": "flight", W: "flight"},
                               {W: {"x_mps": 2.0, "y_mps": 1.0}}, {"drone_share": 0.6}),
    # outside the vocabulary
    "s:side-force-x": ([_e("side_force", x_mps2=-0.6, y_mps2=0.0)], "unknown", {}, {}, {}),
    "s:launch-yaw-stroke": ([_e("launch", "stroke", yaw_k=1.0)], "unknown", {}, {}, {}),
    "s:launch-speed-stroke": ([_e("launch", "stroke", speed_k=0.8)], "unknown", {}, {}, {}),
    # no effect, thrown with the flight cases' objects (`matched_objects`): their
    # configurations miss the configured model by more than the tracker's scatter
    "s:none-cubes": ([], "none", {}, {}, {"matched": True}),
    # the drag factor drawn for each throw (drawn after the others: their rows keep their seeds)
    "s:drag-throw": ([_e(DS, "throw", value=1.8, sd=0.3)], DS, {DS: "flight"},
                     {DS: {"factor": 1.8}}, {}),
    # balls on a hard floor, whose rolling friction lets them roll (Bullet's μ_r = 0.01 m ·
    # 0.7 + 0.0005 m · 1.0 = 0.0075 m, below μ r = 0.7 r for every ball: 0.014-0.0245 m)
    # (drawn last: every other row keeps its seeds)
    "s:bounce-roll-hard": ([_e(B, "contact", restitution=0.05, friction=1.0, rolling_m=0.01)], B,
                           {B: "landing"}, {B: _SLIDE}, {"objects": _BALLS}),
}  # fmt: skip
FAST_SCENE = ("s:wind", "s:none")


def scene_cases(names: tuple[str, ...] | None = None, *, n: int = 80, seed: int = 0
                ) -> list[dict[str, Any]]:  # fmt: skip
    """The cases as plain dicts (each with its own world seed)."""
    rng = np.random.default_rng(seed + 5757)
    # seeds drawn over every case in table order: a case named alone is the table's row
    seeds = {name: (int(rng.integers(2**31)), seed + i) for i, name in enumerate(SCENE_CASES)}
    out = []
    for name in names or tuple(SCENE_CASES):
        effects, truth, phases, expect, opts = SCENE_CASES[name]
        world_seed, case_seed = seeds[name]
        out.append({"name": name, "n": n, "world_seed": world_seed,
                    "seed": case_seed, "effects": effects, "truth": truth, "phases": phases,
                    "expect": expect, "options": opts})  # fmt: skip
    return out


def _measured(expect: dict[str, Any], truth: dict[str, float]) -> dict[str, Any]:
    """The case's expectations with the world's measured values put in."""
    out: dict[str, Any] = {}
    for eff, ps in expect.items():
        if "one_of" in ps:
            # a law the world could not measure (the roll law without a ball) is left out
            alts = [alt for alt in ps["one_of"] if all(k in truth for k in alt)]
            ps = {"one_of": [{k: truth[k] for k in alt} for alt in alts]}
        out[eff] = ps
    return out


def check_scene_case(case: dict[str, Any]) -> dict[str, Any]:
    """Throw one case's campaign in the scene, diagnose it blind, judge it; the row also
    carries the world's measured truth and its tracker scatter."""
    from cell.errors import MissingDependency
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    if path is None:
        raise MissingDependency("robots/cell_scene/ee_params.yaml: the scene's parameters")
    mp = load_params(path)
    rng = np.random.default_rng(case["world_seed"])
    opts = dict(case["options"])
    flight = any(e["kind"] in FLIGHT_KINDS for e in case["effects"])
    objects: tuple[str, ...] | None = opts.pop("objects", None)
    every = opts.pop("all_objects", False)
    if (opts.pop("matched", False) or flight) and not every:
        objects = matched_objects(mp)
    camp = draw_scene_campaign(case["effects"], rng, mp, n=case["n"], objects=objects, **opts)
    judged = {**case, "expect": _measured(case["expect"], camp.truth)}
    row = judge_campaign(judged, camp.records, lambda keep: camp.floors(keep)[0],
                         camp.outliers, ee=mp.ee, objects=mp.objects,
                         validation=mp.validation, tracks=camp.tracks)  # fmt: skip
    kept0 = camp.floors(kept_rows(len(camp.records), row["outlier_rows"]))[1]
    return {**row, "world_truth": camp.truth, "tracker_noise_m": camp.noise_m,
            "world_floor0_m": camp.floor0_m, "world_floor0_kept_m": kept0,
            "world_repeat_sd_m": list(camp.repeat_sd_m),
            "world_effect_m": camp.effect_m,
            "throws": len(camp.records), "objects": list(objects or ["thesis14"])}  # fmt: skip


def run_scene_check(
    names: tuple[str, ...] | None = None,
    *,
    n: int = 80,
    seed: int = 0,
    workers: int = 1,
    address: str | None = None,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> list[dict[str, Any]]:
    """Every case (or `names`) thrown, diagnosed blind and judged; one row per case (the
    same rows serially or on Ray: each case carries its own seeds). `on_row` is called
    with each row as it arrives."""
    from cell.parallel import run_campaign

    def done(i: int, row: dict[str, Any]) -> None:
        if on_row is not None:
            on_row(row)

    return list(
        run_campaign(check_scene_case, scene_cases(names, n=n, seed=seed), workers=workers,
                     address=address, desc="cell gap check --worlds scene", on_result=done,
                     progress=False)
    )  # fmt: skip
