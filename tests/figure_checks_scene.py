"""The checks of what docs/gap_scene.md says of the scene world's launch jitter, its floor
with an effect's own repeat scatter, the bounce cases' repeats
(docs/figures/gap_scene_repeats.json, `python -m cell.gap.scene_repeats`) and the cases
on the verdict's edge (run by tests/test_readme_figures.py through
`check_the_gap_scene_prose`)."""

from __future__ import annotations

import inspect
import math
import re
import statistics
from typing import Any

from tests.figure_checks_pages import _case
from tests.figure_quotes import COVERED, close, load_json, note, page_text, quoted

PAGE = "docs/gap_scene.md"
_LAWS = ("tau", "inv_mu", "tau+inv_mu", "inv_mu+hop", "impact", "drop", "roll")
_COLS = ("repeat_sd_rest_m", "repeat_sd_crossing_m", "slide_rms_m", *_LAWS,
         "inv_mu per object", "tau per object")  # fmt: skip


def _mm(q: str, value_m: float) -> None:
    close(q, 1000 * value_m, len(q.split(".")[1]) if "." in q else 0)


def _written(q: str, value: float) -> None:
    close(q.replace("−", "-"), value, len(q.split(".")[1]) if "." in q else 0)


def check_the_launch_jitter_and_floor(rows: dict[str, dict[str, Any]]) -> None:
    from cell import synth
    from cell.gap import world_scene as ws

    (sd,) = quoted(PAGE, r"ε drawn per throw with an sd of ([\d.]+) %")
    close(sd, 100 * ws.JITTER_REL, 3)
    reach, spread = quoted(PAGE, r"from the arm reaches ([\d.]+) ± ([\d.]+) m\)")
    assert (float(reach), float(spread)) == (synth.THESIS_REACH_M, synth.THESIS_SPREAD_M)
    lo, hi = quoted(PAGE, r"effect-free throws scatter between repeats by (\d+)–(\d+) mm")
    free = [1000 * r["world_repeat_sd_m"][1] for r in rows.values()]
    close(lo, min(free), 0)
    close(hi, max(free), 0)
    (zero,) = quoted(PAGE, r"F² = F0² \+ max\((\d), V_effect − V_none\)")
    assert int(zero) == 0 and "max(0.0, extra)" in inspect.getsource(ws.FloorRows.floors)
    for r in rows.values():  # the formula, as the rows carry it
        eff, none = r["world_repeat_sd_m"]
        f0 = r["world_floor0_m"]
        want = math.sqrt(f0**2 + max(0.0, eff**2 - none**2))
        assert abs(r["world_floor_m"] - want) < 1e-9, r["case"]


def check_the_repeats_table() -> None:
    doc = load_json("docs/figures/gap_scene_repeats.json")
    cases = doc["cases"]
    n, seed = quoted(PAGE, r"bounce case's plan \((\d+) throws, each configuration twice, "
                     r"seed (\d+)\)")  # fmt: skip
    assert (int(n), int(seed)) == (doc["n"], doc["seed"])
    from cell.gap.world_scene import JITTER_REL

    assert doc["jitter"] == JITTER_REL
    pattern = r"\n\| (s:[\w+.-]+) " + r"\| (\d+) " * len(_COLS) + r"\|(?=\n)"
    ms = list(re.finditer(pattern, page_text(PAGE)))
    assert [m.group(1) for m in ms] == list(cases)
    for m in ms:
        note(PAGE, m)
        for q, col in zip(m.groups()[1:], _COLS, strict=True):
            _mm(q, cases[m.group(1)][col])
    sl, s3 = cases["s:bounce-slide"], cases["s:bounce-slide-mu03"]
    c1, mu1, r1, c01, r01, b1, p1, cu_lo, cu_hi, cb_lo, cb_hi = quoted(
        PAGE,
        r"crossings differ by (\d+) mm, the rest points of blocks on a floor of μ ([\d.]+) lie "
        r"(\d+) mm apart; at a tenth of the jitter \(crossings ([\d.]+) mm apart\) still "
        r"(\d+) mm\..*?the best leaves (\d+) mm\), and per object they come nearer \((\d+) "
        r"mm; 1/μ ([\d.]+)–([\d.]+) for the cubes, ([\d.]+)–([\d.]+) for the cuboids",
    )
    _mm(c1, sl["repeat_sd_crossing_m"])
    from cell.gap.check_scene import SCENE_CASES

    def friction(case: str) -> float:
        return float(SCENE_CASES[case][0][0]["friction"])

    assert float(mu1) == friction("s:bounce-slide")
    _mm(r1, sl["repeat_sd_rest_m"])
    tenth = sl["jitters"][f"{JITTER_REL / 10:g}"]
    _mm(c01, tenth["repeat_sd_crossing_m"])
    _mm(r01, tenth["repeat_sd_rest_m"])
    _mm(b1, min(sl[k] for k in _LAWS))
    _mm(p1, sl["inv_mu per object"])
    mu = sl["inv_mu_per_object"]
    cubes = [v for k, v in mu.items() if k.startswith("cube") and not k.startswith("cuboid")]
    cuboids = [v for k, v in mu.items() if k.startswith("cuboid")]
    for q, v in ((cu_lo, min(cubes)), (cu_hi, max(cubes)), (cb_lo, min(cuboids)),
                 (cb_hi, max(cuboids))):  # fmt: skip
        _written(q, v)
    mu3, s3_rms, times = quoted(PAGE, r"On\s+μ ([\d.]+) the slide is long \((\d+) mm RMS\) and "
                                r"no law of the table comes within\s+(\d+) × the scatter")  # fmt: skip
    assert float(mu3) == friction("s:bounce-slide-mu03")
    _mm(s3_rms, s3["slide_rms_m"])
    best = min(s3[k] for k in (*_LAWS, "inv_mu per object", "tau per object"))
    assert int(times) <= best / s3["repeat_sd_rest_m"] < int(times) + 1
    balls = cases["s:bounce-roll"]["inv_mu_per_object"]
    *mus, k40, k55, k70 = quoted(
        PAGE,
        r"1/μ is ([\d.]+), ([\d.]+) and ([\d.]+) for sphere40, sphere55 and\s+sphere70, "
        r"([\d.]+), ([\d.]+) and ([\d.]+) per metre of diameter",
    )
    from cell.sim.items import resolve_object

    for q, k, name in zip(mus, (k40, k55, k70), ("sphere40", "sphere55", "sphere70"),
                          strict=True):  # fmt: skip
        _written(q, balls[name])
        _written(k, balls[name] / max(resolve_object(name)[0].size))
    hop = cases["s:bounce-hop-mu05"]
    mu5, h1, h2, h0 = quoted(PAGE, r"A hop on a floor of μ ([\d.]+)\*\*.*?cuts what the slide "
                             r"leaves from (\d+) to (\d+) mm \(the repeats\s+scatter by (\d+)\)")  # fmt: skip
    assert float(mu5) == friction("s:bounce-hop-mu05")
    _mm(h1, hop["inv_mu"])
    _mm(h2, hop["inv_mu+hop"])
    _mm(h0, hop["repeat_sd_rest_m"])


def check_the_edge_and_the_changes(rows: dict[str, dict[str, Any]], ratio: float) -> None:
    # the floor with the model's validated accuracy ("What changed the table")
    edge = ("s:wind", "s:drag-high", "s:wind+scale", "s:downwash+wind")
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    assert path is not None
    val = load_params(path).validation
    assert val is not None
    miss = {k: v[0] for k, v in val.objects.items()}
    c30, s40, o_lo, o_hi = quoted(
        PAGE,
        r"`validation`: cube30 (\d+) mm, sphere40\s+(\d+) mm, the other objects (\d+)–(\d+) mm\)",
    )
    _mm(c30, miss.pop("cube30"))
    _mm(s40, miss.pop("sphere40"))
    _mm(o_lo, min(miss.values()))
    _mm(o_hi, max(miss.values()))
    *before, r_lo, r_hi, r_med = quoted(
        PAGE,
        r"the tool's floor\s+over the world's, ([\d.]+)–([\d.]+) \(median ([\d.]+)\), is "
        r"([\d.]+)–([\d.]+) \(median ([\d.]+)\)",
    )
    assert before == ["0.67", "1.12", "0.83"]  # the table before, as the page tells it
    ratios = sorted(r["tool_floor_m"] / r["world_floor_m"] for r in rows.values())
    close(r_lo, ratios[0], 2)
    close(r_hi, ratios[-1], 2)
    close(r_med, statistics.median(ratios), 2)
    for c in edge:
        assert rows[c]["passes"] and rows[c]["verdict"] == rows[c]["truth"], c
    over = quoted(
        PAGE, r"`unknown` at ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+) × the repeats' floor"
    )
    assert over == ("1.32", "1.32", "1.31", "1.43")  # the table before, as the page tells it
    # "`s:bounce-roll` names the spurious scale beside its bounce": that step's table; the
    # drop law names the bounce alone since ("What changed the table")
    assert rows["s:bounce-roll"]["verdict"] == "bounce" and rows["s:bounce-roll"]["passes"]
    was, now, of = quoted(
        PAGE, r"`s:drag\+hop`'s drag is its constant\. (\d+) → (\d+) of (\d+) pass"
    )
    assert (was, now) == ("26", "31")  # that change's tables, as the page tells it
    was, now2, of2 = quoted(
        PAGE, r"sd ([\d.]+)\. (\d+) → (\d+) of (\d+)\s+pass; no other row moved"
    )[1:]
    assert (was, of2) == (now, of)  # the throw-to-throw wind's change came after it
    assert now2 == "32"  # that change's table, as the page tells it
    was3, now3, of3 = quoted(PAGE, r"(\d+) → (\d+) of (\d+) pass; `s:wind-y`, `s:downwash\+wind`")
    assert (was3, of3) == (now2, of)  # the rival's law came after it
    assert (now3, of) == ("34", "43")  # that change's table, as the page tells it
    was4, of4, now4, of5 = quoted(PAGE, r"(\d+) of (\d+) → (\d+) of (\d+) pass\.\n")
    assert (was4, of4) == (now3, of)  # the drawn drag factor came after it
    assert (now4, of5) == ("35", "44")  # that change's table, as the page tells it
    was6, now6, of6 = quoted(
        PAGE, r"(\d+) → (\d+) of (\d+) pass; no row without\s+a bounce moved\."
    )
    assert was6 == now4  # the drop law came after the drawn drag factor
    assert (now6, of6) == ("38", "44")  # that change's table, as the page tells it
    was7, of7, now7, of8, d7, d8 = quoted(
        PAGE,
        r"(\d+) of (\d+) → (\d+) of (\d+) pass, diagonal (\d+) → (\d+); no row\s+without a ball",
    )
    assert (was7, of7) == (now6, of6)  # the roll law came after the drop law
    table = load_json("docs/figures/gap_check_scene.json")
    assert (now7, of8, d8) == ("37", "45", "39")  # the roll law's table, as the page tells it
    assert d7 == "38"  # the drop law's table's diagonal, as the page tells it
    for c in ("s:bounce-roll", "s:bounce-hop+outliers"):
        assert rows[c]["verdict"] == "bounce" and rows[c]["passes"], c
        assert rows[c]["laws"] == {"bounce": "drop"}, c
    one, hard = rows["s:bounce-roll-one"], rows["s:bounce-roll-hard"]
    # the roll law's depth from the log: the hard floor's balls named by it, passing; the
    # sliding floor's one ball size by the drop law again, passing
    law = "inv_mu_r_per_m = a + k · stroke_m"  # the roll law's 1/μ_r, a law in the stroke
    assert hard["laws"] == {"bounce": law} and hard["passes"] and hard["params_ok"]
    assert one["laws"] == {"bounce": "drop"} and one["passes"] and one["params_ok"]
    assert set(hard["params"]["bounce"]) == {"a", "k"}  # the depth is the log's, not fitted
    (a_hard,) = quoted(PAGE, r"named `bounce` by\s+the roll law with the log's depth, A ([\d.]+) F")
    close(a_hard, hard["after_over_floor"], 2)
    (a_log,) = quoted(
        PAGE, r"`s:bounce-roll-hard` is named by it within the world's floor \(A ([\d.]+) F\)"
    )
    close(a_log, hard["after_over_floor"], 2)
    was9, now9, of9, d9 = quoted(PAGE, r"(\d+) → (\d+) of (\d+) pass,\s+diagonal (\d+) as before")
    assert (now9, of9, d9) == ("39", "45", "39")  # the roll law's depth's table, as told
    assert was9 == now7 == "37" and d9 == d8
    was10, now10, of10, dw10, d10 = quoted(
        PAGE, r"(\d+) → (\d+) of (\d+) pass, diagonal (\d+) → (\d+); no other row moved"
    )
    assert (was10, dw10) == (now9, d9)  # the air on the slide came after the roll law's depth
    air5, before_air5 = quoted(
        PAGE, r"`s:bounce-hop-mu05` `bounce` at ([\d.]+) F \(was `unknown`, ([\d.]+)\)"
    )
    close(air5, rows["s:bounce-hop-mu05"]["after_over_floor"], 2)
    assert before_air5 == "1.35"  # the table before the air on the slide, as the page tells it
    assert (int(now10), int(of10), int(d10)) == (table["passes"], len(rows), table["diagonal"])
    d_hard, d_one = quoted(
        PAGE,
        r"fails on the floor's depth\s+\((\d+) % off, the depth then fitted.*?its\s+depth, "
        r"judged against the world's roll fit, is (\d+) % off",
    )
    assert (d_hard, d_one) == ("88", "31")  # the table with the roll law's depth fitted
    for c in ("s:wind-y", "s:downwash+wind", "s:wind-all-objects"):
        assert rows[c]["laws"] == {"wind": "level"}, c
    assert "drag_scale" not in rows["s:drag+hop"]["laws"] and rows["s:drag+hop"]["passes"]
    from cell.gap.select import VERDICT_RATIO

    assert VERDICT_RATIO == 1.3  # "over 1.3 × the tool's floor", as the page tells it
    # the wind beside a slide and beside a hop, each named with its phase (the page's
    # "What passes"; the impact law's parameters are in the table)
    quoted(PAGE, r"beside a hop \(`s:wind\+bounce`, `s:wind\+hop`: each effect with its phase")
    for c in ("s:wind+bounce", "s:wind+hop"):
        assert rows[c]["verdict"] == "bounce+wind" and rows[c]["passes"]
    drag, world = quoted(
        PAGE, r"\(`s:drag\+hop`: its constant ([\d.]+) for the\s+world's ([\d.]+)\)"
    )
    _written(drag, rows["s:drag+hop"]["params"]["drag_scale"]["factor"])
    dh_drag = [e for e in _case("s:drag+hop") if e["kind"] == "drag_scale"]
    assert [float(world)] == [e["value"] for e in dh_drag]
    bs = rows["s:bounce-slide"]
    a, tool, af, f, kept, every = quoted(
        PAGE, r"\(`s:bounce-slide`: A (\d+) mm\s+against the tool's floor of (\d+) mm, and A / F "
        r"([\d.]+) with F (\d+) mm on the (\d+) throws kept;\s+the two it flags are the world's "
        r"own longest slides, and with them F is (\d+) mm\)")  # fmt: skip
    _mm(a, bs["after_robust_m"])
    _mm(tool, bs["tool_floor_m"])
    close(af, bs["after_over_floor"], 2)
    assert bs["judged"] == "after_robust_m / world_floor_kept_m"
    _mm(f, bs["world_floor_kept_m"])
    assert int(kept) == bs["throws"] - len(bs["outlier_rows"]) and len(bs["outlier_rows"]) == 2
    _mm(every, bs["world_floor_m"])
    short, law_k, world_k = quoted(
        PAGE, r"join `stroke_offset` \(a stroke read (−[\d.]+) mm short:.*?`speed error \[share\] "
        r"= ([\d.]+) · stroke_m` \(the world's ([\d.]+)\)"
    )  # fmt: skip
    assert float(world_k) == _case("s:launch-speed-stroke")[0]["speed_k"]
    lss = rows["s:launch-speed-stroke"]
    _mm(short.replace("−", "-"), lss["params"]["stroke_offset"]["delta_m"])
    assert (
        lss["verdict"] == "unknown"
        and lss["proposal"] == f"speed error [share] = {law_k} · stroke_m"
    )
    doc = load_json("docs/figures/gap_check_scene.json")
    old, new, total, s1, s2, m1, m2 = quoted(
        PAGE,
        r"(\d+) → (\d+) of (\d+) pass, the three cases.*?`s:bounce-slide`'s A / F ([\d.]+) → "
        r"([\d.]+) and `s:bounce-slide-mu03`'s ([\d.]+) → ([\d.]+) \(both",
    )
    # the tables before the jitter and after it, as the page tells them (the jet member's
    # change, after them, is checked with today's count in `_check_the_jet`)
    assert (old, new, s1, m1) == ("24", "21", "4.70", "8.63")
    assert total == "42"  # the cases of that step (a null case was added after it)
    assert s2 == "2.14"  # that step's table, as the page tells it
    mu3 = rows["s:bounce-slide-mu03"]
    law, m_before, m_after = quoted(
        PAGE, r"`s:bounce-slide-mu03` is given `([^`]+)`, its A / F ([\d.]+) → ([\d.]+) \(still"
    )
    assert m2 == m_before == "5.37"  # the jitter's table, before the bounce had laws
    assert law == mu3["laws"]["bounce"] and mu3["verdict"] == "unknown"
    assert m_after == "4.41"  # that step's table (the impact law's is in the table now)
    # "In `s:drag+hop` the impact law's 1/μ is itself given a law in the stroke"; "the two
    # pairs with a wind take the drop law"
    quoted(PAGE, r"In `s:drag\+hop` the impact law's 1/μ is itself given a law in the stroke")
    assert rows["s:drag+hop"]["laws"]["bounce"] == "inv_mu_imp = a + k · stroke_m"
    for c in ("s:wind+bounce", "s:wind+hop"):
        assert rows[c]["laws"]["bounce"] == "drop", c
    assert ratio == doc["criteria"]["floor_ratio"]
    COVERED[PAGE].sort()


def check_what_does_not(page: str, rows: dict[str, dict[str, Any]], ratios: dict) -> None:
    from cell.model.effects import Wind

    every_obj = rows["s:wind-all-objects"]["params"]["wind"]
    fx, fy, tx, ty, lo, hi = quoted(
        page,
        r"phase right, at ([\d.]+)/−([\d.]+) m/s for ([\d.]+)/−([\d.]+): the\s+calibrated "
        r"objects' drag constants are ([\d.]+)–([\d.]+) × the scene's",
    )
    assert rows["s:wind-all-objects"]["passes"] and rows["s:wind-all-objects"]["laws"] == {
        "wind": "level"
    }
    a, k = quoted(page, r"`factor = a \+ k · stroke_m` with a ([\d.]+), k ([\d.]+) /m,\s+cuts")
    ds = rows["s:drag-stroke"]
    assert ds["passes"] and ds["laws"] == {"drag_scale": "factor = a + k · stroke_m"}
    _written(a, ds["params"]["drag_scale"]["a"])
    _written(k, ds["params"]["drag_scale"]["k"])
    _written(fx, every_obj["x_mps"])
    _written(fy, -every_obj["y_mps"])
    eff = _case("s:wind-all-objects")[0]
    assert (float(tx), -float(ty)) == (eff["x_mps"], eff["y_mps"])
    close(lo, min(ratios.values()), 1)
    close(hi, max(ratios.values()), 1)
    across, up, wy, found_y = quoted(
        page,
        r"\(within ±(\d+) m/s across, ±(\d+) m/s up\), which refused `s:wind-y`: the world's "
        r"([\d.]+) m/s along y, fitted at ([\d.]+) m/s, passes now",
    )
    assert (float(across), float(up)) == (3, 1)  # the old box, as the page tells it
    assert float(wy) == _case("s:wind-y")[0]["y_mps"]
    _written(found_y, rows["s:wind-y"]["params"]["wind"]["y_mps"])
    assert rows["s:wind-y"]["passes"]
    six, one = quoted(page, r"within (\d+) m/s across and (\d+) m/s up or down")
    assert (float(six), float(one)) == (Wind.plausible[0][1], Wind.plausible[2][1])
    sd, mean, steady, fx, fsd, rsd, a_f = quoted(
        page,
        r"`s:wind-throw-wide` \(drawn throw to throw with an sd of ([\d.]+) m/s about ([\d.]+)\s+"
        r"m/s along x\) it found x ([\d.]+) m/s, named `wind` by its level member: .*? finds x "
        r"([\d.]+) m/s and an sd of ([\d.]+) m/s \(the repeats'\s+differences alone: ([\d.]+)\), "
        r"A ([\d.]+) F",
    )
    wide = rows["s:wind-throw-wide"]
    assert (float(sd), float(mean)) == (_case("s:wind-throw-wide")[0]["sd"],
                                        _case("s:wind-throw-wide")[0]["x_mps"])  # fmt: skip
    assert steady == "2.92"  # the table before, as the page tells it
    wt = wide["wind_throw_to_throw"]
    assert wide["verdict"] == "wind" and wide["laws"] == {"wind": wt["law"]} and wt["chosen"]
    _written(fx, wide["params"]["wind"]["x_mps"])
    _written(fsd, wide["params"]["wind"]["sd_mps"])
    _written(rsd, wt["repeats"]["sd_mps"])
    close(a_f, wide["after_over_floor"], 2)
    assert wide["passes"] and wide["outliers_false"] == 0
    t_sd, tx, t_x, tsd = quoted(
        page,
        r"`s:wind-throw` \(sd ([\d.]+)\) takes the form too: x (−[\d.]+) for (−[\d.]+), "
        r"sd (\d+\.\d+)",
    )
    narrow = rows["s:wind-throw"]
    drawn = _case("s:wind-throw")[0]
    assert (float(t_sd), float(t_x.replace("−", "-"))) == (drawn["sd"], drawn["x_mps"])
    assert narrow["wind_throw_to_throw"]["chosen"]
    _written(tx, narrow["params"]["wind"]["x_mps"])
    _written(tsd, narrow["params"]["wind"]["sd_mps"])
    f, factor, a, k = quoted(
        page,
        r"`s:drag-low` \(factor ([\d.]+)\) is the constant now \(([\d.]+)\): the law it was "
        r"given,\s+`factor = a \+ k · stroke_m` \(a ([\d.]+), k (−[\d.]+) /m\)",
    )
    dl = rows["s:drag-low"]
    assert float(f) == _case("s:drag-low")[0]["value"] and dl["passes"] and not dl["laws"]
    _written(factor, dl["params"]["drag_scale"]["factor"])
    assert (a, k) == ("0.793", "−8.77")  # the table before, as the page tells it
    dw = rows["s:downwash"]
    radius, moved, scatter = quoted(
        page,
        r"through a jet ([\d.]+) m\s+wide at the rotor, which the throws leave soon after release: "
        r"it moves the logged points\s+by ([\d.]+) mm RMS .*? against the tracker's scatter of "
        r"(\d+) mm",
    )
    from cell.gap.check_scene import _JET

    assert float(radius) == _JET["radius_m"]
    _mm(moved, dw["world_effect_m"])
    _mm(scatter, _case_noise())
    assert (dw["truth"], rows["s:downwash+wind"]["truth"]) == ("none", "wind")
    base, floor = quoted(
        page, r"the baseline,\s+(\d+) mm, equals the world's effect-free floor, (\d+) mm\)"
    )
    close(base, 1000 * dw["baseline_m"], 0)
    close(floor, 1000 * dw["world_floor_m"], 0)
    long_, tool, b_f = quoted(page, r"on the long drone flights \((\d+) mm, against the\s+tool's "
                              r"floor of (\d+) mm: B / F ([\d.]+), on the verdict's line\)")  # fmt: skip
    close(long_, 1000 * dw["baseline_m"], 0)
    close(tool, 1000 * dw["tool_floor_m"], 0)
    close(b_f, dw["baseline_m"] / dw["tool_floor_m"], 2)
    assert rows["s:none-drone"]["verdict"] == "none"
    fx, fy, tx, ty = quoted(
        page,
        r"In `s:downwash\+wind` the wind is found \(([\d.]+)/([\d.]+) for (\d+)/(\d+)\s+"
        r"m/s\) and named\.",
    )
    assert rows["s:downwash+wind"]["passes"]
    _written(fx, rows["s:downwash+wind"]["params"]["wind"]["x_mps"])
    _written(fy, rows["s:downwash+wind"]["params"]["wind"]["y_mps"])
    w = _case("s:downwash+wind")[1]
    assert (float(tx), float(ty)) == (w["x_mps"], w["y_mps"])
    _check_the_jet(page, rows)
    mu3, t4, m4 = quoted(
        page,
        r"\(for blocks at μ ([\d.]+) `[^`]+`, its mean over the log within\s+(\d+) % of "
        r"the world's τ ([\d.]+)\)",
    )
    # a law in the mass, judged on its mean over the log (`verdict.law_mean`)
    close(t4, 100 * rows["s:bounce-slide-mu03"]["param_errors"]["bounce.tau_s"], 0)
    _written(m4, rows["s:bounce-slide-mu03"]["world_truth"]["tau_s"])
    assert float(mu3) == _case("s:bounce-slide-mu03")[0]["friction"]
    (above,) = quoted(
        page, r"but A stays above ([\d.]+) × F or the verdict misses: a\s+block that tumbles"
    )
    from tests.figure_checks_scene import check_the_edge_and_the_changes

    check_the_edge_and_the_changes(rows, float(above))
    mu5, a5, ratio2, without5, dep, before5 = quoted(
        page,
        r"bouncy floor at μ ([\d.]+) \(`s:bounce-hop-mu05`\) the drop law stands for the "
        r"bounce, A ([\d.]+) F\s+\(`bounce`: within ([\d.]+) × the tool's floor, since the slide "
        r"is braked by the air as the\s+flight is; it was ([\d.]+) F without\), its floor's depth "
        r"(\d+) % off the world's:.*?which stood for it before, left ([\d.]+) F",
    )
    hop5 = rows["s:bounce-hop-mu05"]
    assert float(mu5) == _case("s:bounce-hop-mu05")[0]["friction"]
    close(a5, hop5["after_over_floor"], 2)
    assert (
        float(ratio2) == load_json("docs/figures/gap_check_scene.json")["criteria"]["floor_ratio"]
    )
    close(dep, 100 * hop5["param_errors"]["bounce.depth_m"], 0)
    assert hop5["laws"] == {"bounce": "inv_mu_drop = a + k · mass_kg"} and hop5["passes"]
    assert without5 == "1.35"  # the table before the air on the slide, as the page tells it
    assert before5 == "1.41"  # the table before the drop law, as the page tells it
    was5, now5, dep0, dep1 = quoted(
        page,
        r"`s:bounce-hop-mu05` ([\d.]+) → ([\d.]+) F, its parameters within the tolerance "
        r"\(the depth (\d+) → (\d+) %",
    )
    assert (was5, dep0) == ("1.73", "37")  # the drop law's constant, as the page tells it
    assert (now5, dep1) == ("1.35", "18")  # that change's table (the air's is in the table now)
    assert now5 == without5 and hop5["params_ok"]
    (cubes,) = quoted(page, r"\(`s:none-cubes`, A ([\d.]+) F\)")
    close(cubes, rows["s:none-cubes"]["after_over_floor"], 2)
    assert rows["s:none-cubes"]["passes"] and rows["s:wind+bounce"]["passes"]
    assert rows["s:wind+hop"]["passes"]
    dh = rows["s:drag+hop"]
    da, dk = quoted(
        page,
        r"`s:drag\+hop`'s drag was given a law in the stroke, `factor = a \+ k · stroke_m` with a"
        r"\s+([\d.]+), k (−[\d.]+) /m, for the world's constant factor, until the rule",
    )
    assert (da, dk) == ("2.63", "−16.9")  # the table before, as the page tells it
    assert dh["verdict"] == "bounce+drag_scale" and dh["passes"] and "drag_scale" not in dh["laws"]
    was5, now5, was_roll, now_roll = quoted(
        page,
        r"`s:bounce-hop-mu05` ([\d.]+) → ([\d.]+) F and `s:bounce-roll`\s+([\d.]+) → ([\d.]+) F "
        r"stay `unknown`",
    )
    assert (was5, was_roll) == ("1.65", "1.22")  # the table before the impact law
    assert now5 == "1.41"  # that step's table (the drop law's is in the table now)
    assert now_roll == "1.15"  # the table after the impact law, as the page tells it
    was_roll2, now_roll2 = quoted(
        page,
        r"`s:bounce-roll` is `bounce\+stroke_offset` at\s+([\d.]+) F \(it was "
        r"`bounce\+tracking_scale` at ([\d.]+) F\)",
    )[::-1]
    assert was_roll2 == now_roll  # the table before the rule across the impact velocity
    assert now_roll2 == "1.16"  # that step's table (the drop law's is in the table now)
    (sh,) = quoted(page, r"the bounce alone, its 1/μ\s+([\d.]+) absorbing the scale")
    _written(sh, rows["s:scale+hop"]["params"]["bounce"]["inv_mu"])


# -- docs/realtime.md ------------------------------------------------------------------------


def _case_noise() -> float:
    """The scene world's tracker scatter per axis [m] (`draw_scene_campaign`'s default)."""
    import inspect

    from cell.gap.world_scene import draw_scene_campaign

    return float(inspect.signature(draw_scene_campaign).parameters["noise_m"].default)


def _check_the_jet(page: str, rows: dict[str, dict[str, Any]]) -> None:
    """The wide jet, named by the downwash family's jet member (docs/gap_laws.md)."""
    strong, pair = rows["s:downwash-strong"], rows["s:downwash-strong+wind"]
    assert strong["passes"] and pair["passes"]
    assert strong["laws"] == {"downwash": "jet"} and pair["laws"]["downwash"] == "jet"
    before, a1, speed, radius, w_speed, w_radius, a2, fx, fy, tx, ty, n0, n1, total = quoted(
        page,
        r"could not take \(`unknown`, A ([\d.]+) F\), is named `downwash`,\s+phase flight, alone "
        r"\(A ([\d.]+) F; speed ([\d.]+) m/s and radius ([\d.]+) m at the rotor, for the\s+world's "
        r"(\d+) and ([\d.]+) in a law of another falloff\) and beside the wind \(A ([\d.]+) F, the "
        r"wind\s+([\d.]+)/([\d.]+) for (\d+)/(\d+) m/s\)\. .*? (\d+) → (\d+) of (\d+) pass",
    )
    assert before == "1.14"  # the table before the jet member, as the page tells it
    close(a1, strong["after_over_floor"], 2)
    _written(speed, strong["params"]["downwash"]["speed_mps"])
    _written(radius, strong["params"]["downwash"]["radius_m"])
    from cell.gap.check_scene import _JET_STRONG

    assert (float(w_speed), float(w_radius)) == (_JET_STRONG["w_mps"], _JET_STRONG["radius_m"])
    close(a2, pair["after_over_floor"], 2)
    _written(fx, pair["params"]["wind"]["x_mps"])
    _written(fy, pair["params"]["wind"]["y_mps"])
    w = _case("s:downwash-strong+wind")[1]
    assert (float(tx), float(ty)) == (w["x_mps"], w["y_mps"])
    # the jet member's step, as the page tells it (later steps moved the count on)
    assert (n0, n1, total) == ("21", "23", "42")
    # the latest step: the bounce's impact law and the null case on the flight objects
    m0, t0, m1, t1 = quoted(page, r"(\d+) of (\d+)\s+→ (\d+) of (\d+) pass\. `s:wind\+bounce`")
    assert (m0, t0, m1, t1) == ("23", "42", "26", "43")  # that step, as the page tells it
