"""The random-layout benchmark's measure of the flywheel: second throws against first."""

import math

from cell.bench.bench_sort import repeat_figures


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
