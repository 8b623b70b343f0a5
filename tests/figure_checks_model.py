"""The checks of the figures of the model, the benchmarks and the diagnosis that README.md and
the guide pages quote (run by tests/test_readme_figures.py)."""

from __future__ import annotations

from tests.figure_quotes import ROOT, close, every, load_json, num, quoted


# -- cell bench ------------------------------------------------------------------------------
def check_the_bench_table() -> None:
    page, bench = "docs/figures.md", load_json("docs/figures/bench.json")
    (rate,) = quoted(page, r"\| `predictions_per_s`:[^|]*\| ([\d,]+) \|")
    assert num(rate) == bench["predictions_per_s"]
    (dev,) = quoted(page, r"\| `prediction_max_dev_m`:[^|]*\| ([\d.]+) mm \|")
    close(dev, 1000 * bench["prediction_max_dev_m"], 2)
    n, objects, ident = quoted(
        page,
        r"\| `identify_s`: two-stage identification, (\d+) throws of (\d+) objects \| ([\d.]+) s",
    )
    assert (int(n), int(objects)) == (bench["identify_throws"], bench["identify_objects"])
    close(ident, bench["identify_s"], 1)
    fast, fast95 = quoted(page, r"\| `plan_fast_median_ms`[^|]*\| ([\d.]+) / ([\d.]+) ms \|")
    close(fast, bench["plan_fast_median_ms"], 2)
    close(fast95, bench["plan_fast_p95_ms"], 2)
    nlp, nlp95 = quoted(page, r"\| `plan_nlp_median_ms`[^|]*\| ([\d.]+) / ([\d.]+) ms \|")
    close(nlp, bench["plan_nlp_median_ms"], 1)
    close(nlp95, bench["plan_nlp_p95_ms"], 1)
    (ik,) = quoted(page, r"\| `ik_median_ms`:[^|]*\| ([\d.]+) ms \|")
    close(ik, bench["ik_median_ms"], 2)
    (traj,) = quoted(page, r"\| `trajectory_median_ms`:[^|]*\| ([\d.]+) ms \|")
    close(traj, bench["trajectory_median_ms"], 1)
    (carry,) = quoted(page, r"\| `carry_median_ms`:[^|]*\| ([\d.]+) ms \|")
    close(carry, bench["carry_median_ms"], 0)
    n, gap = quoted(page, r"\| `gap_s`: the sim-to-real diagnosis of (\d+) throws \| ([\d.]+) s \|")
    assert int(n) == bench["gap_throws"]
    close(gap, bench["gap_s"], 1)
    (rate,) = quoted("README.md", r"\| landing predictions per second[^|]*\| ([\d,]+) \|")
    assert num(rate) == bench["predictions_per_s"]
    (fast,) = quoted("README.md", r"\| a throw plan, median[^|]*\| ([\d.]+) ms \|")
    close(fast, bench["plan_fast_median_ms"], 2)


def check_the_scene_reach() -> None:
    bench, breakdown = (
        load_json("docs/figures/bench.json"),
        load_json("docs/figures/scene_reach_breakdown.json"),
    )
    (reach,) = quoted("docs/figures.md", r"`scene_reach_err_pct` \*\*([\d.]+) %\*\*")
    close(reach, bench["scene_reach_err_pct"], 2)
    reach, n = quoted("README.md", r"reach error ([\d.]+) % RMS over (\d+) ad-hoc throws")
    close(reach, bench["scene_reach_err_pct"], 2)
    assert int(n) == bench["scene_reach_throws"]
    n, pct, inside, slow_pct, slow = quoted(
        "docs/figures.md",
        r"Over (\d+) throws of another seed.*?: ([\d.]+) % over (\d+) inside the envelope, "
        r"([\d.]+) % over the (\d+)\s",
    )
    assert int(n) == breakdown["n"] and int(inside) == breakdown["all"]["n"]
    close(pct, breakdown["all"]["rms_pct"], 2)
    assert int(slow) == breakdown["slow"]["n"]
    close(slow_pct, breakdown["slow"]["rms_pct"], 2)


# -- the model: identification, residual, repeatability --------------------------------------
def check_identification() -> None:
    ident, bench = load_json("docs/figures/identify.json"), load_json("docs/figures/bench.json")
    everything = ident["objects"]["all"]
    before, after, n = quoted(
        "README.md", r"held-out landing RMSE ([\d.]+) → ([\d.]+) m on (\d+) synthetic"
    )
    close(before, everything["landing_rmse_before_m"], 3)
    close(after, everything["landing_rmse_after_m"], 3)
    assert int(n) == ident["throws"]
    n, objects, before, after, floor = quoted(
        "docs/figures.md",
        r"(\d+) synthetic throws of the (\d+) identification objects.*?RMSE goes from ([\d.]+) m "
        r"to ([\d.]+) m, against a noise floor .*? of ([\d.]+) m",
    )
    assert (int(n), int(objects)) == (ident["throws"], len(ident["objects"]) - 1)
    close(before, everything["landing_rmse_before_m"], 3)
    close(after, everything["landing_rmse_after_m"], 3)
    assert float(floor) == bench["identify_noise_floor_m"]


def check_the_residual() -> None:
    unseen = load_json("docs/figures/residual_unseen_synthetic.json")
    for learner in ("svr", "rf", "mlp"):
        before, after = quoted(
            "docs/figures.md", rf"\| {learner.upper()} \| ([\d.]+) → ([\d.]+) m \|"
        )
        close(before, unseen[learner]["rmse_before_m"], 3)
        close(after, unseen[learner]["rmse_after_m"], 3)
    n_obj, n_throws = quoted("docs/figures.md", r"then used on (\d+) unseen objects × (\d+) throws")
    assert int(n_obj) == len(unseen["svr"]["per_object"])
    assert {int(n_throws)} == {o["throws"] for o in unseen["svr"]["per_object"].values()}
    n_obj, before, after = quoted(
        "README.md",
        r"\| residual learning, (\d+) unseen objects[^|]*\| landing RMSE ([\d.]+) → ([\d.]+) m \(SVR\)",
    )
    assert int(n_obj) == len(unseen["svr"]["per_object"])
    close(before, unseen["svr"]["rmse_before_m"], 3)
    close(after, unseen["svr"]["rmse_after_m"], 3)
    scene = load_json("docs/figures/residual_unseen_scene.json")
    for page, pattern in (
        ("README.md", r"unseen objects' landing RMSE ([\d.]+) → ([\d.]+) m"),
        ("docs/figures.md", r"unseen objects' landing RMSE from ([\d.]+) m to ([\d.]+) m"),
    ):
        before, after = quoted(page, pattern)
        close(before, scene["rmse_before_m"], 3)
        close(after, scene["rmse_after_m"], 3)
    for obj, before, after in every(
        "docs/figures.md", r"(duck|teddy|rock_472|shard_661) \(?([\d.]+) → ([\d.]+) m"
    ):
        close(before, scene["per_object"][obj]["rmse_before_m"], 3)
        close(after, scene["per_object"][obj]["rmse_after_m"], 3)


def check_the_repeatability() -> None:
    rows = [r for r in load_json("docs/figures/repeatability.json") if (r["rotor_rpm"] or 0) > 0]
    m = quoted(
        "docs/figures.md",
        r"reach is ([\d.]+), ([\d.]+) and ([\d.]+) m at (\d+), (\d+) and (\d+) rpm against the "
        r"thesis' ([\d.]+), ([\d.]+) and ([\d.]+) m: within the thesis' spread",
    )
    assert len(rows) == 3
    for i, r in enumerate(rows):
        close(m[i], r["reach_m"], 3)
        assert int(m[3 + i]) == r["rotor_rpm"]
        close(m[6 + i], r["thesis_reach_m"], 3)
        assert r["within_spread"]


# -- the diagnosis ---------------------------------------------------------------------------
def check_the_gap_check() -> None:
    check = load_json("docs/figures/gap_check.json")
    page = "docs/diagnosis.md"
    right, total, minutes = quoted(
        page, r"(\d+)/(\d+) verdicts right, in ([\d.]+) min of diagnosis"
    )
    assert (int(right), int(total)) == (check["correct"], check["total"])
    close(minutes, sum(c["seconds"] for c in check["campaigns"]) / 60.0, 2)
    (n,) = quoted(page, r"draws campaigns of (\d+) throws")
    assert {int(n)} == {c["throws"] for c in check["campaigns"]}
    rows = every(
        page,
        r"\| `([^`]+)` \| [^|]+ \| ([a-z_+]+) \| ([a-z]+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|",
    )
    by_case = {c["case"]: c for c in check["campaigns"]}
    assert [r[0] for r in rows] == list(by_case)
    for case, verdict, where, floor, base, ratio in rows:
        c = by_case[case]
        assert (verdict, where, c["correct"]) == (c["verdict"], c["where"], True)
        close(floor, c["noise_floor_m"], 4)
        close(base, c["baseline_m"], 4)
        close(ratio, c["after_m"] / c["noise_floor_m"], 2)
    right, total = quoted("README.md", r"\| (\d+) of (\d+) verdicts right \|")
    other = load_json("docs/figures/gap_check_other.json")
    passes, cases, n = quoted(
        "README.md", r"\| (\d+) of (\d+) cases pass \| `cell gap check --worlds other --n (\d+)"
    )
    assert (int(passes), int(cases)) == (other["passes"], other["total"])
    assert int(n) == int(quoted("docs/gap_laws.md", r"--worlds other --n (\d+) --workers")[0])
    assert (int(right), int(total)) == (check["correct"], check["total"])
    scene = load_json("docs/figures/gap_check_scene.json")
    passes, cases, n = quoted(
        "README.md",
        r"\| (\d+) of (\d+) cases pass \(\[why the others fail\]\(docs/gap_scene.md\)\) \| "
        r"`cell gap check --worlds scene --n (\d+)",
    )
    assert (int(passes), int(cases)) == (scene["passes"], scene["total"])
    passes, cases = quoted(
        "README.md", r"The diagnosis in the scene\*\* passes (\d+) of its (\d+) cases"
    )
    assert (int(passes), int(cases)) == (scene["passes"], scene["total"])
    assert f"--worlds scene --n {n} --workers" in (ROOT / "Makefile").read_text()


def check_the_scene_gap() -> None:
    nominal, ident = (
        load_json("docs/scene_gap/nominal.json"),
        load_json("docs/scene_gap/identified.json"),
    )
    cands = {c["effect"]: c for c in nominal["candidates"]}
    page = "docs/diagnosis.md"
    rmse, floor, worst, partial, pair, refused = quoted(
        page,
        r"held-out landing RMSE is ([\d.]+) m over a noise floor of ([\d.]+) m.*?cube30 ([\d.]+) m"
        r".*?best partial cause \(−([\d.]+) %; with `shape_stretch` beside it −([\d.]+) %\); "
        r"`drag_scale` cut more \(−([\d.]+) %\)",
    )
    close(rmse, nominal["baseline"]["heldout_rmse_m"], 2)
    close(floor, nominal["noise_floor_m"], 3)
    close(worst, nominal["where"]["worst"][0]["heldout_rmse_m"], 2)
    assert nominal["where"]["worst"][0]["level"] == "cube30"
    assert nominal["verdict"]["effects"] == ["unknown"]
    close(partial, cands["band_mass"]["shrink_pct"], 1)
    assert nominal["verdict"]["partial_effects"] == ["band_mass", "shape_stretch"]
    close(pair, nominal["verdict"]["shrink_pct"], 1)
    close(refused, cands["drag_scale"]["shrink_pct"], 1)
    assert cands["drag_scale"]["refused"]
    before, after, pct, lo, hi, a_g, alo, ahi, k_g, klo, khi = quoted(
        page,
        r"([\d.]+) → ([\d.]+) m \(−([\d.]+) %, interval\s+([\d.]+)–([\d.]+) %\), a band mass that "
        r"falls with the stroke, `mass_kg = a \+ k · stroke_m` with a\s+(\d+) g \((\d+)–(\d+) g\) "
        r"and k (−\d+) g/m \((−\d+) to (−\d+) g/m\)",
    )
    v = ident["verdict"]
    assert v["effects"] == ["band_mass"] and v["laws"] == {
        "band_mass": "mass_kg = a + k · stroke_m"
    }
    close(before, ident["baseline"]["heldout_rmse_m"], 3)
    close(after, v["heldout_rmse_m"], 3)
    close(pct, v["shrink_pct"], 1)
    close(lo, v["shrink_ci_pct"][0], 1)
    close(hi, v["shrink_ci_pct"][1], 1)
    p, ci = v["params"]["band_mass"], v["params_ci95"]["band_mass"]
    for q, val in ((a_g, p["a"]), (alo, ci["a"][0]), (ahi, ci["a"][1]), (k_g, p["k"]),
                   (klo, ci["k"][0]), (khi, ci["k"][1])):  # fmt: skip
        close(q.replace("−", "-"), 1000 * val, 0)
    rmse, before, after = quoted(
        "README.md",
        r"held-out landing RMSE ([\d.]+) m, verdict `unknown`; re-identified first, "
        r"`band_mass`: ([\d.]+) → ([\d.]+) m",
    )
    close(rmse, nominal["baseline"]["heldout_rmse_m"], 2)
    close(before, ident["baseline"]["heldout_rmse_m"], 3)
    close(after, v["heldout_rmse_m"], 3)


def check_the_probe() -> None:
    """docs/gap_laws.md's probe table and the README's count are those of
    docs/figures/probe_unseen.json (examples/probe_unseen_effects.py --json)."""
    probe = load_json("docs/figures/probe_unseen.json")
    rows = every(
        "docs/gap_laws.md",
        r"\| `([a-z_0-9]+)` \| ([a-z_+]+) \| ([a-z]+) \| `([\d.]+)` \| `([\d.]+)` \| `([\d.]+)` "
        r"\| `([\d.]+)` \| `([\d.]+)` \| [^\n]*\| (OK|PARTIAL|NOT OK) \|",
    )
    by_case = {r["case"]: r for r in probe["rows"]}
    assert [r[0] for r in rows] == list(by_case)
    for case, verdict, where, effect, floor_w, floor, base, ratio, judged in rows:
        r = by_case[case]
        assert (verdict, where, judged) == (r["verdict"], r["where"], r["judged"])
        close(effect, r["effect_m"] / r["world_floor_m"], 1)
        close(floor_w, r["world_floor_m"], 3)
        close(floor, r["tool_floor_m"], 3)
        close(base, r["baseline_m"], 3)
        close(ratio, r["after_over_floor"], 2)
    ok, total = quoted("README.md", r"\| (\d+) of (\d+) cases OK \(`unknown` with the world")
    assert (int(ok), int(total)) == (sum(r["ok"] for r in probe["rows"]), len(probe["rows"]))
    (n,) = quoted("docs/gap_laws.md", r"`(\d+)` throws a case over")
    assert {int(n)} == {probe["n"]}
