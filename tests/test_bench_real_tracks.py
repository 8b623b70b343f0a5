"""`python -m cell.bench.bench_real_tracks` (docs/figures/real_tracks.json, quoted by
docs/gap-tracks.md) reads the shipped real tracks as the tests do, and its second fit finds
on a flight what the test's independent fit (tests/test_gap_real_tracks.py) finds."""

from __future__ import annotations

import numpy as np

from cell.bench import bench_real_tracks as brt
from tests.real_tracks import cube_log, jugglebot_log, tabletennis_flights, tennicam_log
from tests.test_gap_real_tracks import (
    CLEAN_TT,
    SKIP,
    TC_SKIP,
    _cube_usable,
    _independent,
    _independent_tc,
    _independent_tt,
)


def test_the_bench_reads_the_tracks_as_the_tests_do() -> None:
    rows, tracks = brt._jugglebot_log()
    rows_t, tracks_t = jugglebot_log()
    assert [r["throw_id"] for r in rows] == [r["throw_id"] for r in rows_t]
    for r, rt in zip(rows, rows_t, strict=True):
        for key, v in r.items():
            assert v == rt[key] or np.isclose(v, rt[key], rtol=0, atol=1e-12), key
    assert tracks.keys() == tracks_t.keys()
    for tid in tracks:
        np.testing.assert_array_equal(tracks[tid], tracks_t[tid])
    tt, tt_t = brt._tabletennis_flights(), tabletennis_flights()
    assert tt.keys() == tt_t.keys() and brt.TT_CLEAN == CLEAN_TT
    for tid in tt:
        np.testing.assert_array_equal(tt[tid], tt_t[tid])
    assert brt.JB_SKIP == SKIP
    rows, tracks = brt._tennicam_log()
    rows_t, tracks_t = tennicam_log()
    assert rows == rows_t and tracks.keys() == tracks_t.keys() and brt.TC_SKIP == TC_SKIP
    for tid in tracks:
        np.testing.assert_array_equal(tracks[tid], tracks_t[tid])
    rows, tracks, n_all = brt._cube_log()
    rows_t, tracks_t = cube_log(_cube_usable())
    assert n_all == 570 and rows == rows_t and tracks.keys() == tracks_t.keys()
    for tid in tracks:
        np.testing.assert_array_equal(tracks[tid], tracks_t[tid])


def test_the_bench_second_fit_is_the_tests_independent_fit() -> None:
    _, tracks = jugglebot_log()
    tr = tracks["s7-b1"] if "s7-b1" in tracks else next(iter(tracks.values()))
    mine = brt._fit(tr[SKIP:, 0] - tr[SKIP, 0], tr[SKIP:, 1:4], True)
    np.testing.assert_allclose(mine, _independent(tr), rtol=1e-6, atol=1e-9)
    flight = tabletennis_flights()[CLEAN_TT[0]]
    mine_tt = brt._fit(flight[:, 0], flight[:, 1:4], False)
    np.testing.assert_allclose(mine_tt, _independent_tt(flight), rtol=1e-6, atol=1e-9)
    _, tracks_c = tennicam_log()
    tr = tracks_c["e07"]
    mine_tc = brt._fit(tr[TC_SKIP:, 0] - tr[TC_SKIP, 0], tr[TC_SKIP:, 1:4], False)
    np.testing.assert_allclose(mine_tc, _independent_tc(tr)[0], rtol=1e-6, atol=1e-9)
