"""The README quotes figures; `make figures` regenerates them with the JSON beside each. Here
each quoted figure is read from the README and compared with the last generated JSON, so a
figure in the README cannot go stale without this failing."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _json(rel: str) -> dict:
    path = ROOT / rel
    assert path.is_file(), f"{rel} is missing: run `make figures`"
    return json.loads(path.read_text())


def _quoted(pattern: str) -> tuple[str, ...]:
    m = re.search(pattern, README)
    assert m, f"the README no longer quotes {pattern!r}"
    return m.groups()


def test_the_demo_table_is_the_last_generated_run() -> None:
    run = _json("docs/figures/run.json")
    n_in, pct = _quoted(r"in the right bin\s+(\d+) \(([\d.]+) %\)")
    assert int(n_in) == run["in_bin"]
    assert float(pct) == pytest.approx(100 * run["in_bin_rate"], abs=0.05)
    (mean,) = _quoted(r"landing error mean\s+([\d.]+) m")
    assert float(mean) == pytest.approx(run["mean_landing_error_m"], abs=5e-4)
    (p95,) = _quoted(r"landing error p95\s+([\d.]+) m")
    assert float(p95) == pytest.approx(run["p95_landing_error_m"], abs=5e-4)
    (rate,) = _quoted(r"items per hour\s+([\d,]+) \(simulated")
    assert int(rate.replace(",", "")) == round(run["items_per_hour"])


def test_the_scene_residual_figure_is_the_last_generated_one() -> None:
    scene = _json("docs/figures/residual_unseen_scene.json")
    before, after = _quoted(r"unseen objects' landing RMSE from ([\d.]+) m to ([\d.]+) m")
    assert float(before) == pytest.approx(scene["rmse_before_m"], abs=5e-4)
    assert float(after) == pytest.approx(scene["rmse_after_m"], abs=5e-4)


def test_the_scene_gap_quote_is_the_last_generated_report() -> None:
    report = _json("docs/scene_gap/nominal.json")
    (rmse,) = _quoted(r"landing RMSE \*\*([\d.]+) m\*\*")
    assert float(rmse) == pytest.approx(report["baseline"]["heldout_rmse_m"], abs=5e-3)


def test_the_benchmark_table_is_the_last_generated_bench() -> None:
    bench = _json("docs/figures/bench.json")
    (rate,) = _quoted(r"\| `predictions_per_s`:[^|]*\| ([\d,]+) \|")
    assert int(rate.replace(",", "")) == bench["predictions_per_s"]
    fast, fast95 = _quoted(r"\| `plan_fast_median_ms`[^|]*\| ([\d.]+) / ([\d.]+) ms \|")
    assert float(fast) == pytest.approx(bench["plan_fast_median_ms"], abs=0.005)
    assert float(fast95) == pytest.approx(bench["plan_fast_p95_ms"], abs=0.005)
    (gap,) = _quoted(r"\| `gap_s`:[^|]*\| ([\d.]+) s \|")
    # quoted to 0.1 s: half of that, and a hair for a value that ends in 5 (29.75 -> 29.8)
    assert float(gap) == pytest.approx(bench["gap_s"], abs=0.05 + 1e-9)
    (ident,) = _quoted(r"\| `identify_s`:[^|]*\| ([\d.]+) s ")
    assert float(ident) == pytest.approx(bench["identify_s"], abs=0.05 + 1e-9)
    (carry,) = _quoted(r"\| `carry_median_ms`:[^|]*\| ([\d.]+) ms \|")
    assert float(carry) == pytest.approx(bench["carry_median_ms"], abs=0.5 + 1e-9)


def test_table_5_1_unseen_column_is_the_last_generated_example_08() -> None:
    unseen = _json("docs/figures/residual_unseen_synthetic.json")
    for learner in ("svr", "rf", "mlp"):
        before, after = _quoted(rf"\| {learner.upper()} \|[^|]*\|[^|]*\| ([\d.]+) → ([\d.]+) m \|")
        assert float(before) == pytest.approx(unseen[learner]["rmse_before_m"], abs=5e-4)
        assert float(after) == pytest.approx(unseen[learner]["rmse_after_m"], abs=5e-4)


def test_the_random_layout_figures_are_the_last_generated_bench_sort() -> None:
    bench = _json("docs/figures/bench_sort.json")
    rate, lo, hi = _quoted(r"`in_bin_rate` \*\*([\d.]+)\*\* \(95 % interval ([\d.]+)–([\d.]+)\)")
    assert float(rate) == pytest.approx(bench["in_bin_rate"], abs=5e-4)
    assert float(lo) == pytest.approx(bench["in_bin_rate_lo"], abs=5e-4)
    assert float(hi) == pytest.approx(bench["in_bin_rate_hi"], abs=5e-4)
    (unseen,) = _quoted(r"`in_bin_rate_unseen` \*\*([\d.]+)\*\*")
    assert float(unseen) == pytest.approx(bench["in_bin_rate_unseen"], abs=5e-4)
    (items,) = _quoted(r"[Oo]ver (\d+) items of 20\s+layouts")
    assert int(items) == bench["items"]
    (rate_h,) = _quoted(r"`items_per_hour` \*\*([\d,]+)\*\*")
    assert int(rate_h.replace(",", "")) == round(bench["items_per_hour"])
    refused, drawn = _quoted(r"(\d+) of the (\d+) kinds\s+drawn were drawn again")
    assert (int(refused), int(drawn)) == (bench["kinds_refused_at_draw"], bench["kinds_drawn"])
    (reach,) = _quoted(r"`scene_reach_err_pct` \*\*([\d.]+) %\*\*")
    assert float(reach) == pytest.approx(
        _json("docs/figures/bench.json")["scene_reach_err_pct"], abs=0.05
    )


def test_the_floor_is_the_last_generated_bench_sort() -> None:
    bench = _json("docs/figures/bench_sort.json")
    rate, panda, ur5 = _quoted(
        r"`floor_items_per_hour` \*\*([\d,]+)\*\*\s+\([\d,]+ s instead of [\d,]+ s; "
        r"Panda ([\d,]+), UR5 ([\d,]+)"
    )
    assert int(rate.replace(",", "")) == round(bench["floor_items_per_hour"])
    for robot, quoted in (("panda", panda), ("ur5", ur5)):
        rows = [r for r in bench["per_layout"] if r["robot"] == robot]
        k = sum(r["in_bin"] for r in rows)
        sim = sum(r["floor_sim_time_s"] for r in rows)
        assert int(quoted.replace(",", "")) == round(3600.0 * k / sim)
    floor_s, sim_s = _quoted(r"\(([\d,]+) s instead of ([\d,]+) s; Panda")
    assert int(floor_s.replace(",", "")) == round(bench["floor_sim_time_s"])
    assert int(sim_s.replace(",", "")) == round(bench["sim_time_s"])
    (at_95,) = _quoted(r"these\s+floor cycles give ([\d,]+) items per hour")
    assert int(at_95.replace(",", "")) == round(
        3600.0 * 0.95 * bench["items"] / bench["floor_sim_time_s"]
    )


def _check_campaign(quoted: tuple[str, ...], bench: dict) -> None:
    """A campaign's quoted (in bin, items, in-bin rate, its interval's ends, the rate on
    unseen items, items per hour) against its JSON."""
    n_in, items, rate, lo, hi, unseen, rate_h = quoted
    assert (int(n_in), int(items)) == (bench["in_bin"], bench["items"])
    assert float(rate) == pytest.approx(bench["in_bin_rate"], abs=5e-4)
    assert float(lo) == pytest.approx(bench["in_bin_rate_lo"], abs=5e-4)
    assert float(hi) == pytest.approx(bench["in_bin_rate_hi"], abs=5e-4)
    assert float(unseen) == pytest.approx(bench["in_bin_rate_unseen"], abs=5e-4)
    assert int(rate_h.replace(",", "")) == round(bench["items_per_hour"])


def test_the_moving_releases_and_repeat_throws_are_the_last_generated_bench_sort() -> None:
    bench = _json("docs/figures/bench_sort.json")
    moving, thrown = _quoted(r"(\d+) of the (\d+)\s+throws were released on the move")
    assert (int(moving), int(thrown)) == (bench["released_moving"], bench["thrown"])
    pairs, second, first, closer = _quoted(
        r"\((\d+) pairs, without `--learn`\) lands at a median ([\d.]+) mm from the\s+point "
        r"it was aimed at against ([\d.]+) mm for its first, closer in (\d+) % of the pairs"
    )
    assert int(pairs) == bench["repeat_pairs"]
    assert float(second) == pytest.approx(1000 * bench["repeat_second_median_error_m"], abs=0.05)
    assert float(first) == pytest.approx(1000 * bench["repeat_first_median_error_m"], abs=0.05)
    assert int(closer) == round(100 * bench["repeat_second_closer_rate"])


def test_the_tradeoff_caption_is_the_last_generated_tradeoff() -> None:
    points = _json("docs/figures/tradeoff.json")["points"]
    for p in points:
        scale = f"{p['speed_scale']:g}"
        rate_h, rate, lo, hi = _quoted(
            rf"×{re.escape(scale)}: ([\d,]+) items per hour at ([\d.]+) \(([\d.]+)–([\d.]+)\)"
        )
        assert int(rate_h.replace(",", "")) == round(p["items_per_hour"])
        assert float(rate) == pytest.approx(p["in_bin_rate"], abs=5e-4)
        assert float(lo) == pytest.approx(p["in_bin_rate_lo"], abs=5e-3)
        assert float(hi) == pytest.approx(p["in_bin_rate_hi"], abs=5e-3)


def test_the_flywheel_figures_are_the_last_generated_ones() -> None:
    fw = _json("docs/figures/flywheel.json")
    # the same named groups in both sentences; a number quoted twice must agree ((?P=…))
    tail = (
        r"\((?P<in1>\d+)/(?P<n>\d+) → (?P<in2>\d+)/(?P=n) in their bins; median (?P<d1>[\d.]+) "
        r"→ (?P<d2>[\d.]+) mm, (?P<closer>\d+) of (?P<both>\d+) closer\)"
    )
    sentences = {
        "bins": r"`tasks/bins.yaml` run twice into a fresh store the thrown items' mean landing "
        r"error goes (?P<m1>[\d.]+) → (?P<m2>[\d.]+) mm " + tail,
        "random_3_ur5": r"--seed 3 --robot ur5` \((?P<n0>\d+) items\) (?P<m1>[\d.]+) → "
        r"(?P<m2>[\d.]+) mm over the (?P<both0>\d+) items thrown both times " + tail,
    }
    for name, pattern in sentences.items():
        m = re.search(pattern.replace(" ", r"\s+"), README)
        assert m, f"the README no longer quotes the flywheel's {name} figures"
        g, f = m.groupdict(), fw[name]
        assert int(g["n"]) == f["items"] and int(g["both"]) == f["thrown_both"]
        assert int(g.get("n0") or g["n"]) == f["items"]
        assert int(g.get("both0") or g["both"]) == f["thrown_both"]
        assert (int(g["in1"]), int(g["in2"]), int(g["closer"])) == (
            f["in_bin_first"],
            f["in_bin_second"],
            f["second_closer"],
        )
        for group, key in (
            ("m1", "mean_landing_error_first_m"),
            ("m2", "mean_landing_error_second_m"),
            ("d1", "median_landing_error_first_m"),
            ("d2", "median_landing_error_second_m"),
        ):
            assert float(g[group]) == pytest.approx(1000 * f[key], abs=0.05)


def _check_option_campaign(option: str, bench: dict) -> None:
    """An option's random-layout benchmark as the README quotes it (`… OPTION --floor`: in
    bin, items, rate and interval, unseen rate, items per hour, floor) against its JSON."""
    pattern = (
        r"--floor`: (\d+) of (\d+) in their bins, ([\d.]+) "
        r"\(([\d.]+)–([\d.]+)\), ([\d.]+) on the items never calibrated, ([\d,]+) items per "
        r"hour, floor ([\d,]+)"
    ).replace(" ", r"\s+")
    words = r"\s+".join(re.escape(w) for w in option.split())
    m = re.search(words + r"\s+" + pattern, README)
    assert m, f"the README no longer quotes the {option} benchmark"
    n_in, items, rate, lo, hi, unseen, rate_h, floor = m.groups()
    _check_campaign((n_in, items, rate, lo, hi, unseen, rate_h), bench)
    assert int(floor.replace(",", "")) == round(bench["floor_items_per_hour"])


def test_the_bin_order_figures_are_the_last_generated_ones() -> None:
    _check_option_campaign("--order bins", _json("docs/figures/bench_sort_bins.json"))
    run, demo = _json("docs/figures/run_bins.json"), _json("docs/figures/run.json")
    n_in, items, rate_h, rate_default = _quoted(
        r"`cell run tasks/bins.yaml --order bins`: (\d+)/(\d+)\s+in their bins, ([\d,]+) "
        r"items per hour against ([\d,]+)"
    )
    assert (int(n_in), int(items)) == (run["in_bin"], run["items"])
    assert int(rate_h.replace(",", "")) == round(run["items_per_hour"])
    assert int(rate_default.replace(",", "")) == round(demo["items_per_hour"])


def test_the_plain_planner_figures_are_the_last_generated_ones() -> None:
    """`--no-cycle-search --no-turn-release` over the random layouts and on the demo."""
    _check_option_campaign(
        "--no-cycle-search --no-turn-release", _json("docs/figures/bench_sort_plain.json")
    )
    run, demo = _json("docs/figures/run_plain.json"), _json("docs/figures/run.json")
    pattern = (
        r"`cell run tasks/bins.yaml --no-cycle-search --no-turn-release`: (\d+)/(\d+) in their "
        r"bins, ([\d,]+) items per hour, (\d+) s of wall time against (\d+) s by default"
    )
    m = re.search(pattern.replace(" ", r"\s+"), README)
    assert m, "the README no longer quotes the demo without the release search"
    n_in, items, rate_h, wall, wall_default = m.groups()
    assert (int(n_in), int(items)) == (run["in_bin"], run["items"])
    assert int(rate_h.replace(",", "")) == round(run["items_per_hour"])
    assert (int(wall), int(wall_default)) == (round(run["wall_time_s"]), round(demo["wall_time_s"]))
