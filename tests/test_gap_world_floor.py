"""The world's floor a `cell gap check` row is judged against is counted on the rows the
robust held-out RMSE is counted on: a row the tool flags is out of both (and with it its
repeat's share of the repeats' scatter), an injected outlier is never in the floor."""

from __future__ import annotations

import numpy as np
import pytest

from cell.gap.check_other import FLOOR_RATIO, judge_campaign, other_cases
from cell.gap.world_other import draw_other_campaign


def test_a_scene_floor_on_kept_rows_drops_a_flagged_rows_repeat_pair():
    """Six configurations thrown twice; one pair rests 1 m apart (a block's long slide),
    the others 2 cm apart, and nothing scatters without the effect. By hand: F0² is the
    mean of the rows' effect-free misses², and a pair's pooled variance is |a − b|² / 2
    (one degree of freedom), so F² = F0² + Σ_pairs |a − b|² / 2 / pairs. Leaving one row
    of the wide pair out takes the pair out of V and that row out of F0."""
    pytest.importorskip("pybullet")
    from cell.gap.world_scene import FloorRows, SceneCampaign, draw_plan

    cfg = draw_plan(6, np.random.default_rng(0), repeats=1)
    configs = tuple(c for c in cfg for _ in range(2))  # rows 2k, 2k + 1 repeat config k
    rng = np.random.default_rng(1)
    free = np.repeat(rng.uniform(-1, 1, (6, 2)), 2, axis=0)  # no scatter without the effect
    eff = free.copy()
    eff[1::2, 0] += 0.02  # [m] each pair 2 cm apart ...
    eff[1, 0] += 0.98  # ... and the first pair 1 m apart
    miss_sq = rng.uniform(0.0005, 0.0015, 12)  # [m²] the effect-free misses²
    rows = FloorRows(miss_sq=miss_sq, configs=configs, with_xy=eff, without_xy=free)
    camp = SceneCampaign(records=[{}] * 12, floor_m=0.0, noise_m=0.0, outliers=(11,),
                         truth={}, rows=rows)  # fmt: skip

    def by_hand(rows_in: list[int]) -> tuple[float, float]:
        f0_sq = sum(miss_sq[i] for i in rows_in) / len(rows_in)
        pairs = [k for k in range(6) if 2 * k in rows_in and 2 * k + 1 in rows_in]
        v = sum((eff[2 * k, 0] - eff[2 * k + 1, 0]) ** 2 / 2 for k in pairs) / len(pairs)
        return (f0_sq + v) ** 0.5, f0_sq**0.5

    every = [i for i in range(12) if i != 11]  # row 11 an injected outlier: never counted
    kept = [i for i in every if i != 1]  # row 1 flagged by the tool
    keep = np.ones(12, bool)
    keep[1] = False
    assert camp.floors() == pytest.approx(by_hand(every), rel=1e-12)
    assert camp.floors(keep) == pytest.approx(by_hand(kept), rel=1e-12)
    assert camp.floors(keep)[0] < 0.3 * camp.floors()[0]  # the wide pair was most of F


def test_a_row_is_judged_against_the_world_floor_on_the_rows_its_robust_error_counts():
    """A band mass drawn throw to throw (sd 20 % of 0.02 kg) in a log without repeats: the
    throws it moves most are the world's own scatter (in its floor, no injected outlier),
    and the tool flags them (without repeats the spread cannot show, and the verdict reads
    the mass by its one value, `cell.gap.param_throw`). The judged ratio is the robust
    RMSE over the world's floor counted by hand on the rows it kept (the logged landings'
    RMS distance from the deterministic world); the plain RMSE is set against the floor
    on every row."""
    case = other_cases(("o:bm-throw",), n=160)[0]
    camp = draw_other_campaign(case["effects"], np.random.default_rng(case["world_seed"]),
                               n=case["n"], repeats=1, **case["options"])  # fmt: skip
    assert camp.outliers == ()
    row = judge_campaign(case, camp.records, camp.floor_on, camp.outliers)
    flagged = row["outlier_rows"]
    assert len(flagged) >= 3, flagged
    landed = np.array([[r["landed_x_m"], r["landed_y_m"]] for r in camp.records])
    sq = np.sum((landed - camp.reference_xy) ** 2, axis=1)
    kept = [i for i in range(len(sq)) if i + 1 not in flagged]
    f_every = float(np.sqrt(np.mean(sq)))
    f_kept = float(np.sqrt(np.mean(sq[kept])))
    assert f_kept < 0.7 * f_every  # the flagged rows carry most of the world's scatter
    assert row["world_floor_m"] == pytest.approx(f_every, rel=1e-12)
    assert row["world_floor_kept_m"] == pytest.approx(f_kept, rel=1e-12)
    assert row["judged"] == "after_robust_m / world_floor_kept_m"
    assert row["after_over_floor"] == pytest.approx(row["after_robust_m"] / f_kept, rel=1e-12)
    assert row["plain_over_floor"] == pytest.approx(row["after_m"] / f_every, rel=1e-12)
    assert row["floor_ok"] == (row["after_robust_m"] <= FLOOR_RATIO * f_kept)


def test_an_injected_outlier_is_never_in_the_other_worlds_floor():
    """5 % of the landings moved 0.3-1 m (mis-logged): by hand, the floor is the RMS distance
    of the other rows' logged landings from the deterministic world, whether or not the
    tool's kept rows leave the moved ones out."""
    camp = draw_other_campaign([], np.random.default_rng(5), n=80, outliers=0.05)
    assert len(camp.outliers) == 4
    landed = np.array([[r["landed_x_m"], r["landed_y_m"]] for r in camp.records])
    sq = np.sum((landed - camp.reference_xy) ** 2, axis=1)
    inl = [i for i in range(len(sq)) if i not in camp.outliers]
    assert camp.floor_on() == pytest.approx(np.sqrt(np.mean(sq[inl])), rel=1e-12)
    assert camp.floor_on() == camp.floor_m
    keep = np.ones(len(sq), bool)
    keep[list(camp.outliers)] = False
    assert camp.floor_on(keep) == camp.floor_on()
    keep[inl[0]] = False
    assert camp.floor_on(keep) == pytest.approx(np.sqrt(np.mean(sq[inl[1:]])), rel=1e-12)
