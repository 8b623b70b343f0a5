"""The golden table of the model conventions, reproduced within 1 mm (ΔL, f_o to 4 digits)."""

import math

import numpy as np
import pytest

from cell.model import (
    DEFAULT_EE,
    SHAPES,
    ThrowBatch,
    band_state,
    predict_landing,
    reference_landing,
)

OBJECTS = {
    "cube50": ("cube", 0.060, (0.05, 0.05, 0.05)),
    "cube30": ("cube", 0.020, (0.03, 0.03, 0.03)),
    "cuboid_c": ("cuboid", 0.110, (0.05, 0.05, 0.10)),
    "cyl50": ("cylinder", 0.075, (0.05, 0.05, 0.07)),
    "cyl70": ("cylinder", 0.120, (0.07, 0.07, 0.06)),
    "sphere40": ("sphere", 0.030, (0.04, 0.04, 0.04)),
    "sphere70": ("sphere", 0.090, (0.07, 0.07, 0.07)),
}
# object, stroke, release xyz, (elev, azim) deg, base velocity, land_z, dL, f_o, landed x, y, t
GOLDEN = [
    (
        "cube50",
        0.0625,
        (0, 0, 0.6),
        (30, 0),
        (0, 0, 0),
        0.0,
        0.05936,
        14.6559,
        1.2902,
        0.0000,
        0.5290,
    ),
    (
        "cube50",
        0.04,
        (0.1, -0.2, 0.5),
        (45, 20),
        (0, 0, 0),
        0.0,
        0.08164,
        20.9840,
        2.0345,
        0.5041,
        0.7339,
    ),
    (
        "cube30",
        0.08,
        (0, 0, 0.7),
        (10, -15),
        (0, 0, 0),
        0.0,
        0.04086,
        9.9023,
        2.6318,
        -0.7052,
        0.5008,
    ),
    (
        "cuboid_c",
        0.035,
        (0, 0, 0.8),
        (35, 0),
        (0, 0, 0),
        0.25,
        0.08660,
        22.4585,
        0.9837,
        0.0000,
        0.5063,
    ),
    (
        "cyl50",
        0.06,
        (0, 0, 0.6),
        (20, 5),
        (0.5, 0, 0),
        0.0,
        0.06183,
        15.3350,
        1.2128,
        0.0869,
        0.4457,
    ),
    (
        "sphere40",
        0.05,
        (0.2, 0.1, 0.9),
        (0, 0),
        (0, 0, 0),
        0.0,
        0.07116,
        18.0433,
        3.2117,
        0.1000,
        0.4311,
    ),
    (
        "sphere70",
        0.03,
        (0, 0, 2.0),
        (8, 0),
        (0, 0, 0),
        0.0,
        0.09309,
        24.1390,
        2.1426,
        0.0000,
        0.6892,
    ),
    (
        "cyl70",
        0.1,
        (0, 0, 0.5),
        (60, -30),
        (0, 0.3, 0.2),
        0.1,
        0.02571,
        5.6346,
        0.0870,
        0.0585,
        0.3636,
    ),
]


def golden_batch() -> ThrowBatch:
    return ThrowBatch.build(
        stroke=[r[1] for r in GOLDEN],
        position=[r[2] for r in GOLDEN],
        elevation=[math.radians(r[3][0]) for r in GOLDEN],
        azimuth=[math.radians(r[3][1]) for r in GOLDEN],
        base_velocity=[r[4] for r in GOLDEN],
        land_z=[r[5] for r in GOLDEN],
        shape=[SHAPES.index(OBJECTS[r[0]][0]) for r in GOLDEN],
        mass=[OBJECTS[r[0]][1] for r in GOLDEN],
        size=[OBJECTS[r[0]][2] for r in GOLDEN],
    )


@pytest.mark.parametrize("row", GOLDEN, ids=[f"{r[0]}@{r[1]}" for r in GOLDEN])
def test_band_matches_golden(row):
    shape, mass, size = OBJECTS[row[0]]
    band = band_state(row[1], size[0], DEFAULT_EE)
    assert float(band.stretch) == pytest.approx(row[6], abs=5e-6)
    assert float(band.push) == pytest.approx(row[7], abs=5e-5)


@pytest.mark.parametrize("predict", [predict_landing, reference_landing], ids=["fast", "reference"])
def test_landing_matches_golden_within_1mm(predict):
    land = predict(golden_batch(), DEFAULT_EE)
    expected = np.array([[r[8], r[9]] for r in GOLDEN])
    err = np.linalg.norm(land.xy - expected, axis=1)
    assert err.max() < 1e-3, err
    t_expected = np.array([r[10] for r in GOLDEN])
    np.testing.assert_allclose(land.t_flight, t_expected, atol=1e-4)
