"""Issue 57 (worlds side): campaigns thrown in the PyBullet scene with the effect applied
physically (`cell.gap.world_scene`), diagnosed blind by `cell gap`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.gap.world_scene import EffectScene, draw_scene_campaign, matched_objects
from tests.source_imports import imported_modules

pytest.importorskip("pybullet")


def test_scene_world_shares_nothing_with_the_fit():
    mods = imported_modules(Path(__file__).parents[1] / "cell" / "gap" / "world_scene.py")
    assert not [m for m in mods if m.startswith(("cell.gap", "cell.model.effects"))], mods


def test_wind_side_force_and_floor_act_as_the_closed_forms_say():
    """An item at rest in weightless air with a wind w along x: dv/dt = (c/m)(w − v)², so
    v(t) = w − w / (1 + (c/m) w t); a side force alone: v = a t."""
    sc = EffectScene()
    try:
        sc.client.setGravity(0, 0, 0)
        item = sc.spawn_item("cube50", position=(0.0, 0.0, 2.0))
        obj = item.obj
        c = 0.5 * 1.225 * obj.cd * obj.area  # [kg/m]
        w = 3.0
        sc.wind = np.array([w, 0.0, 0.0])
        sc.drag_factor = 2.0
        sc.run_for(0.3)
        vx = sc.item_velocity(item)[0][0]
        k = 2.0 * c / obj.mass
        assert vx == pytest.approx(w - w / (1 + k * w * sc.t), rel=2e-3)
        sc.wind[:] = 0.0
        sc.remove_item(item)
        item = sc.spawn_item("sphere40", position=(0.0, 0.0, 2.0))
        sc.side_mps2 = np.array([0.0, 0.5, 0.0])
        t0 = sc.t
        sc.run_for(0.2)
        assert sc.item_velocity(item)[0][1] == pytest.approx(0.5 * (sc.t - t0), rel=2e-3)
        sc.set_floor(0.6, 0.3)
        info = sc.client.getDynamicsInfo(sc.floor, -1)
        assert (info[1], info[5]) == pytest.approx((0.3, 0.6))  # friction, restitution
    finally:
        sc.close()


def test_strong_wind_in_the_scene_is_named_wind_in_flight():
    """A 2.8 m/s wind acting as a force on the flying items is named `wind`, phase flight,
    its speed within 30 %. The objects are those whose calibrated drag constant is within
    25 % of the scene's (the parameter file's identified masses are launch-effective ones:
    for the heavy objects its drag constant is up to 2.1 × the scene's, see
    docs/gap_scene.md). 48 throws (80 before: 7.3 -> 4.7 CPU-s, the scene's throws 74 ms
    each): the speed 16 % off, A 0.94 × the floor (campaign seeds 0-2: 11-16 %, ≤ 1.01)."""
    from cell.gap.run import diagnose_log
    from cell.log.table import ThrowTable
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    assert path is not None
    mp = load_params(path)
    camp = draw_scene_campaign(
        [{"kind": "wind", "form": "const", "x_mps": 2.0, "y_mps": -2.0}],
        np.random.default_rng(11),
        mp,
        n=48,
        objects=matched_objects(mp),
    )
    d, _ = diagnose_log(ThrowTable.from_records(camp.records), mp.ee, objects=mp.objects)
    v = d.report["verdict"]
    assert v["effects"] == ["wind"], d.report["candidates"][:2]
    assert v["phases"] == {"wind": "flight"}
    got = np.hypot(v["params"]["wind"]["x_mps"], v["params"]["wind"]["y_mps"])
    assert got == pytest.approx(np.hypot(2.0, 2.0), rel=0.3)
    assert v["heldout_rmse_robust_m"] <= 1.3 * camp.floor_m


def test_scene_cases_cover_the_brief():
    from cell.cli import main
    from cell.gap.check_scene import SCENE_CASES, scene_cases

    cases = scene_cases()
    assert len(cases) >= 12
    kinds = {e["kind"] for c in cases for e in c["effects"]}
    assert kinds >= {"wind", "drag_scale", "downwash", "bounce", "tracker", "side_force"}
    for kind in ("wind", "drag_scale", "bounce", "tracker"):  # ≥ 2 laws or sizes each
        laws = {(e["form"], tuple(sorted((k, str(v)) for k, v in e.items())))
                for c in cases for e in c["effects"] if e["kind"] == kind}  # fmt: skip
        assert len(laws) >= 2, kind
    assert {e["form"] for c in cases for e in c["effects"]} >= {"throw", "object"}
    assert sum("+" in c["truth"] for c in cases) >= 2
    assert sum(c["options"].get("outliers", 0) > 0 for c in cases) >= 2
    assert any(c["truth"] == "unknown" for c in cases)
    assert "s:wind" in SCENE_CASES
    assert main(["gap", "check", "--worlds", "scene", "--truths", "s:gremlins"]) == 2


def _batch(objects: tuple[str, ...]):  # type: ignore[no-untyped-def]
    from cell.log.records import throw_record
    from cell.log.table import ThrowTable
    from cell.sim.items import resolve_object

    recs = []
    for i in range(12):
        obj, _ = resolve_object(objects[i % len(objects)])
        recs.append(throw_record(
            f"t{i}", obj, stroke_m=0.04 + 0.005 * i, position_m=(0.0, 0.0, 0.7),
            elevation_rad=0.5, azimuth_rad=0.0, land_z_m=0.1, landed_xy_m=(1.0, 0.0),
            t_flight_s=0.5,
        ))  # fmt: skip
    return ThrowTable.from_records(recs).to_batch()


def test_a_law_in_mass_or_size_needs_three_values_of_it():
    """With two objects, a law in the mass, one in the size and one per object are the same
    two numbers: only the stroke (12 values) is offered as a covariate; with three objects
    the mass and size are too."""
    from cell.gap.laws import MIN_LEVELS, law_forms, levels
    from cell.model.effects import DragScale

    two, three = _batch(("cube30", "sphere40")), _batch(("cube30", "sphere40", "cube50"))
    assert MIN_LEVELS == 3
    assert [levels(two, c) for c in ("stroke_m", "mass_kg", "size_x_m")] == [12, 2, 2]
    assert {f.covariate for f in law_forms(DragScale, two)} == {"stroke_m"}  # type: ignore[attr-defined]
    got = {f.covariate for f in law_forms(DragScale, three)}  # type: ignore[attr-defined]
    assert got == {"stroke_m", "mass_kg", "size_x_m"}
    assert len(law_forms(DragScale)) == 6  # without a batch: every form


def test_a_constant_told_per_object_is_judged_object_by_object():
    """A world's constant factor found as a per-object law passes when every object's value
    is within 30 % of it, and fails when one is not (the scene's s:drag-const)."""
    from cell.gap.check_other import _params_ok

    expect = {"drag_scale": {"factor": 2.5}}
    law = {"common": 2.78, "spread": 0.3, "per_object": {"cube30": 2.73, "sphere40": 3.16}}
    ok, errs = _params_ok(expect, {"drag_scale": law})
    assert ok and errs["drag_scale.factor"] == pytest.approx(0.66 / 2.5)
    law["per_object"]["sphere40"] = 3.3
    assert not _params_ok(expect, {"drag_scale": law})[0]
    assert not _params_ok(expect, {"drag_scale": {"k": 82.0}})[0]  # a law in a covariate


def test_a_bounce_told_by_a_law_is_judged_by_its_mean_over_the_log():
    """A bounce's slide is measured in the world as one constant over the log (`one_of`);
    a law in the size is judged by the value it gives averaged over the log's throws (the
    report's `law_mean`), under the parameter the law is of. A world's own constant (not
    measured) is not judged that way."""
    from cell.gap.check_other import _params_ok

    expect = {"bounce": {"one_of": [{"tau_s": 0.05}, {"inv_mu": 0.15}]}}
    got = {"bounce": {"k": 2.6}}
    assert not _params_ok(expect, got)[0]  # without the law's mean: nothing to compare
    ok, errs = _params_ok(expect, got, {"bounce": {"inv_mu": 0.16}})
    assert ok and errs == {"bounce.inv_mu": pytest.approx(0.01 / 0.15)}
    assert not _params_ok(expect, got, {"bounce": {"inv_mu": 0.2}})[0]  # 33 % off
    assert not _params_ok(expect, got, {"bounce": {"tau_s": 0.2}})[0]  # the other law, 4 × off
    const = {"drag_scale": {"factor": 2.5}}
    assert not _params_ok(const, {"drag_scale": {"k": 82.0}}, {"drag_scale": {"factor": 2.5}})[0]


def test_a_case_named_alone_is_its_table_row():
    """`--truths` reruns a row of the table: a case's seeds do not depend on which cases
    run with it (they were drawn in the order of the cases asked for)."""
    from cell.gap.check_other import other_cases
    from cell.gap.check_scene import scene_cases

    for every, alone in ((scene_cases, ("s:wind-y", "s:drag-low")),
                         (other_cases, ("o:wind", "o:side-force"))):  # fmt: skip
        table = {c["name"]: c for c in every()}
        for c in every(alone):
            assert (c["world_seed"], c["seed"]) == (
                table[c["name"]]["world_seed"], table[c["name"]]["seed"])  # fmt: skip
        assert len({c["world_seed"] for c in table.values()}) == len(table)


def test_repeat_variance_is_the_pooled_spread_about_each_configuration():
    """Two configurations thrown twice and three times: Σ|x − mean_g|² / Σ(n_g − 1), by
    hand: (2 · 0.1² + 0.1² + 0.1²) / (1 + 2) = 0.04 / 3."""
    from cell.gap.world_scene import draw_plan, repeat_var

    a, b = draw_plan(2, np.random.default_rng(0), repeats=1)
    plan = [a, b, a, b, b]
    xy = np.array([[1.0, 0.0], [2.0, 2.1], [1.2, 0.0], [2.0, 2.0], [2.0, 1.9]])
    assert repeat_var(plan, xy, np.ones(5, bool)) == pytest.approx(0.04 / 3)
    # a configuration without its repeat (row 3 left out) adds nothing
    use = np.array([True, True, False, True, True])
    assert repeat_var(plan, xy, use) == pytest.approx(0.02 / 2)
    assert np.isnan(repeat_var(plan, xy, np.array([True, True, False, False, False])))


def test_a_tumbling_block_scatters_between_repeats_the_launch_barely_does():
    """PyBullet repeats a throw to the bit; the world's launcher does not (stroke jitter
    0.1 %). Blocks on a floor of μ 1.0 come to rest far apart on repeats whose crossings
    of the landing plane differ by millimetres: the bounce's scatter is chaotic, and the
    world's floor of a bounce (F² = F0² + max(0, V_effect − V_none)) contains it."""
    from cell.gap.world_scene import draw_plan, repeat_var, throw_plan

    bounce = [{"kind": "bounce", "form": "contact", "restitution": 0.05, "friction": 1.0}]
    plan = draw_plan(16, np.random.default_rng(3), repeats=4, objects=("cube30", "cube50"))
    same, _, _ = throw_plan(plan, bounce, 5, jitter_rel=0.0)
    assert repeat_var(plan, same, np.ones(len(plan), bool)) == 0.0  # repeats in one scene
    # and in a fresh scene, drawn from another seed: each configuration thrown once more
    first = np.array([plan.index(t) == i for i, t in enumerate(plan)])
    assert first.sum() == 4
    again, _, _ = throw_plan(plan, bounce, 6, jitter_rel=0.0, rows=first)
    assert np.array_equal(same[first], again[first])  # the same throws, to the bit
    rest, _, _ = throw_plan(plan, bounce, 5)
    cross, _, _ = throw_plan(plan, [], 5)
    use = np.all(np.isfinite(rest), axis=1) & np.all(np.isfinite(cross), axis=1)
    sd_rest = np.sqrt(repeat_var(plan, rest, use))
    sd_cross = np.sqrt(repeat_var(plan, cross, use))
    assert sd_cross < 0.005  # [m] the jitter's own scatter: a few mm
    assert sd_rest > 0.02 and sd_rest > 5 * sd_cross, (sd_rest, sd_cross)


def test_the_repeats_tool_refuses_what_it_cannot_measure(capsys: pytest.CaptureFixture) -> None:
    """`python -m cell.gap.scene_repeats`: an unknown case, a case without a bounce or a
    jitter out of range is a `cell: error:` line and exit 2, before any throw."""
    from cell.gap.scene_repeats import main

    assert main(["s:gremlins"]) == 2
    assert main(["s:bounce-slide", "--jitter", "0.5"]) == 2
    assert main(["s:bounce-slide", "--jitters", "a,b"]) == 2
    assert main(["s:wind"]) == 2
    err = capsys.readouterr().err
    assert err.count("cell: error:") == 4 and "not a case with a bounce" in err


def test_the_null_case_on_cubes_throws_the_flight_cases_objects(monkeypatch):
    """`s:none-cubes` has no effect, yet throws the objects the flight cases throw (their
    configurations miss the configured model by more than the tracker's scatter), and the
    campaign is drawn without any option of its own."""
    import cell.gap.check_scene as cs
    from cell.params import load_params, scene_params_path

    seen: list[tuple] = []

    def draw(effects, rng, mp, *, n, objects=None, **opts):  # type: ignore[no-untyped-def]
        seen.append((objects, opts))
        raise RuntimeError("drawn")

    monkeypatch.setattr(cs, "draw_scene_campaign", draw)
    for name in ("s:none-cubes", "s:wind", "s:none"):
        with pytest.raises(RuntimeError, match="drawn"):
            cs.check_scene_case(cs.scene_cases((name,))[0])
    matched = cs.matched_objects(load_params(scene_params_path()))
    assert matched and seen == [(matched, {}), (matched, {}), (None, {})]


def test_a_scene_throw_logs_the_crossing_and_the_rest_of_its_own_track(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """What `throw_plan` logs, against each item's track recorded after every physics step
    by a scene of its own: the crossing of the landing plane going down interpolated by
    `cell.sim.settle.crossing` and the velocity on the step after it; with a bounce, the
    position on the last step, reached once the item was slower than REST_SPEED for
    REST_STEPS steps after the crossing (or REST_WAIT_S after it)."""
    import cell.gap.world_scene as ws
    from cell.sim.settle import crossing

    tracks: list[tuple[int, list[tuple[float, ...]]]] = []

    class Recording(ws.EffectScene):
        def spawn_item(self, *args, **kwargs):  # type: ignore[no-untyped-def]
            item = super().spawn_item(*args, **kwargs)
            tracks.append((item.body, []))
            return item

        def step(self, n: int = 1) -> None:
            super().step(n)
            body, track = tracks[-1]
            if any(it.body == body for it in self.items):
                p, _ = self.client.getBasePositionAndOrientation(body)
                v, _ = self.client.getBaseVelocity(body)
                track.append((self.t, *p, *v))

    monkeypatch.setattr(ws, "EffectScene", Recording)
    plan = ws.draw_plan(2, np.random.default_rng(5), repeats=1, objects=("cube30",))
    wind = {"kind": "wind", "form": "const", "x_mps": 1.0, "y_mps": -0.5}
    bounce = {"kind": "bounce", "form": "contact", "restitution": 0.3, "friction": 0.4}
    for effects in ([wind], [wind, bounce]):
        tracks.clear()
        xy, _, vc = ws.throw_plan(plan, effects, 3)
        assert len(tracks) == len(plan)
        for i, (_, track) in enumerate(tracks):
            a = np.array(track)
            x, y, t = crossing(a[:, :4], ws.LAND_Z_M)
            k = int(np.searchsorted(a[:, 0], t))  # the step after the crossing
            assert a[k - 1, 3] > ws.LAND_Z_M >= a[k, 3]
            np.testing.assert_array_equal(vc[i], a[k, 4:7])
            if len(effects) == 1:
                assert xy[i] == pytest.approx([x, y], abs=1e-12)
                assert len(a) == k + 1  # the flight stopped at the crossing
                continue
            np.testing.assert_array_equal(xy[i], a[-1, 1:3])
            slow = np.linalg.norm(a[k:, 4:7], axis=1) < ws.REST_SPEED
            waited = a[-1, 0] - t > ws.REST_WAIT_S - 2e-3
            assert waited or (slow[-ws.REST_STEPS :].all() and len(slow) >= ws.REST_STEPS)
            assert len(a) > k + ws.REST_STEPS - 1


def _median_gravity(camp) -> float:  # type: ignore[no-untyped-def]
    """The median apparent gravity / G of a campaign's tracks (`cell.gap.tracks`)."""
    from cell.gap.run import _k_of
    from cell.gap.tracks import fit_tracks
    from cell.log.table import ThrowTable

    table = ThrowTable.from_records(camp.records)
    fit = fit_tracks(table.text("throw_id"), camp.tracks, _k_of(table))
    return float(np.nanmedian(fit.g_ratio))


def test_the_scene_tracks_show_a_trackers_scale_as_its_apparent_gravity():
    """With `track_noise_m` the scene logs each throw's flight as the tracker sees it
    (positions scaled about the origin, late by its latency): a whole-track fit finds an
    apparent gravity of s · g, and logging the tracks moves no landing."""
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    assert path is not None
    mp = load_params(path)
    objs = ("sphere55", "cube50")
    tracker = [{"kind": "tracker", "form": "const", "scale": 1.03, "latency_s": 0.02}]
    for effects, s in (([], 1.0), (tracker, 1.03)):
        camp = draw_scene_campaign(effects, np.random.default_rng(4), mp, n=20, objects=objs,
                                   track_noise_m=0.003)  # fmt: skip
        assert camp.tracks is not None and len(camp.tracks) == len(camp.records)
        assert _median_gravity(camp) == pytest.approx(s, abs=0.005)
        for r in camp.records:
            t = camp.tracks[r["throw_id"]]
            assert np.all(np.diff(t[:, 0]) > 0) and t[-1, 0] <= r["t_flight_s"]
    bare = draw_scene_campaign(tracker, np.random.default_rng(4), mp, n=20, objects=objs)
    assert bare.tracks is None and bare.records == camp.records


@pytest.fixture(scope="module")
def balls_rolling() -> tuple[Any, Any]:
    """The scene's parameters and 32 throws of three balls that roll on after the landing
    (`s:bounce-roll`'s world, no tracker scale), their tracks logged (3 mm of scatter):
    thrown once for the two tests that read them, one its tracks, the other its landings
    alone (logging the tracks moves no landing:
    `test_the_scene_tracks_show_a_trackers_scale_as_its_apparent_gravity`; the 32 throws
    drawn again without them were 3.6 CPU-s)."""
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    assert path is not None
    mp = load_params(path)
    roll = {"kind": "bounce", "form": "contact", "restitution": 0.05, "friction": 1.0,
            "rolling_m": 0.05}  # fmt: skip
    camp = draw_scene_campaign([roll], np.random.default_rng(2), mp, n=32,
                               objects=("sphere40", "sphere55", "sphere70"),
                               track_noise_m=0.003)  # fmt: skip
    return mp, camp


def test_a_trackers_scale_beside_a_rolling_ball_is_refused_where_the_tracks_show_g(
    balls_rolling: tuple[Any, Any],
) -> None:
    """Balls rolling on after the landing (`s:bounce-roll`'s world, no tracker scale): on
    the landings alone a tracker scale (1.057 here) fits part of the roll and nothing
    refuses it; the scene's tracks show g (1.002), and the scale is refused alone, and beside
    the bounce where a pair with it is tried (`cell.gap.select.refusal`). With the bounce's
    drop law, which follows the balls' fall to the floor, the bounce leaves the scale nothing
    to take and no pair with it is tried here; the pair's refusal beside the impact law is
    `test_a_trackers_scale_beside_a_rolling_ball_is_refused_where_the_misses_across_show_none`'s."""
    from cell.gap.run import diagnose_log
    from cell.log.table import ThrowTable

    mp, camp = balls_rolling
    d, _ = diagnose_log(ThrowTable.from_records(camp.records), mp.ee, objects=mp.objects,
                        tracks=camp.tracks, validation=mp.validation)  # fmt: skip
    rep = d.report
    assert "tracking_scale" not in rep["verdict"]["effects"]
    (ts,) = [c for c in rep["candidates"] if c["effect"] == "tracking_scale"]
    assert ts["refused"] and "apparent gravity is 1.00" in ts["refused"], ts["refused"]
    pairs = {k: t for k, t in rep["tests"].items() if "tracking_scale" in k}
    assert all("tracking_scale: the tracks' apparent" in t["refused"]
               for t in pairs.values()), pairs  # fmt: skip
    assert rep["verdict"]["laws"] == {"bounce": "drop"}


def test_a_trackers_scale_beside_a_rolling_ball_is_refused_where_the_misses_across_show_none(
    balls_rolling: tuple[Any, Any],
) -> None:
    """Balls rolling on (`s:bounce-roll`'s world, no tracker scale, landings only): a scale
    fitted beside the impact law takes part of the roll along the flight, and no gate of the
    effects alone refuses it; across the impact velocity, where a roll moves no landing, the
    misses show no scale, and the pair is refused (`cell.gap.select.across_refusal`). The same
    landings scaled by 1.03 about the origin (a tracker at 1.03, made here, not fitted): the
    misses across show 1.03 within 3 standard errors and the pair may join. The join's test
    records that scale beside the cut (`Selection.passes`), the pair refused or not."""
    from cell.gap.fit import Score, fit_set
    from cell.gap.problem import build_problem
    from cell.gap.select import Selection, across_refusal, across_scale, refusal
    from cell.log.table import ThrowTable
    from cell.model.effects import BounceImpact, TrackingScale

    mp, camp = balls_rolling  # its landings alone (the tracks are not read)
    for s_true in (1.0, 1.03):
        recs = [{**r, "landed_x_m": s_true * r["landed_x_m"],
                 "landed_y_m": s_true * r["landed_y_m"]} for r in camp.records]  # fmt: skip
        prob = build_problem(ThrowTable.from_records(recs), mp.ee, objects=mp.objects,
                             validation=mp.validation)  # fmt: skip
        fit = fit_set(prob, [BounceImpact, TrackingScale], np.arange(len(prob)))[0]
        assert all(refusal(e, None) is None for e in fit.effects), fit.effects
        s, se, used = across_scale(prob, fit.effects)
        assert used == len(prob) and 0.0 < se < 0.02, (s, se, used)
        pair = Score(names=("bounce", "tracking_scale"), full=fit,
                     heldout=np.zeros(len(prob)), heldout_rmse_m=0.0)  # fmt: skip
        sel = Selection(prob, [], {}, {}, None, 0.0, lambda _: None)
        # the join's test records the scale the misses across show, joined or not: the
        # tracker's own scale within 3 standard errors
        sel.passes(np.full(len(prob), 1.0), pair)
        rec = sel.tests["bounce+tracking_scale"]
        assert abs(rec["across_scale"][0] - s_true) < 3 * rec["across_scale"][1], rec
        if s_true == 1.0:
            # the pair's scale is off 1 by more than the misses across allow
            assert abs(fit.effects[1].params()["scale_factor"] - s) > se, (fit.effects, s, se)
            assert abs(s - 1.0) < 1.96 * se, (s, se)
            why = sel.refuse(pair)
            assert why and "across the impact velocity" in why, why
            assert rec["refused"] == why and not rec["passes"], rec
            # no scale across: within the refusal's 1.96 standard errors of 1 (the pair's
            # own scale, the roll taken along the flight, is not)
            assert abs(rec["across_scale"][0] - 1.0) < 1.96 * rec["across_scale"][1], rec
        else:
            assert abs(s - s_true) < 3 * se and abs(s - 1.0) > 1.96 * se, (s, se)
            assert across_refusal(prob, fit.effects) is None and sel.refuse(pair) is None
