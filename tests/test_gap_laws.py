"""Issue 57 (fit side): learned laws, outliers, proposals beyond the vocabulary and
compound pairs, on worlds from another implementation (`cell.gap.world_other`, which
imports nothing of the model or the fit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cell.gap.fit import fit_set, score_set
from cell.gap.laws import choose_law
from cell.gap.outliers import flag
from cell.gap.problem import build_problem
from cell.gap.propose import propose
from cell.gap.run import diagnose_log
from cell.gap.world_other import OBJECTS, Throws, draw_other_campaign, landings
from cell.log.table import ThrowTable
from cell.model.effects import BandMass, Bounce, BounceImpact, BounceRolling, ReleasePitch
from cell.model.params import DEFAULT_EE
from tests.source_imports import imported_modules

# MODEL.md golden values: object, stroke, release, elevation/azimuth [deg], base velocity,
# land_z, landed x, y [m], flight time [s]
GOLDEN = [
    ("cube50", 0.0625, (0, 0, 0.6), 30, 0, (0, 0, 0), 0.0, 1.2902, 0.0, 0.5290),
    ("cube50", 0.04, (0.1, -0.2, 0.5), 45, 20, (0, 0, 0), 0.0, 2.0345, 0.5041, 0.7339),
    ("cube30", 0.08, (0, 0, 0.7), 10, -15, (0, 0, 0), 0.0, 2.6318, -0.7052, 0.5008),
    ("cuboid_c", 0.035, (0, 0, 0.8), 35, 0, (0, 0, 0), 0.25, 0.9837, 0.0, 0.5063),
    ("cyl50", 0.06, (0, 0, 0.6), 20, 5, (0.5, 0, 0), 0.0, 1.2128, 0.0869, 0.4457),
    ("sphere40", 0.05, (0.2, 0.1, 0.9), 0, 0, (0, 0, 0), 0.0, 3.2117, 0.1000, 0.4311),
    ("sphere70", 0.03, (0, 0, 2.0), 8, 0, (0, 0, 0), 0.0, 2.1426, 0.0, 0.6892),
    ("cyl70", 0.1, (0, 0, 0.5), 60, -30, (0, 0.3, 0.2), 0.1, 0.0870, 0.0585, 0.3636),
]


def _problem(effects, *, n=240, seed=3, **kw):
    camp = draw_other_campaign(effects, np.random.default_rng(seed), n=n, **kw)
    table = ThrowTable.from_records(camp.records)
    return build_problem(table, DEFAULT_EE, seed=0), camp, table


def test_other_world_shares_no_code_and_meets_the_golden_values():
    src = Path(__file__).parents[1] / "cell" / "gap" / "world_other.py"
    imports = imported_modules(src)
    assert all(not m.startswith("cell") for m in imports), imports
    g = GOLDEN
    th = Throws(
        obj=np.array([r[0] for r in g]),
        shape=np.array([OBJECTS[r[0]][0] for r in g]),
        mass=np.array([OBJECTS[r[0]][1] for r in g]),
        size=np.array([OBJECTS[r[0]][2] for r in g]),
        stroke=np.array([r[1] for r in g]),
        p0=np.array([r[2] for r in g], float),
        elev=np.radians([r[3] for r in g]),
        azim=np.radians([r[4] for r in g]),
        vb=np.array([r[5] for r in g], float),
        platform=np.array(["arm"] * len(g)),
        rpm=np.zeros(len(g)),
        land_z=np.array([r[6] for r in g]),
    )
    xy, t, _ = landings(th, [])
    assert np.max(np.abs(xy - np.array([r[7:9] for r in g]))) < 1e-3
    assert np.max(np.abs(t - np.array([r[9] for r in g]))) < 1e-3


def test_stroke_proportional_band_mass_is_learned_as_such():
    prob, _, _ = _problem([{"kind": "band_mass", "form": "stroke", "k": 0.15}])
    const = score_set(prob, [BandMass])
    best, tried = choose_law(prob, const)
    eff = best.full.effects[-1]
    assert eff.law == "mass_kg = k · stroke_m", tried
    assert eff.params()["k"] == pytest.approx(0.15, rel=0.05)
    assert best.heldout_rmse_m < 0.8 * const.heldout_rmse_m


def test_constant_world_gets_no_extra_terms():
    prob, _, _ = _problem([{"kind": "release_pitch", "form": "const", "value": 0.08}])
    const = score_set(prob, [ReleasePitch])
    best, tried = choose_law(prob, const)
    assert type(best.full.effects[-1]) is ReleasePitch, tried
    assert best.full.effects[-1].params()["delta_rad"] == pytest.approx(0.08, rel=0.05)


def test_size_proportional_bounce_is_learned_as_such():
    # a ball's rolling friction: its slide's 1/μ grows with its size (1/μ = k · size_x_m)
    prob, _, _ = _problem([{"kind": "slide", "form": "friction_size", "k": 2.6}], n=160)
    const = score_set(prob, [Bounce])
    best, tried = choose_law(prob, const)
    eff = best.full.effects[-1]
    assert eff.law == "inv_mu = k · size_x_m", tried
    assert eff.params()["k"] == pytest.approx(2.6, rel=0.05)
    assert best.heldout_rmse_m < 0.8 * const.heldout_rmse_m


def test_a_laws_mean_over_the_log_is_reported_and_its_slide_is_the_closed_form():
    from cell.gap.diagnose import _law_means
    from cell.gap.laws import law_class
    from cell.model.effects_apply import predict_with_effects

    prob, _, _ = _problem([], n=60)
    size = prob.batch.size[:, 0]
    law = law_class(Bounce, "size_x_m", False)(k=2.6)  # type: ignore[call-arg]
    assert _law_means([law], prob)["bounce"]["inv_mu"] == pytest.approx(2.6 * size.mean())
    # the model's friction slide takes one 1/μ per throw: v_h |v_h| · 1/μ / (2 g)
    bare = predict_with_effects(prob.batch, DEFAULT_EE)
    slid = predict_with_effects(prob.batch, DEFAULT_EE, [law])
    vh = bare.impact_velocity[:, :2]
    want = vh * (np.linalg.norm(vh, axis=1) * 2.6 * size / (2 * 9.81))[:, None]
    got = np.c_[slid.x - bare.x, slid.y - bare.y]
    assert np.allclose(got, want, rtol=2e-3, atol=1e-9)


@pytest.mark.parametrize(
    ("slide", "cls", "param", "value"),
    [({"form": "friction", "mu": 1.2}, Bounce, "inv_mu", 1 / 1.2),
     ({"form": "const", "tau_s": 0.05}, BounceRolling, "tau_s", 0.05)],
)  # fmt: skip
def test_constant_bounce_gets_no_extra_terms(slide, cls, param, value):
    prob, _, _ = _problem([{"kind": "slide", **slide}], n=160)
    best, tried = choose_law(prob, score_set(prob, [cls]))
    assert type(best.full.effects[-1]) is cls, tried
    assert set(tried["bounce"]) > {"constant", f"{param} = k · size_x_m"}  # the forms were tried
    assert best.full.effects[-1].params()[param] == pytest.approx(value, rel=0.05)


def test_outliers_are_flagged_by_row_and_robust_error_is_reported():
    prob, camp, table = _problem([], n=120, outliers=0.05)  # 6 outliers among 120 throws
    pre = flag(prob.residual(np.arange(len(prob))))
    true = np.zeros(len(prob), bool)
    true[list(camp.outliers)] = True
    assert np.array_equal(pre, true)
    # an in-noise log flags (almost) nothing
    assert flag(np.random.default_rng(1).normal(0, 0.01, (800, 2))).sum() <= 1
    d, _ = diagnose_log(table, DEFAULT_EE, seed=0)
    rep = d.report
    assert rep["verdict"]["effects"] == ["none"]
    assert set(rep["outliers"]["rows"]) == {i + 1 for i in camp.outliers}
    v = rep["verdict"]
    assert v["heldout_rmse_robust_m"] < 1.3 * camp.floor_m < v["heldout_rmse_m"]


def test_flagged_outliers_do_not_drive_the_verdicts_parameters():
    # the same world drawn twice, the second time with 5 % of its landings moved 0.3-1 m
    # (the outliers are drawn last: every other row is the same). 80 throws (4 moved): the
    # verdict's wind 0.03 (x) and 0.02 (y) half-widths of the clean fit's interval off it
    # (seeds 0, 1: at most 0.16, 0.32); with the flagged rows in the fit (the first pass
    # reported) 1.15, 4.99 and 8.7 half-widths (at 120 throws 3.8)
    wind = [{"kind": "wind", "form": "const", "x_mps": 1.5, "y_mps": -1.0}]

    def camp(out):
        return draw_other_campaign(wind, np.random.default_rng(3), n=80, outliers=out)

    dirty, clean = camp(0.05), camp(0.0)
    d, _ = diagnose_log(ThrowTable.from_records(dirty.records), DEFAULT_EE, seed=0)
    v = d.report["verdict"]
    assert v["effects"] == ["wind"], v
    assert set(d.report["outliers"]["rows"]) == {i + 1 for i in dirty.outliers}
    # independent: the verdict's wind law fitted by least squares on the clean world's
    # every throw (the all-throws fit alone: no held-out folds are read here)
    law = [type(e) for e in d.verdict_effects]
    ref_prob = build_problem(ThrowTable.from_records(clean.records), DEFAULT_EE)
    ref, _, _ = fit_set(ref_prob, law, np.arange(len(ref_prob)))
    for (k, want), (lo, hi) in zip(ref.effects[0].params().items(), ref.ci,
                                   strict=True):  # fmt: skip
        assert abs(v["params"]["wind"][k] - want) < 0.5 * (hi - lo), (k, v["params"], want)


def test_sideways_launch_error_growing_with_stroke_is_proposed_as_such():
    prob, camp, _ = _problem([{"kind": "release_yaw", "form": "stroke", "k": 1.0}])
    prop, miss = propose(prob, (), camp.floor_m)
    assert not flag(miss).any()
    top = prop["terms"][0]
    assert top["phase"] == "launch"
    assert top["term"] == "azimuth error [rad] = k · stroke_m", prop["law"]
    assert top["k"] == pytest.approx(1.0, rel=0.15)
    assert prop["heldout_rmse_after_m"] < 1.3 * camp.floor_m
    assert prop["shrink_pct"] > 50


def test_per_object_law_is_learned_and_shrunk():
    from cell.gap.check_other import _PER_OBJ_BM
    from cell.gap.diagnose import _law_params

    prob, _, _ = _problem(
        [{"kind": "band_mass", "form": "object", "value": 0.015, "per_object": _PER_OBJ_BM}]
    )
    best, tried = choose_law(prob, score_set(prob, [BandMass]))
    e = best.full.effects[-1]
    assert e.law == "mass_kg = a_object", tried
    rep = _law_params(e, {k: list(v) for k, v in zip(e.params(), best.full.ci, strict=True)})
    for obj, v in rep["per_object"].items():
        assert v == pytest.approx(_PER_OBJ_BM[obj], rel=0.15), rep


def test_launch_effect_and_landing_slide_are_found_as_a_pair():
    # 200 throws: the pair on seeds 3, 0, 1, band mass 0.01998-0.02004 kg, τ 0.049-0.051 s,
    # the robust held-out RMSE 1.003-1.009 x the floor
    _, camp, table = _problem(
        [{"kind": "band_mass", "form": "const", "value": 0.02},
         {"kind": "slide", "form": "const", "tau_s": 0.05}],
        n=200,
    )  # fmt: skip
    d, _ = diagnose_log(table, DEFAULT_EE, seed=0)
    v = d.report["verdict"]
    assert sorted(v["effects"]) == ["band_mass", "bounce"], v
    assert v["phases"] == {"band_mass": "launch", "bounce": "landing"}
    assert v["params"]["band_mass"]["mass_kg"] == pytest.approx(0.02, rel=0.1)
    assert v["params"]["bounce"]["tau_s"] == pytest.approx(0.05, rel=0.3)
    assert v["heldout_rmse_robust_m"] <= 1.3 * camp.floor_m


def test_other_world_cases_cover_the_issue():
    from cell.cli import main
    from cell.gap.check_other import OTHER_CASES, other_cases

    cases = other_cases()
    assert len(cases) >= 40
    forms = {e["form"] for c in cases for e in c["effects"]}
    assert forms >= {"const", "stroke", "mass", "object", "throw", "friction"}
    assert sum("+" in c["truth"] for c in cases) >= 5
    assert sum(c["options"].get("outliers", 0) > 0 for c in cases) >= 5
    assert sum(c["truth"] == "unknown" for c in cases) >= 3
    assert "o:downwash+wind" in OTHER_CASES
    assert main(["gap", "check", "--worlds", "other", "--truths", "o:gremlins"]) == 2


def test_a_law_that_runs_a_throw_out_of_its_effects_range_is_not_chosen():
    """The scene's `s:drag-low` (a constant factor 0.4) was given factor = 0.79 − 8.77 ·
    stroke: on its strokes (35–102 mm) that law runs below the plausible 0.25 and through
    the bound 0.1, where the world's drag is never negative."""
    from cell.gap.laws import law_class, law_range, law_stretched, per_object_class
    from cell.model.effects import DragScale

    prob, _, _ = _problem([], n=60)
    s = prob.batch.stroke
    lin = law_class(DragScale, "stroke_m", True)
    bad = lin(a=0.79, k=-8.77)
    lo, hi = law_range(bad, prob.batch)
    assert lo == pytest.approx(0.79 - 8.77 * s.max()) and hi == pytest.approx(0.79 - 8.77 * s.min())
    assert law_stretched(bad, prob.batch)
    assert not law_stretched(lin(a=1.2, k=4.0), prob.batch)  # 1.3–1.7 over the strokes
    assert law_stretched(law_class(DragScale, "stroke_m", False)(k=50.0), prob.batch)  # > 4
    per = per_object_class(DragScale, prob)
    n_obj = len(per.object_ids)  # type: ignore[attr-defined]
    assert not law_stretched(per(*np.linspace(0.5, 3.0, n_obj)), prob.batch)
    assert law_stretched(per(*([1.0] * (n_obj - 1) + [4.5])), prob.batch)


def test_the_proposal_library_leaves_out_collinear_terms():
    from cell.gap.propose import COLLINEAR_TOL, covariates, independent

    rng = np.random.default_rng(0)
    a = rng.normal(size=(60, 3))
    near = 2 * a[:, 0] - a[:, 1] + 0.1 * COLLINEAR_TOL * rng.normal(size=60)
    lib = np.c_[a, near, rng.normal(size=60), np.zeros(60)]
    assert independent(lib).tolist() == [True, True, True, False, True, False]
    # a log of two objects: their mass and size take two values each, so only the
    # constant and the stroke enter the library
    prob, _, _ = _problem([], n=120)
    assert covariates(prob) == ["1", "stroke_m", "mass_kg", "size_x_m"]
    two = build_problem(_two_objects(prob.table), DEFAULT_EE, seed=0)
    assert covariates(two) == ["1", "stroke_m"]


def _two_objects(table: ThrowTable, pair: tuple[str, str] = ("cube30", "sphere40")) -> ThrowTable:
    return table.take(np.flatnonzero(np.isin(table.text("object_id"), pair)))


def test_a_side_force_on_two_objects_is_proposed_in_one_readable_term():
    """With two objects (mass and size collinear) the proposal was 14–16 terms with
    coefficients of 1e4–1e9 in mass and size; it names the force now."""
    _, camp, table = _problem([{"kind": "side_force", "form": "const", "x_mps2": 0.0,
                                "y_mps2": 0.6}], n=400)  # fmt: skip
    prob = build_problem(_two_objects(table), DEFAULT_EE, seed=0)
    prop, _ = propose(prob, (), camp.floor_m)
    top = prop["terms"][0]
    assert top["term"] == "force y [m/s²] = k", prop["law"]
    assert top["k"] == pytest.approx(0.6, rel=0.15)
    assert all(abs(t["k"]) < 100 for t in prop["terms"]), prop["law"]
    assert not any("mass_kg" in t["term"] or "size_x_m" in t["term"] for t in prop["terms"])


def _diagnosed(table: ThrowTable) -> dict:
    d, _ = diagnose_log(table, DEFAULT_EE, seed=0)
    return d.report


def test_a_level_wind_is_given_no_vertical_part():
    """A wind across the cell (this world has no vertical air) is the level member: a
    vertical part does not predict held-out throws better."""
    _, _, table = _problem([{"kind": "wind", "form": "const", "x_mps": -1.5, "y_mps": 2.0}])
    rep = _diagnosed(table)
    v = rep["verdict"]
    assert v["effects"] == ["wind"] and v["laws"] == {"wind": "level"}, v
    assert v["params"]["wind"] == pytest.approx({"x_mps": -1.5, "y_mps": 2.0}, abs=0.3)
    by = {c["effect"]: c for c in rep["candidates"]}
    assert set(by["wind"]["laws_heldout_rmse_m"]) == {"level", "with vertical"}


def test_a_wind_with_a_vertical_part_is_given_it():
    """The same throws landed by the model with air sinking at 0.7 m/s beside the wind
    across (a vertical part within the plausible 1 m/s): the member with it stands."""
    from cell.model.effects import Wind

    # 120 throws: the member with it, z -0.66 to -0.72 m/s (seeds 3, 0, 1, 2)
    prob, camp, _ = _problem([], n=120)
    wind = Wind(-1.5, 2.0, -0.7)
    land = prob.landing(np.arange(len(prob)), (wind,))
    xy = np.c_[land.x, land.y] + np.random.default_rng(4).normal(0, 0.012, (len(prob), 2))
    recs = [{**r, "landed_x_m": float(p[0]), "landed_y_m": float(p[1])}
            for r, p in zip(camp.records, xy, strict=True)]  # fmt: skip
    v = _diagnosed(ThrowTable.from_records(recs))["verdict"]
    assert v["effects"] == ["wind"] and v["laws"] == {"wind": "with vertical"}, v
    assert v["params"]["wind"]["z_mps"] == pytest.approx(-0.7, abs=0.15)


def _coulomb_rest(xy, vimp, mu, dt=1e-3):
    """Where objects come to rest on a Coulomb floor of friction mu that acts through the
    impact: the plastic impact's normal impulse m |v_z| brings a friction impulse of at
    most mu m |v_z| against v_h, then the object decelerates at mu g, stepped in time
    (written here from the physics, not from the model's closed form)."""
    vh = vimp[:, :2]
    speed = np.linalg.norm(vh, axis=1)
    u = vh / speed[:, None]
    s = np.zeros_like(speed)
    left = np.maximum(speed - mu * np.abs(vimp[:, 2]), 0.0)  # after the impact
    while np.any(left > 0):
        new = np.maximum(left - mu * 9.81 * dt, 0.0)
        s += 0.5 * (left + new) * dt
        left = new
    return xy + u * s[:, None]


def _slid_table(mu, n=160, seed=11):
    """A campaign of the other implementation's throws (no effect in flight) that come to
    rest by `_coulomb_rest`, logged with 12 mm of scatter per axis."""
    from cell.gap.world_other import draw_throws, landings, throw_record

    rng = np.random.default_rng(seed)
    th = draw_throws(n, rng)
    xy, tl, vimp = landings(th, [], None)
    ok = np.all(np.isfinite(xy), axis=1)
    obs = _coulomb_rest(xy, vimp, mu) + rng.normal(0.0, 0.012, (n, 2))
    recs = [throw_record(th, i, obs[i], float(tl[i])) for i in np.flatnonzero(ok)]
    return ThrowTable.from_records(recs)


def _bounce_members(prob):
    """The bounce family's members scored one by one {class: score}."""
    from cell.model.effects import FAMILIES

    return {c: score_set(prob, [c]) for c in FAMILIES["bounce"]}


def _bounce_member(prob, members=None):
    """The score of the bounce family's member that stands for the effect: the lowest
    `member_rank_of`, the rule `cell.gap.diagnose._score_members` applies per family."""
    from cell.gap.select import member_rank_of

    return min((members or _bounce_members(prob)).values(), key=member_rank_of)


def test_an_impact_slide_is_told_from_the_friction_law():
    # a floor of μ 0.5 whose friction acts through the impact: steep impacts slide less
    prob = build_problem(_slid_table(0.5), DEFAULT_EE, seed=0)
    members = _bounce_members(prob)
    best = _bounce_member(prob, members)
    eff = best.full.effects[-1]
    assert isinstance(eff, BounceImpact), best.full.effects
    assert eff.inv_mu_imp == pytest.approx(1 / 0.5, rel=0.03)
    fric = members[Bounce]  # the friction member's score, as scored among the others
    assert best.heldout_rmse_m < 0.7 * fric.heldout_rmse_m


@pytest.mark.parametrize(
    ("slide", "cls"),
    [({"form": "friction", "mu": 1.2}, Bounce), ({"form": "const", "tau_s": 0.05}, BounceRolling)],
)  # fmt: skip
def test_a_friction_or_rolling_world_is_not_given_the_impact_law(slide, cls):
    prob, _, _ = _problem([{"kind": "slide", **slide}], n=160)
    assert type(_bounce_member(prob).full.effects[-1]) is cls


def _two_most_thrown(prob):
    """The problem restricted to its two most thrown objects."""
    objs, counts = np.unique(prob.groups, return_counts=True)
    return prob.subset(np.isin(prob.groups, objs[np.argsort(counts)[-2:]]))


def test_a_law_in_the_stroke_is_checked_on_whole_objects_and_kept_where_it_holds():
    from cell.gap.laws import OBJECTS_OUT, objects_out

    prob, _, _ = _problem([{"kind": "band_mass", "form": "stroke", "k": 0.15}])
    two = _two_most_thrown(prob)
    held = objects_out(two)
    assert held is not None and list(held.folds) == ["object"]
    for train, test in held.folds["object"]:  # each object predicted from the other's
        assert np.unique(two.groups[test]).size == 1
        assert not set(two.groups[train]) & set(two.groups[test])
    assert objects_out(two.subset(two.groups == two.groups[0])) is None
    const = score_set(two, [BandMass])
    best, tried = choose_law(two, const)
    rows = tried["band_mass"]
    assert best.full.effects[-1].law == "mass_kg = k · stroke_m", rows
    assert f"mass_kg = k · stroke_m, {OBJECTS_OUT}" in rows
    assert best.full.effects[-1].params()["k"] == pytest.approx(0.15, rel=0.05)


def test_a_law_in_the_stroke_that_one_object_alone_follows_is_refused():
    """A constant band mass, and on one of two objects a miss outside the vocabulary that
    grows with the stroke (its landings pushed along the throw by 4 m per m of stroke
    about the mean): a law of the mass in the stroke cuts the random folds' held-out
    RMSE most, but predicts each object from the other worse than the constant (the
    scene's `s:drag+hop`, whose drag took the stroke law its hop called for)."""
    from dataclasses import replace

    from cell.gap.laws import OBJECTS_OUT, TERM_PENALTY

    prob, _, _ = _problem([{"kind": "band_mass", "form": "const", "value": 0.02}], seed=5)
    two = _two_most_thrown(prob)
    s, az = two.batch.stroke, two.batch.azimuth
    push = np.where(two.groups == two.groups[0], 4.0 * (s - s.mean()), 0.0)
    two = replace(two, observed=two.observed + push[:, None] * np.c_[np.cos(az), np.sin(az)])
    const = score_set(two, [BandMass])
    best, tried = choose_law(two, const)
    rows = tried["band_mass"]
    lin = "mass_kg = a + k · stroke_m"
    forms = {
        k: v * (1 + TERM_PENALTY * (k == lin)) for k, v in rows.items() if OBJECTS_OUT not in k
    }
    assert min(forms, key=forms.__getitem__) == lin, rows  # the best on random folds
    assert rows[f"{lin}, {OBJECTS_OUT}"] > rows[f"constant, {OBJECTS_OUT}"], rows
    assert type(best.full.effects[-1]) is BandMass, rows


def _scene_like(n: int, seed: int, objects: tuple[str, ...] | None, effects: tuple, sd: float):
    """n throws planned as the scene plans them (`cell.gap.world_scene.draw_plan`: two
    repeats per configuration, strokes 35–105 mm), landed by the scene's configured model
    with `effects` and a tracker's scatter sd [m] per axis; (the log, the parameters)."""
    from cell.gap.world_scene import _records, draw_plan
    from cell.params import load_params, scene_params_path

    mp = load_params(scene_params_path())
    plan = draw_plan(n, np.random.default_rng(seed), objects=objects)
    recs = _records(plan, np.zeros((n, 2)), np.ones(n), np.ones(n, bool))
    prob = build_problem(ThrowTable.from_records(recs), mp.ee, objects=mp.objects, seed=0)
    effs = tuple(e(prob) if callable(e) else e for e in effects)
    land = prob.landing(np.arange(n), effs)
    xy = np.c_[land.x, land.y] + np.random.default_rng(seed + 1).normal(0, sd, (n, 2))
    recs = [{**r, "landed_x_m": float(p[0]), "landed_y_m": float(p[1])}
            for r, p in zip(recs, xy, strict=True)]  # fmt: skip
    return ThrowTable.from_records(recs), mp


@pytest.mark.parametrize("seed", [0, 1])
def test_a_drag_growing_with_the_stroke_is_not_named_a_stroke_offset(seed):
    """Air drag whose factor is 30 · stroke (1.05–3.15 over the strokes) on two objects at
    a tracker's 35 mm: a stroke offset of about 1 mm ranks above the constant drag, and
    its constant was the verdict; the drag with its own law in the stroke predicts
    held-out throws better (`Selection.rival_law`) and is named with k near 30."""
    from cell.gap.laws import law_class
    from cell.model.effects import DragScale

    law = law_class(DragScale, "stroke_m", False)(30.0)
    table, mp = _scene_like(80, seed, ("cube30", "sphere40"), (law,), 0.035)
    d, _ = diagnose_log(table, mp.ee, objects=mp.objects, seed=0, validation=mp.validation)
    rep = d.report
    by = [c["effect"] for c in rep["candidates"]]
    assert by.index("stroke_offset") < by.index("drag_scale"), by  # the constant ranks below
    v = rep["verdict"]
    assert v["effects"] == ["drag_scale"], v
    assert v["laws"]["drag_scale"] == "factor = k · stroke_m", v
    assert v["params"]["drag_scale"]["k"] == pytest.approx(30.0, rel=0.1)
    over = [t for k, t in rep["tests"].items() if k.startswith("drag_scale (") and "over" in k]
    assert over and over[0]["passes"] and over[0]["cut_ci_m"][0] > 0, rep["tests"]


def test_a_wind_across_objects_of_other_drag_is_given_no_vertical_part():
    """A level wind on 14 objects whose drag is 0.6–1.0 × the model's, each its own: the
    vertical part takes up some of the drag the model gets wrong and predicts held-out
    throws 1.2 % better, less than a term's penalty (`member_rank_of`): the level member
    stands, without an updraught the world does not have."""
    from cell.gap.laws import per_object_class
    from cell.model.effects import DragScale, WindLevel

    def drag(prob):
        cls = per_object_class(DragScale, prob)
        return cls(*np.random.default_rng(6).uniform(0.6, 1.0, len(cls.bounds)))

    table, mp = _scene_like(80, 4, None, (drag, WindLevel(2.5, -1.2)), 0.035)
    d, _ = diagnose_log(table, mp.ee, objects=mp.objects, seed=0, validation=mp.validation)
    rep = d.report
    laws = {c["effect"]: c for c in rep["candidates"]}["wind"]["laws_heldout_rmse_m"]
    assert laws["with vertical"] < laws["level"] < 1.03 * laws["with vertical"], laws
    v = rep["verdict"]
    assert v["effects"] == ["wind"] and v["laws"] == {"wind": "level"}, v
    assert v["params"]["wind"] == pytest.approx({"x_mps": 2.5, "y_mps": -1.2}, rel=0.3)


@pytest.mark.parametrize(("off_m", "kept"), [(-0.6, False), (-0.1, True)])
def test_a_landing_plane_further_off_than_any_cells_is_not_proposed(off_m, kept):
    """Throws landed by the model on a surface off_m [m] from the logged plane: 0.1 m off
    is proposed as a plane height of -0.1 m; 0.6 m off is more than any cell's floor is
    (`cell.gap.propose.PLANE_MAX_M`): the term is left out, listed with its value, and the
    law is fitted without it (a floor that far off is no cell's: the term stands for
    something else, as a slide's on the scene's bounce logs)."""
    from cell.gap.propose import PLANE_CONST, PLANE_MAX_M

    _, camp, table = _problem([], n=160)
    recs = camp.records
    true = ThrowTable.from_records([{**r, "land_z_m": r["land_z_m"] + off_m} for r in recs])
    land = build_problem(true, DEFAULT_EE, seed=0).landing(np.arange(len(recs)))
    xy = np.c_[land.x, land.y] + np.random.default_rng(5).normal(0, 0.012, (len(recs), 2))
    recs = [{**r, "landed_x_m": float(p[0]), "landed_y_m": float(p[1])}
            for r, p in zip(recs, xy, strict=True)]  # fmt: skip
    prob = build_problem(ThrowTable.from_records(recs), DEFAULT_EE, seed=0)
    prop, _ = propose(prob, (), camp.floor_m)
    k = {t["term"]: t["k"] for t in prop["terms"]}
    assert abs(off_m) > PLANE_MAX_M or kept
    if kept:
        assert k[PLANE_CONST] == pytest.approx(off_m, rel=0.15), prop["law"]
        assert "implausible_left_out" not in prop
    else:
        assert PLANE_CONST not in k, prop["law"]
        (out,) = prop["implausible_left_out"]
        # the term is linear in the height: 0.6 m off reads as 0.41 m, still beyond the bound
        assert out["term"] == PLANE_CONST and off_m < out["k"] < -PLANE_MAX_M, out
        assert all(abs(v) <= PLANE_MAX_M for t, v in k.items() if "plane" in t), prop["law"]
