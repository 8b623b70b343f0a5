"""`cell plan` and the plan benchmark."""

from __future__ import annotations

import json
import math

from cell.bench import available
from cell.bench.bench_plan import measure
from cell.catalogue import get_object
from cell.cli import main
from cell.model import DEFAULT_EE, ThrowBatch, predict_landing
from cell.optimize import SIGMA_COLUMNS
from tests.test_optimize_plan import _independent_landing

# THROW_LOG.md column names of σ, copied here
LOG_COLUMNS = [
    "x_m",
    "y_m",
    "z_m",
    "vx_mps",
    "vy_mps",
    "vz_mps",
    "roll_rad",
    "elevation_rad",
    "azimuth_rad",
    "stroke_m",
]


def test_sigma_columns_are_the_throw_log_names():
    assert list(SIGMA_COLUMNS) == LOG_COLUMNS


def test_plan_json_names_sigma_like_the_throw_log_and_lands(capsys):
    rc = main(["plan", "--target", "1.6", "-0.4", "0.25", "--object", "cyl50", "--json"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    for key in [*LOG_COLUMNS, "pred_x_m", "pred_y_m", "miss_m", "energy_j", "t_flight_s"]:
        assert isinstance(d[key], float), key
    assert d["miss_m"] <= 1e-3
    b = ThrowBatch.single(
        get_object("cyl50"),
        stroke=d["stroke_m"],
        position=(d["x_m"], d["y_m"], d["z_m"]),
        elevation=d["elevation_rad"],
        azimuth=d["azimuth_rad"],
        base_velocity=(d["vx_mps"], d["vy_mps"], d["vz_mps"]),
        land_z=0.25,
    )
    land = predict_landing(b, DEFAULT_EE)
    assert math.hypot(land.x[0] - 1.6, land.y[0] + 0.4) <= 1e-3
    assert abs(land.x[0] - d["pred_x_m"]) < 1e-9


def test_independent_model_lands_the_printed_json_sigma(capsys):
    """σ* exactly as `cell plan --json` prints it, flown by the independent MODEL.md integrator."""
    for target, method in ((("-1.2", "1.5", "0.3"), "auto"), (("2.2", "0.2", "0.0"), "nlp")):
        rc = main(
            ["plan", "--target", *target, "--object", "sphere55", "--json", "--method", method]
        )
        assert rc == 0
        d = json.loads(capsys.readouterr().out)
        obj = get_object("sphere55")
        x, y, _ = _independent_landing(
            obj.shape, obj.mass, obj.size, [d[c] for c in LOG_COLUMNS], d["land_z_m"]
        )
        assert math.hypot(x - float(target[0]), y - float(target[1])) < 5e-3


def test_plan_text_and_adhoc_object(capsys):
    rc = main(
        [
            "plan",
            "--target",
            "2",
            "0.3",
            "0.1",
            "--shape",
            "sphere",
            "--mass",
            "0.05",
            "--size",
            "0.05",
            "0.05",
            "0.05",
            "--method",
            "nlp",
        ]
    )
    assert rc == 0
    out = capsys.readouterr().out
    assert "stroke" in out and "miss" in out and "stored energy" in out and "nlp" in out


def test_unreachable_target_is_a_clean_error_with_the_range(capsys):
    rc = main(["plan", "--target", "9", "0", "0", "--object", "cube50"])
    assert rc == 2
    err = capsys.readouterr().err
    assert "out of reach" in err and "cube50 reaches" in err and "Traceback" not in err


def test_bad_bounds_are_a_clean_error(capsys):
    rc = main(
        ["plan", "--target", "2", "0", "0", "--object", "cube50", "--box", *"1 0 0 0 1 1".split()]
    )
    assert rc == 2
    assert "position_min" in capsys.readouterr().err


def test_bench_plan_figures():
    assert "plan" in available()
    f = measure(6, 2, seed=1)
    for key in (
        "plan_fast_median_ms",
        "plan_fast_p95_ms",
        "plan_nlp_median_ms",
        "plan_nlp_p95_ms",
        "plan_max_miss_m",
    ):
        assert math.isfinite(f[key]) and f[key] >= 0, key
    assert f["plan_fast_targets"] == 6 and f["plan_nlp_targets"] == 2
    assert f["plan_fast_failed"] == 0 and f["plan_nlp_failed"] == 0
    assert f["plan_max_miss_m"] <= 1e-3
