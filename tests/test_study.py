"""The repeatability case study (thesis Table 5.2) and `cell study repeatability`."""

import json
import math

import numpy as np
import pytest

from cell.catalogue import get_object
from cell.cli import main
from cell.model import DEFAULT_EE, ThrowBatch, predict_landing
from cell.platforms.downwash import DEFAULT_DRONE_LAW
from cell.study.plot import plot_study
from cell.study.repeatability import THESIS_TABLE, run_study

# Table 5.2 of the thesis (reach mean ± std over 20 throws [m])
TABLE = {
    None: (1.345, 0.1086),
    0.0: (3.046, 0.0941),
    8900.0: (3.0387, 0.0949),
    13900.0: (2.832, 0.0955),
    14860.0: (2.8221, 0.1003),
}


@pytest.fixture(scope="module")
def study():
    return run_study()


def test_the_table_is_the_thesis():
    assert {r.rotor_rpm: (r.reach_m, r.std_m) for r in THESIS_TABLE} == TABLE


def test_anchors_reproduce_the_arm_and_the_still_drone(study):
    arm, still = study.rows[0], study.rows[1]
    assert arm.reach_m == pytest.approx(1.345, abs=1e-4)
    assert still.reach_m == pytest.approx(3.046, abs=1e-4)
    # the same stroke from both; the drone is higher
    assert DEFAULT_EE.stroke_min <= study.stroke_m <= DEFAULT_EE.stroke_max
    assert study.drone_release_m[2] > study.arm_release_m[2] + 1.0
    # recompute the arm's reach with the nominal model independently of the study
    b = ThrowBatch.single(
        get_object("cube50"),
        stroke=study.stroke_m,
        position=study.arm_release_m,
        elevation=0.0,
        azimuth=0.0,
    )
    assert float(predict_landing(b, DEFAULT_EE).x[0]) == pytest.approx(1.345, abs=1e-4)


def test_fitted_downwash_reproduces_the_drone_rows(study):
    mom, thr = study.fits
    assert mom.name == "momentum" and thr.name == "threshold"
    assert mom.law.threshold_rpm == 0.0
    assert mom.law.induced_mps_per_krpm == pytest.approx(
        DEFAULT_DRONE_LAW.induced_mps_per_krpm, rel=0.01
    )
    drone = [r for r in study.rows if r.platform == "drone"]
    reach = [r.reach_m for r in drone]
    assert all(a > b for a, b in zip(reach, reach[1:], strict=False))  # shorter with rpm
    for r in drone:  # within the thesis' spread
        assert abs(r.reach_m - r.thesis_reach_m) <= r.thesis_std_m
        assert r.within_spread
    assert mom.within_spread
    # the threshold law has one more parameter and fits at least as well
    assert thr.rms_sem <= mom.rms_sem + 1e-9
    sem = {rpm: std / math.sqrt(20) for rpm, (_, std) in TABLE.items()}
    resid = [abs(r.reach_threshold_m - r.thesis_reach_m) / sem[r.rotor_rpm] for r in drone[1:]]
    assert max(resid) <= 2.0 and thr.within_sem
    # a physically sized rotor: C_T within what propellers have, thrust above zero
    assert 0.005 < mom.thrust_coefficient < 0.3
    assert mom.thrust_at_max_n > 0
    assert "momentum theory" in study.verdict.lower()


def test_least_squares_is_a_minimum(study):
    # moving the fitted constant either way raises the weighted residual
    from cell.study.repeatability import _cube, _drone_reach

    mom = study.fits[0]
    rows = [r for r in THESIS_TABLE if r.rotor_rpm]
    rpm = [r.rotor_rpm for r in rows]
    mean = np.array([r.reach_m for r in rows])
    sem = np.array([r.sem_m for r in rows])

    def cost(c):
        law = mom.law.with_params(induced_mps_per_krpm=c)
        r = _drone_reach(
            _cube(study.setup),
            DEFAULT_EE,
            study.setup,
            study.stroke_m,
            study.drone_release_m[2],
            rpm,
            law,
        )
        return float(np.sum(((r - mean) / sem) ** 2))

    c = mom.law.induced_mps_per_krpm
    best = cost(c)
    assert best < cost(c * 0.97) and best < cost(c * 1.03)


def test_plot_is_written(study, tmp_path):
    out = plot_study(study, tmp_path / "study.png")
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_cli_json_rows(capsys):
    assert main(["study", "repeatability", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["platform"] for r in rows] == ["arm"] + ["drone"] * 4
    for r in rows:
        assert {"platform", "rotor_rpm", "reach_m", "thesis_reach_m", "thesis_std_m"} <= set(r)
        assert (r["thesis_reach_m"], r["thesis_std_m"]) == TABLE[r["rotor_rpm"]]
        assert abs(r["reach_m"] - r["thesis_reach_m"]) <= r["thesis_std_m"]
