"""README.md and the guide pages under docs/ quote figures; `make figures` regenerates them
with the JSON beside each. Here each quoted figure is read from its page and compared with the
last generated JSON (or, for the rules and limits the pages state, with the code), so a figure
cannot go stale without this failing; and every number written on those pages must be one of
the figures checked here, or a non-measurement named in EXEMPT (`test_every_number_has_a_source`).

docs/HISTORY.md is a dated record of past measurements at named commits, not regenerated,
and is not checked against today's JSON (its top says so)."""

from __future__ import annotations

import math
import re
from collections.abc import Callable

import pytest

from tests.figure_checks_cube import check_the_real_cube
from tests.figure_checks_grip import check_the_grip_page
from tests.figure_checks_guides import (
    check_the_cli_limits,
    check_the_gap_laws,
    check_the_gap_tracks_rules,
    check_the_identify_evidence,
    check_the_real_launcher_flights,
    check_the_real_table_tennis,
    check_the_real_tracks,
)
from tests.figure_checks_model import (
    check_identification,
    check_the_bench_table,
    check_the_gap_check,
    check_the_probe,
    check_the_repeatability,
    check_the_residual,
    check_the_scene_gap,
    check_the_scene_reach,
)
from tests.figure_checks_pages import (
    check_the_arms_page,
    check_the_gap_scene_prose,
    check_the_gap_scene_table,
    check_the_realtime_page,
    check_the_ur3_reach,
)
from tests.figure_quotes import (
    COVERED,
    PAGES,
    close,
    every,
    load_json,
    note,
    num,
    page_text,
    quoted,
)


# -- the demo --------------------------------------------------------------------------------
def check_the_demo_table() -> None:
    run = load_json("docs/figures/run.json")
    for page in ("README.md",):
        rows = dict(every(page, r"\n  (items|placed|thrown|not released) +(\d+)(?=\n)"))
        assert {k: int(v) for k, v in rows.items()} == {
            "items": run["items"],
            "placed": run["placed"],
            "thrown": run["thrown"],
            "not released": run["failed"],  # the items stopped before their release
        }
        n_in, pct = quoted(page, r"in the right bin +(\d+) \(([\d.]+) %\)")
        assert int(n_in) == run["in_bin"]
        close(pct, 100 * run["in_bin_rate"], 1)
        (mean,) = quoted(page, r"landing error mean +([\d.]+) m")
        close(mean, run["mean_landing_error_m"], 3)
        (p95,) = quoted(page, r"landing error p95 +([\d.]+) m")
        close(p95, run["p95_landing_error_m"], 3)
        (cycle,) = quoted(page, r"mean cycle time +([\d.]+) s")
        close(cycle, run["mean_cycle_time_s"], 2)
        (rate,) = quoted(page, r"items per hour +([\d,]+) \(simulated")
        assert num(rate) == round(run["items_per_hour"])
        (wall,) = quoted(page, r"wall time +([\d.]+) s")
        close(wall, run["wall_time_s"], 1)
        med, p95, most, cores, workers = quoted(
            page,
            r"planning per item +median ([\d.]+) s, p95 ([\d.]+) s, max ([\d.]+) s \(wall "
            r"time, (\d+) cores(?:, (\d+) plan workers?)?\)",
        )
        for q, key in ((med, "plan_s_median"), (p95, "plan_s_p95"), (most, "plan_s_max")):
            close(q, run[key], 2)
        assert int(cores) == run["cores"]
        if workers is not None:  # quoted from a run that printed them (`plan_workers`)
            assert int(workers) == run["plan_workers"]
        (realtime,) = quoted(page, r"real-time items/h +([\d,]+) \(planning overlapped")
        assert num(realtime) == round(run["items_per_hour_realtime"])
    check_the_planning_row("the demo", run)
    wall, sim = quoted("README.md", r"(\d+) s of wall time against (\d+) s simulated")
    assert (int(wall), int(sim)) == (round(run["wall_time_s"]), round(run["sim_time_s"]))
    plain = load_json("docs/figures/run_plain.json")
    p95, rate = quoted(
        "README.md",
        r"([\d.]+) s with `--no-cycle-search --no-turn-release` \(([\d,]+) items per hour\)",
    )
    close(p95, plain["plan_s_p95"], 2)
    assert num(rate) == round(plain["items_per_hour"])
    ur10, ur3 = load_json("docs/figures/run_ur10.json"), load_json("docs/figures/run_ur3.json")
    got = quoted(
        "README.md",
        r"UR10 (\d+)/(\d+) in their bins, ([\d,]+) items per hour; UR3 (\d+)/(\d+), ([\d,]+) "
        r"items per hour",
    )
    for (n_in, n, rate), r in ((got[:3], ur10), (got[3:], ur3)):
        assert (int(n_in), int(n), num(rate)) == (
            r["in_bin"],
            r["items"],
            round(r["items_per_hour"]),
        )
    n_in, n, rate, err = quoted(
        "README.md",
        r"the demo job \| (\d+)/(\d+) in their bins, ([\d,]+) items per hour, mean landing "
        r"error ([\d.]+) m",
    )
    assert (int(n_in), int(n), num(rate)) == (
        run["in_bin"],
        run["items"],
        round(run["items_per_hour"]),
    )
    close(err, run["mean_landing_error_m"], 3)
    page = "docs/figures.md"
    n_in, n, mean, p95, cycle, rate, wall = quoted(
        page,
        r"(\d+) of (\d+) items in the right bin, landing error mean ([\d.]+) m, p95 ([\d.]+) m, "
        r"a mean cycle of ([\d.]+) s, ([\d,]+) items per hour \(simulated time\), in a wall "
        r"time of (\d+) s",
    )
    assert (int(n_in), int(n)) == (run["in_bin"], run["items"])
    close(mean, run["mean_landing_error_m"], 3)
    close(p95, run["p95_landing_error_m"], 3)
    close(cycle, run["mean_cycle_time_s"], 2)
    assert num(rate) == round(run["items_per_hour"])
    assert int(wall) == round(run["wall_time_s"])


def check_the_planning_row(what: str, fig: dict) -> None:
    """The README's row "planning per item on WHAT": p95, real-time and simulated rate."""
    verdict, p95, realtime, rate = quoted(
        "README.md",
        rf"planning per item on {what} \(goal p95 ≤ 0.5 s: (met|missed)\) \| "
        r"p95 ([\d.]+) s; ([\d,]+) items per hour in real time against ([\d,]+) simulated",
    )
    close(p95, fig["plan_s_p95"], 2)
    assert verdict == ("met" if fig["plan_s_p95"] <= 0.5 else "missed")
    assert num(realtime) == round(fig["items_per_hour_realtime"])
    assert num(rate) == round(fig["items_per_hour"])


def check_the_demo_variants() -> None:
    page, demo = "docs/figures.md", load_json("docs/figures/run.json")
    plain, bins = load_json("docs/figures/run_plain.json"), load_json("docs/figures/run_bins.json")
    n_in, n, rate, wall, wall0 = quoted(
        page,
        r"`cell run tasks/bins.yaml --no-cycle-search --no-turn-release`: (\d+)/(\d+) in their "
        r"bins, ([\d,]+) items per hour, (\d+) s of wall time against (\d+) s by default",
    )
    assert (int(n_in), int(n), num(rate)) == (
        plain["in_bin"],
        plain["items"],
        round(plain["items_per_hour"]),
    )
    assert (int(wall), int(wall0)) == (round(plain["wall_time_s"]), round(demo["wall_time_s"]))
    n_in, n, rate, rate0 = quoted(
        page,
        r"`cell run tasks/bins.yaml --order bins`: (\d+)/(\d+) in their bins, ([\d,]+) items "
        r"per hour against ([\d,]+)",
    )
    assert (int(n_in), int(n), num(rate)) == (
        bins["in_bin"],
        bins["items"],
        round(bins["items_per_hour"]),
    )
    assert num(rate0) == round(demo["items_per_hour"])


# -- the random layouts ----------------------------------------------------------------------
def check_the_random_layouts() -> None:
    bench = load_json("docs/figures/bench_sort_tune.json")
    for page in ("docs/figures.md",):
        rate, lo, hi = quoted(
            page, r"`in_bin_rate` \*\*([\d.]+)\*\* \(95 % interval ([\d.]+)–([\d.]+)\)"
        )
        for q, key in ((rate, "in_bin_rate"), (lo, "in_bin_rate_lo"), (hi, "in_bin_rate_hi")):
            close(q, bench[key], 3)
        (unseen,) = quoted(page, r"`in_bin_rate_unseen` \*\*([\d.]+)\*\*")
        close(unseen, bench["in_bin_rate_unseen"], 3)
        items, layouts = quoted(page, r"[Oo]ver (\d+) items of (\d+) layouts")
        assert (int(items), int(layouts)) == (bench["items"], bench["layouts"])
        (rate_h,) = quoted(page, r"`items_per_hour` \*\*([\d,]+)\*\*")
        assert num(rate_h) == round(bench["items_per_hour"])
        refused, drawn = quoted(page, r"(\d+) of the (\d+) kinds drawn were drawn again")
        assert (int(refused), int(drawn)) == (bench["kinds_refused_at_draw"], bench["kinds_drawn"])
        dropped, missed = quoted(
            page, r"`dropped_while_carried` (\d+), `missed_bin` (\d+) \(by object"
        )
        assert (int(dropped), int(missed)) == (
            bench["failures"].get("dropped_while_carried", 0),
            bench["failures"].get("missed_bin", 0),
        )
        n, last = quoted(page, r"draws (\d+) sort jobs \(`cell job random`, seeds 0–(\d+),")
        assert (int(n), int(last)) == (bench["layouts"], bench["layouts"] - 1)
        COVERED[page].append(
            re.search(r"random`, seeds\s+(0)–", page_text(page)).span(1)  # type: ignore[union-attr]
        )
    check_the_headline(bench)


def check_the_headline(tune: dict) -> None:
    """README's headline is the `test` layouts (bench_sort.json); the `tune` figure beside it."""
    bench = load_json("docs/figures/bench_sort.json")
    assert (bench["set"], tune["set"]) == ("test", "tune")
    n_items, rate, lo, hi, unseen, rate_h = quoted(
        "README.md",
        r"\| (\d+) items: in-bin rate ([\d.]+) \(95 % interval ([\d.]+)–([\d.]+)\), ([\d.]+) on "
        r"items never calibrated, ([\d,]+) items per hour \|",
    )
    assert int(n_items) == bench["items"]
    for q, key in ((rate, "in_bin_rate"), (lo, "in_bin_rate_lo"), (hi, "in_bin_rate_hi")):
        close(q, bench[key], 3)
    close(unseen, bench["in_bin_rate_unseen"], 3)
    assert num(rate_h) == round(bench["items_per_hour"])
    (n_layouts,) = quoted("README.md", r"\| (\d+) random jobs the cell has never seen \(the `test`")
    assert int(n_layouts) == bench["layouts"]
    n_tune, rate_tune, rate_h_tune = quoted(
        "README.md", r"\| (\d+) items: in-bin rate ([\d.]+), ([\d,]+) items per hour \|"
    )
    assert int(n_tune) == tune["items"]
    close(rate_tune, tune["in_bin_rate"], 3)
    assert num(rate_h_tune) == round(tune["items_per_hour"])
    (floor,) = quoted("README.md", r"\(a floor for the cell's poses\) \| ([\d,]+) items per hour")
    assert num(floor) == round(bench["floor_items_per_hour"])
    check_the_planning_row("the `test` layouts", bench)
    wall, sim = quoted(
        "README.md",
        r"real time against [\d,]+ simulated, ([\d,]+) s of wall time against ([\d,]+) s "
        r"simulated \(one layout",
    )
    assert (num(wall), num(sim)) == (round(bench["wall_time_s"]), round(bench["sim_time_s"]))
    (rate_h,) = quoted(
        "README.md", r"The `test` layouts make\s+([\d,]+) items per hour against a goal of 1,500"
    )
    assert num(rate_h) == round(bench["items_per_hour"])
    (dropped,) = quoted("README.md", r"(No) item was dropped while carried on the\s+`test` layouts")
    assert bench["failures"].get("dropped_while_carried", 0) == 0
    quoted("README.md", r"nor on the `tune` (ones)")
    tune = load_json("docs/figures/bench_sort_tune.json")
    assert tune["failures"].get("dropped_while_carried", 0) == 0
    slowest = [lay for lay in bench["per_layout"] if lay["slowest_item"] == "o5_tetrapack"]
    (n_slowest,) = quoted("README.md", r"a placed tetrapack is the slowest item of (\w+) layouts")
    assert n_slowest == {1: "one", 2: "two", 3: "three", 4: "four"}.get(len(slowest))
    (missed,) = quoted("README.md", r"bounce out: (\d+) of the `test` layouts' items missed")
    assert int(missed) == bench["failures"].get("missed_bin", 0)
    from cell.arm.tuning import TUNING

    rim, steep = quoted(
        "README.md", r"rim is under ([\d.]+) m the cell throws steeply\s+\(the throw axis (\d+)°"
    )
    assert float(rim) == TUNING.steep_rim_m
    assert int(steep) == round(math.degrees(TUNING.steep_elevation_rad))


def check_the_layout_sets() -> None:
    """The sets' seeds as docs/figures.md gives them are `cell.bench.bench_sort.LAYOUT_SETS`."""
    from cell.bench.bench_sort import LAYOUT_SETS

    test_from, tune_lo, tune_hi, chosen_lo, chosen_hi = quoted(
        "docs/figures.md",
        r"`--set test` \(the default,\s+seeds from (\d+)\).*?`--set tune` \(seeds (\d+)–(\d+)\),"
        r".*?\(on (\d+)–(\d+)\)",
    )
    assert int(test_from) == LAYOUT_SETS["test"][0]
    assert (int(tune_lo), int(tune_hi) + 1) == LAYOUT_SETS["tune"]
    tune = load_json("docs/figures/bench_sort_tune.json")
    assert [int(chosen_lo), int(chosen_hi)] == tune["seeds"]
    (seed,) = quoted("docs/figures.md", r"`cell bench sort --set tune --layouts 20 --seed (\d+)")
    assert int(seed) == tune["seeds"][0]
    lo, hi, seed = quoted(
        "docs/arm.md",
        r"the `tune` layouts, seeds (\d+)–(\d+)\s+\(`cell bench sort --set tune --seed (\d+)`",
    )
    assert [int(lo), int(hi)] == tune["seeds"] and int(seed) == tune["seeds"][0]


def check_the_floor() -> None:
    page, bench = "docs/figures.md", load_json("docs/figures/bench_sort_tune.json")
    rate, floor_s, sim_s, panda, ur5 = quoted(
        page,
        r"`floor_items_per_hour` \*\*([\d,]+)\*\* \(([\d,]+) s instead of ([\d,]+) s; "
        r"Panda ([\d,]+), UR5 ([\d,]+)\)",
    )
    assert num(rate) == round(bench["floor_items_per_hour"])
    assert (num(floor_s), num(sim_s)) == (
        round(bench["floor_sim_time_s"]),
        round(bench["sim_time_s"]),
    )
    for robot, q in (("panda", panda), ("ur5", ur5)):
        rows = [r for r in bench["per_layout"] if r["robot"] == robot]
        k = sum(r["in_bin"] for r in rows)
        assert num(q) == round(3600.0 * k / sum(r["floor_sim_time_s"] for r in rows))
    share, at = quoted(
        page, r"with ([\d.]+) of the items in their bins these floor cycles give ([\d,]+) items"
    )
    assert num(at) == round(3600.0 * float(share) * bench["items"] / bench["floor_sim_time_s"])


def check_the_moving_releases_and_repeat_throws() -> None:
    page, bench = "docs/figures.md", load_json("docs/figures/bench_sort_tune.json")
    moving, thrown = quoted(page, r"(\d+) of the (\d+) throws were released on the move")
    assert (int(moving), int(thrown)) == (bench["released_moving"], bench["thrown"])
    pairs, second, first, closer = quoted(
        page,
        r"\((\d+) pairs, without `--learn`\) lands at a median ([\d.]+) mm from the point "
        r"it was aimed at against ([\d.]+) mm for its first, closer in (\d+) % of the pairs",
    )
    assert int(pairs) == bench["repeat_pairs"]
    close(second, 1000 * bench["repeat_second_median_error_m"], 1)
    close(first, 1000 * bench["repeat_first_median_error_m"], 1)
    assert int(closer) == round(100 * bench["repeat_second_closer_rate"])


def check_the_options() -> None:
    page = "docs/figures.md"
    for option, rel in (
        ("--no-cycle-search --no-turn-release", "docs/figures/bench_sort_plain.json"),
        ("--order bins", "docs/figures/bench_sort_bins.json"),
    ):
        bench = load_json(rel)
        n_in, items, rate, lo, hi, unseen, rate_h, floor = quoted(
            page,
            r"\s+".join(map(re.escape, option.split()))
            + r" --floor`: (\d+) of (\d+) in their bins, ([\d.]+) "
            r"\(([\d.]+)–([\d.]+)\), ([\d.]+) on the items never calibrated, ([\d,]+) items per "
            r"hour, floor ([\d,]+)",
        )
        assert (int(n_in), int(items)) == (bench["in_bin"], bench["items"])
        for q, key in (
            (rate, "in_bin_rate"),
            (lo, "in_bin_rate_lo"),
            (hi, "in_bin_rate_hi"),
            (unseen, "in_bin_rate_unseen"),
        ):
            close(q, bench[key], 3)
        assert num(rate_h) == round(bench["items_per_hour"])
        assert num(floor) == round(bench["floor_items_per_hour"])


def check_the_tradeoff() -> None:
    page, tradeoff = "docs/figures.md", load_json("docs/figures/tradeoff.json")
    for p in tradeoff["points"]:
        scale = f"{p['speed_scale']:g}"
        s, rate_h, rate, lo, hi = quoted(
            page,
            rf"×({re.escape(scale)}): ([\d,]+) items per hour at ([\d.]+) \(([\d.]+)–([\d.]+)\)",
        )
        assert float(s) == p["speed_scale"]
        assert num(rate_h) == round(p["items_per_hour"])
        close(rate, p["in_bin_rate"], 3)
        close(lo, p["in_bin_rate_lo"], 2)
        close(hi, p["in_bin_rate_hi"], 2)
    missed = quoted(
        page,
        r"missed their bins: (\d+) at ×([\d.]+), (\d+) at ×([\d.]+), (\d+) at ×([\d.]+)\)",
    )
    for n, s in zip(missed[::2], missed[1::2], strict=True):
        (p,) = [p for p in tradeoff["points"] if p["speed_scale"] == float(s)]
        assert int(n) == p["failures"].get("missed_bin", 0), s
    assert "no item was dropped while carried at any speed" in page_text(page)
    assert not any(p["failures"].get("dropped_while_carried") for p in tradeoff["points"])
    (items,) = quoted(page, r"joint limits, (\d+) items a point")
    assert {int(items)} == {p["items"] for p in tradeoff["points"]}
    layout_set, seed = quoted(page, r"`cell bench tradeoff --set (\w+) --layouts 4 --seed (\d+)")
    # a figure made before `--set` was there holds no "set": it ran seeds 0-3, the tune set
    assert (layout_set, int(seed)) == (tradeoff.get("set", "tune"), tradeoff.get("seeds", [0])[0])


def check_the_flywheel() -> None:
    page, fw = "docs/figures.md", load_json("docs/figures/flywheel.json")
    tail = (
        r"\((?P<in1>\d+)/(?P<n>\d+) → (?P<in2>\d+)/(?P=n) in their bins; median (?P<d1>[\d.]+) "
        r"→ (?P<d2>[\d.]+) mm, (?P<closer>\d+) of (?P<both>\d+) closer\)"
    )
    sentences = {
        "bins": r"run twice into a fresh store the thrown items' mean landing error goes "
        r"(?P<m1>[\d.]+) → (?P<m2>[\d.]+) mm " + tail,
        "random_3_ur5": r"--robot ur5` \((?P<n0>\d+) items\) (?P<m1>[\d.]+) → (?P<m2>[\d.]+) mm "
        r"over the (?P<both0>\d+) items thrown both times " + tail,
    }
    for name, pattern in sentences.items():
        m = re.search(pattern.replace(" ", r"\s+"), page_text(page))
        assert m, f"{page} no longer quotes the flywheel's {name} figures"
        note(page, m)
        COVERED[page].append(m.span("n") if m.group("n") else (0, 0))
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
            close(g[group], 1000 * f[key], 1)
        # the repeated "/n" of the second ratio
        i = m.start("in2")
        COVERED[page].append((i, m.end("d1")))


CHECKS: tuple[Callable[[], None], ...] = (
    check_the_demo_table,
    check_the_demo_variants,
    check_the_random_layouts,
    check_the_floor,
    check_the_moving_releases_and_repeat_throws,
    check_the_options,
    check_the_tradeoff,
    check_the_flywheel,
    check_the_bench_table,
    check_the_scene_reach,
    check_identification,
    check_the_residual,
    check_the_repeatability,
    check_the_gap_check,
    check_the_scene_gap,
    check_the_probe,
    check_the_gap_tracks_rules,
    check_the_real_tracks,
    check_the_real_table_tennis,
    check_the_real_launcher_flights,
    check_the_real_cube,
    check_the_identify_evidence,
    check_the_cli_limits,
    check_the_layout_sets,
    check_the_gap_laws,
    check_the_arms_page,
    check_the_ur3_reach,
    check_the_realtime_page,
    check_the_gap_scene_table,
    check_the_gap_scene_prose,
    check_the_grip_page,
)


@pytest.mark.parametrize("check", CHECKS, ids=lambda f: f.__name__)
def test_the_quoted_figures_are_the_last_generated(check: Callable[[], None]) -> None:
    check()


# -- every number has a source ---------------------------------------------------------------
# Numbers on the pages that are not measurements, each with why (a pattern; its digits are
# exempt). Everything else must be a figure checked above.
EXEMPT: tuple[tuple[str, str, str], ...] = (
    ("*", r"(?:Python|Protocol|design) [\d.]+", "a version or a design's name"),
    ("*", r"(?:Table|Fig\.|§|Algorithm) ?[\d.–]+", "the thesis' tables, figures, sections"),
    ("*", r"(?m)^\d+\. ", "a numbered list"),
    ("*", r"95 % interval", "the confidence level of an interval"),
    ("*", r"2-core|2 cores|on one core", "the machine the figures were measured on"),
    ("*", r"\d{4}-\d{2}-\d{2}", "a date"),
    ("*", r"[≥≤] [\d,.]+ (?:m?s|mm)?|goal [\d,]+|goal of [\d,]+", "a goal, not a measurement"),
    ("*", r"exit 2\b", "the exit status of a refused input (tests/test_mounts.py runs it)"),
    ("*", r"ISO \d+", "a standard's number"),
    ("docs/gap_scene.md", r"/ 2g|1/μ|1 / \(1 \+|\(1 \+", "a formula's constants"),
    ("README.md", r"\(100\.0 %\)", "checked with its count (in_bin_rate)"),
    ("docs/figures.md", r"interval 0\.948–0\.977", "checked (bench_sort_tune.json)"),
)


def _strip(page: str, text: str) -> str:
    """The page with what is not prose blanked out (same length): input and command blocks,
    inline code, link targets, the citation."""

    def blank(m: re.Match) -> str:
        return re.sub(r"[^\n]", " ", m.group(0))

    lines, fence = text.split("\n"), ""
    for i, line in enumerate(lines):
        if line.startswith("```"):
            fence = "" if fence else (line[3:].strip() or "plain")
            lines[i] = " " * len(line)
        elif fence and fence != "text":  # input and commands; program output is checked
            lines[i] = " " * len(line)
    text = "\n".join(lines)
    text = re.sub(r"`[^`\n]*`", blank, text)
    text = re.sub(r"\]\([^)]*\)", blank, text)
    if page == "README.md":
        text = re.sub(r"## Citation\n.*", blank, text, flags=re.S)
    return text


def test_every_number_has_a_source() -> None:
    for spans in COVERED.values():
        spans.clear()
    for check in CHECKS:
        check()
    missing = []
    for page in PAGES:
        text = _strip(page, page_text(page))
        covered = list(COVERED[page])
        for where, pattern, _why in EXEMPT:
            if where in ("*", page):
                covered.extend(m.span() for m in re.finditer(pattern, text))
        for m in re.finditer(r"(?<![\w.\-/])\d+(?:,\d{3})*(?:\.\d+)?", text):
            if not any(a <= m.start() and m.end() <= b for a, b in covered):
                line = text.count("\n", 0, m.start()) + 1
                missing.append(f"{page}:{line}: {m.group(0)}")
    assert not missing, "numbers without a source:\n" + "\n".join(missing)
