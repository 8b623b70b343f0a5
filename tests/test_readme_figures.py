"""README.md and the guide pages under docs/ quote figures; `make figures` regenerates them
with the JSON beside each. Here each quoted figure is read from its page and compared with the
last generated JSON (or, for the rules and limits the pages state, with the code), so a figure
cannot go stale without this failing; and every number written on those pages must be one of
the figures checked here, or a non-measurement named in EXEMPT (`test_every_number_has_a_source`).

docs/HISTORY.md is a dated record of past measurements at named commits, not regenerated,
and is not checked against today's JSON (its top says so)."""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# the pages whose numbers must each have a source (docs/HISTORY.md is a dated record)
PAGES = (
    "README.md",
    "docs/jobs.md",
    "docs/throw_log.md",
    "docs/diagnosis.md",
    "docs/campaigns.md",
    "docs/recordings.md",
    "docs/hardware.md",
    "docs/figures.md",
)
_COVERED: dict[str, list[tuple[int, int]]] = {p: [] for p in PAGES}


def _text(page: str) -> str:
    return (ROOT / page).read_text()


def _json(rel: str) -> dict:
    path = ROOT / rel
    assert path.is_file(), f"{rel} is missing: run `make figures`"
    return json.loads(path.read_text())


def _note(page: str, m: re.Match) -> None:
    _COVERED[page].extend(m.span(g) for g in range(1, (m.re.groups or 0) + 1) if m.group(g))


def _quoted(page: str, pattern: str) -> tuple[str, ...]:
    """The groups of the first match of `pattern` on `page` (spaces match any whitespace)."""
    m = re.search(pattern.replace(" ", r"\s+"), _text(page), flags=re.S)
    assert m, f"{page} no longer quotes {pattern!r}"
    _note(page, m)
    return m.groups()


def _every(page: str, pattern: str) -> list[tuple[str, ...]]:
    """The groups of every match of `pattern` on `page` (at least one)."""
    ms = list(re.finditer(pattern.replace(" ", r"\s+"), _text(page)))
    assert ms, f"{page} no longer quotes {pattern!r}"
    for m in ms:
        _note(page, m)
    return [m.groups() for m in ms]


def _num(s: str) -> float:
    return float(s.replace(",", ""))


def _close(quoted: str, value: float, digits: int) -> None:
    """`quoted` is `value` as written to `digits` decimals (half a unit of the last one)."""
    assert _num(quoted) == pytest.approx(value, abs=0.5 * 10**-digits + 1e-9), (quoted, value)


# -- the demo --------------------------------------------------------------------------------
def check_the_demo_table() -> None:
    run = _json("docs/figures/run.json")
    for page in ("README.md",):
        rows = dict(_every(page, r"\n  (items|placed|thrown|failed) +(\d+)(?=\n)"))
        assert {k: int(v) for k, v in rows.items()} == {
            k: run[k] for k in ("items", "placed", "thrown", "failed")
        }
        n_in, pct = _quoted(page, r"in the right bin +(\d+) \(([\d.]+) %\)")
        assert int(n_in) == run["in_bin"]
        _close(pct, 100 * run["in_bin_rate"], 1)
        (mean,) = _quoted(page, r"landing error mean +([\d.]+) m")
        _close(mean, run["mean_landing_error_m"], 3)
        (p95,) = _quoted(page, r"landing error p95 +([\d.]+) m")
        _close(p95, run["p95_landing_error_m"], 3)
        (cycle,) = _quoted(page, r"mean cycle time +([\d.]+) s")
        _close(cycle, run["mean_cycle_time_s"], 2)
        (rate,) = _quoted(page, r"items per hour +([\d,]+) \(simulated")
        assert _num(rate) == round(run["items_per_hour"])
        (wall,) = _quoted(page, r"wall time +([\d.]+) s")
        _close(wall, run["wall_time_s"], 1)
    n_in, n, rate, err = _quoted(
        "README.md",
        r"the demo job \| (\d+)/(\d+) in their bins, ([\d,]+) items per hour, mean landing "
        r"error ([\d.]+) m",
    )
    assert (int(n_in), int(n), _num(rate)) == (
        run["in_bin"],
        run["items"],
        round(run["items_per_hour"]),
    )
    _close(err, run["mean_landing_error_m"], 3)
    page = "docs/figures.md"
    n_in, n, mean, p95, cycle, rate, wall = _quoted(
        page,
        r"(\d+) of (\d+) items in the right bin, landing error mean ([\d.]+) m, p95 ([\d.]+) m, "
        r"a mean cycle of ([\d.]+) s, ([\d,]+) items per hour \(simulated time\), in a wall "
        r"time of (\d+) s",
    )
    assert (int(n_in), int(n)) == (run["in_bin"], run["items"])
    _close(mean, run["mean_landing_error_m"], 3)
    _close(p95, run["p95_landing_error_m"], 3)
    _close(cycle, run["mean_cycle_time_s"], 2)
    assert _num(rate) == round(run["items_per_hour"])
    assert int(wall) == round(run["wall_time_s"])


def check_the_demo_variants() -> None:
    page, demo = "docs/figures.md", _json("docs/figures/run.json")
    plain, bins = _json("docs/figures/run_plain.json"), _json("docs/figures/run_bins.json")
    n_in, n, rate, wall, wall0 = _quoted(
        page,
        r"`cell run tasks/bins.yaml --no-cycle-search --no-turn-release`: (\d+)/(\d+) in their "
        r"bins, ([\d,]+) items per hour, (\d+) s of wall time against (\d+) s by default",
    )
    assert (int(n_in), int(n), _num(rate)) == (
        plain["in_bin"],
        plain["items"],
        round(plain["items_per_hour"]),
    )
    assert (int(wall), int(wall0)) == (round(plain["wall_time_s"]), round(demo["wall_time_s"]))
    n_in, n, rate, rate0 = _quoted(
        page,
        r"`cell run tasks/bins.yaml --order bins`: (\d+)/(\d+) in their bins, ([\d,]+) items "
        r"per hour against ([\d,]+)",
    )
    assert (int(n_in), int(n), _num(rate)) == (
        bins["in_bin"],
        bins["items"],
        round(bins["items_per_hour"]),
    )
    assert _num(rate0) == round(demo["items_per_hour"])
    wall0, wall = _quoted("README.md", r"wall time of (\d+) s against (\d+) s without the search")
    assert (int(wall0), int(wall)) == (round(demo["wall_time_s"]), round(plain["wall_time_s"]))


# -- the random layouts ----------------------------------------------------------------------
def check_the_random_layouts() -> None:
    bench = _json("docs/figures/bench_sort.json")
    for page in ("docs/figures.md",):
        rate, lo, hi = _quoted(
            page, r"`in_bin_rate` \*\*([\d.]+)\*\* \(95 % interval ([\d.]+)–([\d.]+)\)"
        )
        for q, key in ((rate, "in_bin_rate"), (lo, "in_bin_rate_lo"), (hi, "in_bin_rate_hi")):
            _close(q, bench[key], 3)
        (unseen,) = _quoted(page, r"`in_bin_rate_unseen` \*\*([\d.]+)\*\*")
        _close(unseen, bench["in_bin_rate_unseen"], 3)
        items, layouts = _quoted(page, r"[Oo]ver (\d+) items of (\d+) layouts")
        assert (int(items), int(layouts)) == (bench["items"], bench["layouts"])
        (rate_h,) = _quoted(page, r"`items_per_hour` \*\*([\d,]+)\*\*")
        assert _num(rate_h) == round(bench["items_per_hour"])
        refused, drawn = _quoted(page, r"(\d+) of the (\d+) kinds drawn were drawn again")
        assert (int(refused), int(drawn)) == (bench["kinds_refused_at_draw"], bench["kinds_drawn"])
        dropped, missed = _quoted(
            page, r"`dropped_while_carried` (\d+), `missed_bin` (\d+) \(by object"
        )
        assert (int(dropped), int(missed)) == (
            bench["failures"]["dropped_while_carried"],
            bench["failures"]["missed_bin"],
        )
        n, last = _quoted(page, r"draws (\d+) sort jobs \(`cell job random`, seeds 0–(\d+),")
        assert (int(n), int(last)) == (bench["layouts"], bench["layouts"] - 1)
        _COVERED[page].append(
            re.search(r"seeds\s+(0)–", _text(page)).span(1)  # type: ignore[union-attr]
        )
    n_items, rate, lo, hi, unseen, rate_h = _quoted(
        "README.md",
        r"\| (\d+) items: in-bin rate ([\d.]+) \(95 % interval ([\d.]+)–([\d.]+)\), ([\d.]+) on "
        r"items never calibrated, ([\d,]+) items per hour \|",
    )
    assert int(n_items) == bench["items"]
    for q, key in ((rate, "in_bin_rate"), (lo, "in_bin_rate_lo"), (hi, "in_bin_rate_hi")):
        _close(q, bench[key], 3)
    _close(unseen, bench["in_bin_rate_unseen"], 3)
    assert _num(rate_h) == round(bench["items_per_hour"])
    (n_layouts,) = _quoted("README.md", r"\| (\d+) random jobs the cell has never seen \|")
    assert int(n_layouts) == bench["layouts"]
    (floor,) = _quoted("README.md", r"\(a floor for the cell's poses\) \| ([\d,]+) items per hour")
    assert _num(floor) == round(bench["floor_items_per_hour"])
    (rate_h,) = _quoted("README.md", r"make ([\d,]+) items per\s+hour against a goal")
    assert _num(rate_h) == round(bench["items_per_hour"])
    dropped, items = _quoted("README.md", r"layouts (\d+) of (\d+) items were\s+dropped")
    assert (int(dropped), int(items)) == (
        bench["failures"]["dropped_while_carried"],
        bench["items"],
    )
    (missed,) = _quoted("README.md", r"Of the (\d+) items that missed their bins")
    assert int(missed) == bench["failures"]["missed_bin"]


def check_the_floor() -> None:
    page, bench = "docs/figures.md", _json("docs/figures/bench_sort.json")
    rate, floor_s, sim_s, panda, ur5 = _quoted(
        page,
        r"`floor_items_per_hour` \*\*([\d,]+)\*\* \(([\d,]+) s instead of ([\d,]+) s; "
        r"Panda ([\d,]+), UR5 ([\d,]+)\)",
    )
    assert _num(rate) == round(bench["floor_items_per_hour"])
    assert (_num(floor_s), _num(sim_s)) == (
        round(bench["floor_sim_time_s"]),
        round(bench["sim_time_s"]),
    )
    for robot, quoted in (("panda", panda), ("ur5", ur5)):
        rows = [r for r in bench["per_layout"] if r["robot"] == robot]
        k = sum(r["in_bin"] for r in rows)
        assert _num(quoted) == round(3600.0 * k / sum(r["floor_sim_time_s"] for r in rows))
    share, at = _quoted(
        page, r"with ([\d.]+) of the items in their bins these floor cycles give ([\d,]+) items"
    )
    assert _num(at) == round(3600.0 * float(share) * bench["items"] / bench["floor_sim_time_s"])


def check_the_moving_releases_and_repeat_throws() -> None:
    page, bench = "docs/figures.md", _json("docs/figures/bench_sort.json")
    moving, thrown = _quoted(page, r"(\d+) of the (\d+) throws were released on the move")
    assert (int(moving), int(thrown)) == (bench["released_moving"], bench["thrown"])
    pairs, second, first, closer = _quoted(
        page,
        r"\((\d+) pairs, without `--learn`\) lands at a median ([\d.]+) mm from the point "
        r"it was aimed at against ([\d.]+) mm for its first, closer in (\d+) % of the pairs",
    )
    assert int(pairs) == bench["repeat_pairs"]
    _close(second, 1000 * bench["repeat_second_median_error_m"], 1)
    _close(first, 1000 * bench["repeat_first_median_error_m"], 1)
    assert int(closer) == round(100 * bench["repeat_second_closer_rate"])


def check_the_options() -> None:
    page = "docs/figures.md"
    for option, rel in (
        ("--no-cycle-search --no-turn-release", "docs/figures/bench_sort_plain.json"),
        ("--order bins", "docs/figures/bench_sort_bins.json"),
    ):
        bench = _json(rel)
        n_in, items, rate, lo, hi, unseen, rate_h, floor = _quoted(
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
            _close(q, bench[key], 3)
        assert _num(rate_h) == round(bench["items_per_hour"])
        assert _num(floor) == round(bench["floor_items_per_hour"])


def check_the_tradeoff() -> None:
    page, tradeoff = "docs/figures.md", _json("docs/figures/tradeoff.json")
    for p in tradeoff["points"]:
        scale = f"{p['speed_scale']:g}"
        s, rate_h, rate, lo, hi = _quoted(
            page,
            rf"×({re.escape(scale)}): ([\d,]+) items per hour at ([\d.]+) \(([\d.]+)–([\d.]+)\)",
        )
        assert float(s) == p["speed_scale"]
        assert _num(rate_h) == round(p["items_per_hour"])
        _close(rate, p["in_bin_rate"], 3)
        _close(lo, p["in_bin_rate_lo"], 2)
        _close(hi, p["in_bin_rate_hi"], 2)
    dropped = _quoted(
        page,
        r"dropped while carried: (\d+) at ×([\d.]+), (\d+) at ×([\d.]+), (\d+) at ×([\d.]+)\)",
    )
    for n, s in zip(dropped[::2], dropped[1::2], strict=True):
        (p,) = [p for p in tradeoff["points"] if p["speed_scale"] == float(s)]
        assert int(n) == p["failures"].get("dropped_while_carried", 0), s
    (items,) = _quoted(page, r"joint limits, (\d+) items a point")
    assert {int(items)} == {p["items"] for p in tradeoff["points"]}


def check_the_flywheel() -> None:
    page, fw = "docs/figures.md", _json("docs/figures/flywheel.json")
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
        m = re.search(pattern.replace(" ", r"\s+"), _text(page))
        assert m, f"{page} no longer quotes the flywheel's {name} figures"
        _note(page, m)
        _COVERED[page].append(m.span("n") if m.group("n") else (0, 0))
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
            _close(g[group], 1000 * f[key], 1)
        # the repeated "/n" of the second ratio
        i = m.start("in2")
        _COVERED[page].append((i, m.end("d1")))


# -- cell bench ------------------------------------------------------------------------------
def check_the_bench_table() -> None:
    page, bench = "docs/figures.md", _json("docs/figures/bench.json")
    (rate,) = _quoted(page, r"\| `predictions_per_s`:[^|]*\| ([\d,]+) \|")
    assert _num(rate) == bench["predictions_per_s"]
    (dev,) = _quoted(page, r"\| `prediction_max_dev_m`:[^|]*\| ([\d.]+) mm \|")
    _close(dev, 1000 * bench["prediction_max_dev_m"], 2)
    n, objects, ident = _quoted(
        page,
        r"\| `identify_s`: two-stage identification, (\d+) throws of (\d+) objects \| ([\d.]+) s",
    )
    assert (int(n), int(objects)) == (bench["identify_throws"], bench["identify_objects"])
    _close(ident, bench["identify_s"], 1)
    fast, fast95 = _quoted(page, r"\| `plan_fast_median_ms`[^|]*\| ([\d.]+) / ([\d.]+) ms \|")
    _close(fast, bench["plan_fast_median_ms"], 2)
    _close(fast95, bench["plan_fast_p95_ms"], 2)
    nlp, nlp95 = _quoted(page, r"\| `plan_nlp_median_ms`[^|]*\| ([\d.]+) / ([\d.]+) ms \|")
    _close(nlp, bench["plan_nlp_median_ms"], 1)
    _close(nlp95, bench["plan_nlp_p95_ms"], 1)
    (ik,) = _quoted(page, r"\| `ik_median_ms`:[^|]*\| ([\d.]+) ms \|")
    _close(ik, bench["ik_median_ms"], 2)
    (traj,) = _quoted(page, r"\| `trajectory_median_ms`:[^|]*\| ([\d.]+) ms \|")
    _close(traj, bench["trajectory_median_ms"], 1)
    (carry,) = _quoted(page, r"\| `carry_median_ms`:[^|]*\| ([\d.]+) ms \|")
    _close(carry, bench["carry_median_ms"], 0)
    n, gap = _quoted(
        page, r"\| `gap_s`: the sim-to-real diagnosis of (\d+) throws \| ([\d.]+) s \|"
    )
    assert int(n) == bench["gap_throws"]
    _close(gap, bench["gap_s"], 1)
    (rate,) = _quoted("README.md", r"\| landing predictions per second[^|]*\| ([\d,]+) \|")
    assert _num(rate) == bench["predictions_per_s"]
    (fast,) = _quoted("README.md", r"\| a throw plan, median[^|]*\| ([\d.]+) ms \|")
    _close(fast, bench["plan_fast_median_ms"], 2)


def check_the_scene_reach() -> None:
    bench, breakdown = (
        _json("docs/figures/bench.json"),
        _json("docs/figures/scene_reach_breakdown.json"),
    )
    (reach,) = _quoted("docs/figures.md", r"`scene_reach_err_pct` \*\*([\d.]+) %\*\*")
    _close(reach, bench["scene_reach_err_pct"], 2)
    reach, n = _quoted("README.md", r"reach error ([\d.]+) % RMS over (\d+) ad-hoc throws")
    _close(reach, bench["scene_reach_err_pct"], 2)
    assert int(n) == bench["scene_reach_throws"]
    n, pct, inside, slow_pct, slow = _quoted(
        "docs/figures.md",
        r"Over (\d+) throws of another seed.*?: ([\d.]+) % over (\d+) inside the envelope, "
        r"([\d.]+) % over the (\d+)\s",
    )
    assert int(n) == breakdown["n"] and int(inside) == breakdown["all"]["n"]
    _close(pct, breakdown["all"]["rms_pct"], 2)
    assert int(slow) == breakdown["slow"]["n"]
    _close(slow_pct, breakdown["slow"]["rms_pct"], 2)


# -- the model: identification, residual, repeatability --------------------------------------
def check_identification() -> None:
    ident, bench = _json("docs/figures/identify.json"), _json("docs/figures/bench.json")
    everything = ident["objects"]["all"]
    before, after, n = _quoted(
        "README.md", r"held-out landing RMSE ([\d.]+) → ([\d.]+) m on (\d+) synthetic"
    )
    _close(before, everything["landing_rmse_before_m"], 3)
    _close(after, everything["landing_rmse_after_m"], 3)
    assert int(n) == ident["throws"]
    n, objects, before, after, floor = _quoted(
        "docs/figures.md",
        r"(\d+) synthetic throws of the (\d+) identification objects.*?RMSE goes from ([\d.]+) m "
        r"to ([\d.]+) m, against a noise floor .*? of ([\d.]+) m",
    )
    assert (int(n), int(objects)) == (ident["throws"], len(ident["objects"]) - 1)
    _close(before, everything["landing_rmse_before_m"], 3)
    _close(after, everything["landing_rmse_after_m"], 3)
    assert float(floor) == bench["identify_noise_floor_m"]


def check_the_residual() -> None:
    unseen = _json("docs/figures/residual_unseen_synthetic.json")
    for learner in ("svr", "rf", "mlp"):
        before, after = _quoted(
            "docs/figures.md", rf"\| {learner.upper()} \| ([\d.]+) → ([\d.]+) m \|"
        )
        _close(before, unseen[learner]["rmse_before_m"], 3)
        _close(after, unseen[learner]["rmse_after_m"], 3)
    n_obj, n_throws = _quoted(
        "docs/figures.md", r"then used on (\d+) unseen objects × (\d+) throws"
    )
    assert int(n_obj) == len(unseen["svr"]["per_object"])
    assert {int(n_throws)} == {o["throws"] for o in unseen["svr"]["per_object"].values()}
    n_obj, before, after = _quoted(
        "README.md",
        r"\| residual learning, (\d+) unseen objects[^|]*\| landing RMSE ([\d.]+) → ([\d.]+) m \(SVR\)",
    )
    assert int(n_obj) == len(unseen["svr"]["per_object"])
    _close(before, unseen["svr"]["rmse_before_m"], 3)
    _close(after, unseen["svr"]["rmse_after_m"], 3)
    scene = _json("docs/figures/residual_unseen_scene.json")
    for page, pattern in (
        ("README.md", r"unseen objects' landing RMSE ([\d.]+) → ([\d.]+) m"),
        ("docs/figures.md", r"unseen objects' landing RMSE from ([\d.]+) m to ([\d.]+) m"),
    ):
        before, after = _quoted(page, pattern)
        _close(before, scene["rmse_before_m"], 3)
        _close(after, scene["rmse_after_m"], 3)
    for obj, before, after in _every(
        "docs/figures.md", r"(duck|teddy|rock_472|shard_661) \(?([\d.]+) → ([\d.]+) m"
    ):
        _close(before, scene["per_object"][obj]["rmse_before_m"], 3)
        _close(after, scene["per_object"][obj]["rmse_after_m"], 3)


def check_the_repeatability() -> None:
    rows = [r for r in _json("docs/figures/repeatability.json") if (r["rotor_rpm"] or 0) > 0]
    m = _quoted(
        "docs/figures.md",
        r"reach is ([\d.]+), ([\d.]+) and ([\d.]+) m at (\d+), (\d+) and (\d+) rpm against the "
        r"thesis' ([\d.]+), ([\d.]+) and ([\d.]+) m: within the thesis' spread",
    )
    assert len(rows) == 3
    for i, r in enumerate(rows):
        _close(m[i], r["reach_m"], 3)
        assert int(m[3 + i]) == r["rotor_rpm"]
        _close(m[6 + i], r["thesis_reach_m"], 3)
        assert r["within_spread"]


# -- the diagnosis ---------------------------------------------------------------------------
def check_the_gap_check() -> None:
    check = _json("docs/figures/gap_check.json")
    page = "docs/diagnosis.md"
    right, total, minutes = _quoted(
        page, r"(\d+)/(\d+) verdicts right, in ([\d.]+) min of diagnosis"
    )
    assert (int(right), int(total)) == (check["correct"], check["total"])
    _close(minutes, sum(c["seconds"] for c in check["campaigns"]) / 60.0, 2)
    (n,) = _quoted(page, r"draws campaigns of (\d+) throws")
    assert {int(n)} == {c["throws"] for c in check["campaigns"]}
    rows = _every(
        page,
        r"\| `([^`]+)` \| [^|]+ \| ([a-z_+]+) \| ([a-z]+) \| ([\d.]+) \| ([\d.]+) \| ([\d.]+) \|",
    )
    by_case = {c["case"]: c for c in check["campaigns"]}
    assert [r[0] for r in rows] == list(by_case)
    for case, verdict, where, floor, base, ratio in rows:
        c = by_case[case]
        assert (verdict, where, c["correct"]) == (c["verdict"], c["where"], True)
        _close(floor, c["noise_floor_m"], 4)
        _close(base, c["baseline_m"], 4)
        _close(ratio, c["after_m"] / c["noise_floor_m"], 2)
    right, total = _quoted("README.md", r"\| (\d+) of (\d+) verdicts right \|")
    assert (int(right), int(total)) == (check["correct"], check["total"])


def check_the_scene_gap() -> None:
    nominal, ident = _json("docs/scene_gap/nominal.json"), _json("docs/scene_gap/identified.json")
    cands = {c["effect"]: c for c in nominal["candidates"]}
    page = "docs/diagnosis.md"
    rmse, floor, worst, partial, refused = _quoted(
        page,
        r"held-out landing RMSE is ([\d.]+) m over a noise floor of ([\d.]+) m.*?cube30 ([\d.]+) m"
        r".*?best partial cause \(−([\d.]+) %\); `drag_scale` cut more \(−([\d.]+) %\)",
    )
    _close(rmse, nominal["baseline"]["heldout_rmse_m"], 2)
    _close(floor, nominal["noise_floor_m"], 3)
    _close(worst, nominal["where"]["worst"][0]["heldout_rmse_m"], 2)
    assert nominal["where"]["worst"][0]["level"] == "cube30"
    assert nominal["verdict"]["effects"] == ["unknown"]
    _close(partial, cands["band_mass"]["shrink_pct"], 1)
    _close(refused, cands["drag_scale"]["shrink_pct"], 1)
    assert cands["drag_scale"]["refused"]
    before, after, pct, lo, hi, mass, mlo, mhi = _quoted(
        page,
        r"([\d.]+) → ([\d.]+) m \(−([\d.]+) %, interval ([\d.]+)–([\d.]+) %\), a band mass of "
        r"(\d+) g \((\d+)–(\d+) g\)",
    )
    v = ident["verdict"]
    assert v["effects"] == ["band_mass"]
    _close(before, ident["baseline"]["heldout_rmse_m"], 3)
    _close(after, v["heldout_rmse_m"], 3)
    _close(pct, v["shrink_pct"], 1)
    _close(lo, v["shrink_ci_pct"][0], 1)
    _close(hi, v["shrink_ci_pct"][1], 1)
    _close(mass, 1000 * v["params"]["band_mass"]["mass_kg"], 0)
    _close(mlo, 1000 * v["params_ci95"]["band_mass"]["mass_kg"][0], 0)
    _close(mhi, 1000 * v["params_ci95"]["band_mass"]["mass_kg"][1], 0)
    rmse, before, after = _quoted(
        "README.md",
        r"held-out landing RMSE ([\d.]+) m, verdict `unknown`; re-identified first, "
        r"`band_mass`: ([\d.]+) → ([\d.]+) m",
    )
    _close(rmse, nominal["baseline"]["heldout_rmse_m"], 2)
    _close(before, ident["baseline"]["heldout_rmse_m"], 3)
    _close(after, v["heldout_rmse_m"], 3)


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
)


@pytest.mark.parametrize("check", CHECKS, ids=lambda f: f.__name__)
def test_the_quoted_figures_are_the_last_generated_json(check: Callable[[], None]) -> None:
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
    ("README.md", r"\(100\.0 %\)", "checked with its count (in_bin_rate)"),
    ("docs/figures.md", r"interval 0\.945–0\.975", "checked (bench_sort.json)"),
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
    for spans in _COVERED.values():
        spans.clear()
    for check in CHECKS:
        check()
    missing = []
    for page in PAGES:
        text = _strip(page, _text(page))
        covered = list(_COVERED[page])
        for where, pattern, _why in EXEMPT:
            if where in ("*", page):
                covered.extend(m.span() for m in re.finditer(pattern, text))
        for m in re.finditer(r"(?<![\w.\-/])\d+(?:,\d{3})*(?:\.\d+)?", text):
            if not any(a <= m.start() and m.end() <= b for a, b in covered):
                line = text.count("\n", 0, m.start()) + 1
                missing.append(f"{page}:{line}: {m.group(0)}")
    assert not missing, "numbers without a source:\n" + "\n".join(missing)
