"""The random-layout benchmark's figures from its layouts: the flywheel's measure (second
throws against first) and each layout's own figures."""

import math

from cell.bench.bench_sort import failures_by_object, per_layout, repeat_figures, summarise_layouts
from cell.orchestrator import FAILURES


def _it(oid: str, err: float, action: str = "throw") -> dict:
    return {"object_id": oid, "landing_error_m": err, "action": action}


def test_repeat_figures_pair_each_objects_first_two_throws_within_a_layout():
    layouts = [
        {"items": [_it("a", 0.30), _it("b", 0.10), _it("a", 0.05), _it("a", 0.9), _it("b", 0.2)]},
        # a place, a failure (NaN) and an object thrown once make no pair
        {"items": [_it("a", 0.02, "place"), _it("a", math.nan), _it("a", 0.4), _it("c", 0.1)]},
    ]
    f = repeat_figures(layouts)
    assert f["repeat_pairs"] == 2  # (a: 0.30 → 0.05) and (b: 0.10 → 0.20); the 3rd a is not paired
    assert f["repeat_second_closer_rate"] == 0.5
    assert f["repeat_first_median_error_m"] == 0.30  # upper median of [0.10, 0.30]
    assert f["repeat_second_median_error_m"] == 0.20


def test_repeat_figures_without_pairs_are_nan():
    f = repeat_figures([{"items": [_it("a", 0.1)]}])
    assert f["repeat_pairs"] == 0 and math.isnan(f["repeat_second_closer_rate"])


def _lay(seed, robot, cycles_in, sim, refused=""):
    items = [
        {
            "object_id": f"o{i}",
            "cycle_time_s": c,
            "in_bin": ok,
            "landing_error_m": 0.01,
            "action": "throw",
            "failure": "" if ok else "missed_bin",
            "unseen": False,
        }
        for i, (c, ok) in enumerate(cycles_in)
    ]
    return {
        "seed": seed,
        "robot": robot,
        "items": items,
        "sim_time_s": sim,
        "wall_time_s": 1.0,
        "refused": refused,
    }


def test_per_layout_figures_add_up_to_the_campaigns():
    layouts = [
        _lay(3, "panda", [(2.0, True), (5.0, True), (3.0, False)], 10.0),
        _lay(4, "ur5", [(1.5, True), (2.5, True)], 4.0),
        _lay(5, "panda", [], 0.0, refused="bin_2: out of reach"),
    ]
    rows = per_layout(layouts)
    assert [r["seed"] for r in rows] == [3, 4, 5]
    assert rows[0]["items_per_hour"] == 3600.0 * 2 / 10.0
    assert rows[0]["median_cycle_s"] == 3.0
    assert (rows[0]["slowest_item"], rows[0]["slowest_cycle_s"]) == ("o1", 5.0)
    assert rows[1]["median_cycle_s"] == 2.5  # the upper median of two
    assert rows[2]["refused"] and rows[2]["items_per_hour"] == 0.0
    assert math.isnan(rows[2]["median_cycle_s"])
    total = summarise_layouts(layouts)
    assert total["per_layout"] == rows
    assert sum(r["in_bin"] for r in rows) == total["in_bin"] == 4
    assert sum(r["sim_time_s"] for r in rows) == total["sim_time_s"]
    assert total["items_per_hour"] == 3600.0 * 4 / 14.0


def test_failures_by_object_count_each_reason_per_object_and_add_up():
    def item(oid: str, failure: str) -> dict:
        return {"object_id": oid, "failure": failure}

    items = [
        item("bottle", "dropped_while_carried"),
        item("cube", "missed_bin"),
        item("bottle", "dropped_while_carried"),
        item("cube", ""),
        item("egg", "missed_bin"),
        item("cube", "missed_bin"),
        item("duck", "ik"),
    ]
    f = failures_by_object(items)
    assert f == {
        "ik": {"duck": 1},
        "dropped_while_carried": {"bottle": 2},
        "missed_bin": {"cube": 2, "egg": 1},
    }
    assert list(f) == [r for r in FAILURES if r in f]  # in the fixed list's order
    assert list(f["missed_bin"]) == ["cube", "egg"]  # most frequent first
    assert sum(sum(v.values()) for v in f.values()) == sum(bool(it["failure"]) for it in items)
    layouts = [_lay(3, "panda", [(2.0, True), (3.0, False), (3.0, False)], 10.0)]
    total = summarise_layouts(layouts)
    assert total["failures_by_object"] == {"missed_bin": {"o1": 1, "o2": 1}}
    assert sum(total["failures"].values()) == 2


def test_the_kinds_drawn_again_are_summed_over_the_layouts():
    from cell.bench.bench_sort import refused_at_draw

    a, b = _lay(0, "panda", [(2.0, True)], 2.0), _lay(1, "ur5", [(2.0, True)], 2.0)
    a.update(refused_at_draw=["rock_000", "adhoc cube", "rock_000"], kinds_drawn=9)
    b.update(refused_at_draw=["cuboid_a"], kinds_drawn=5)
    f = refused_at_draw([a, b, _lay(2, "panda", [], 0.0)])  # an older result has neither key
    assert f["kinds_drawn"] == 14 and f["kinds_refused_at_draw"] == 4
    assert list(f["refused_at_draw_by_object"].items()) == [
        ("rock_000", 2),
        ("adhoc cube", 1),
        ("cuboid_a", 1),
    ]
    assert summarise_layouts([a, b])["kinds_refused_at_draw"] == 4
