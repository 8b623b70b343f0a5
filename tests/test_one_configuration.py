"""A throw log of one configuration (a lab repeating one throw): every effect it could name
moves its landings alike, so the verdict is `unknown`, the report says why
(`one_configuration`) and lists the effects that explain the shift alike.

The logs are written here, not by `cell.gap`'s worlds: a world whose encoder reads the
stroke 5 mm short (the true stroke is the logged one + 5 mm), its landings the nominal
model's at the true stroke (`cell.model.throw.predict_landing`) plus 10 mm of Gaussian
scatter per axis, each configuration thrown twice."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from cell.gap.run import diagnose_log
from cell.log import read_throws_csv
from cell.model.params import DEFAULT_EE
from cell.model.throw import ThrowBatch, predict_landing

DELTA_M = 0.005  # [m] the world's stroke offset: true stroke = logged + DELTA_M
NOISE_M = 0.01  # [m] landing scatter per axis
HEADER = (
    "throw_id,object_id,shape,mass_kg,size_x_m,size_y_m,size_z_m,stroke_m,x_m,y_m,z_m,"
    "elevation_rad,azimuth_rad,roll_rad,vx_mps,vy_mps,vz_mps,platform,rotor_rpm,land_z_m,"
    "landed_x_m,landed_y_m"
).split(",")


def _world(strokes: list[float], poses: int, n: int = 120, seed: int = 1061) -> dict:
    """A 60 g 50 mm cube thrown at 0.7 rad: the strokes in turn, and `poses` release poses
    (1: one position and azimuth for every throw); each configuration twice."""
    rng = np.random.default_rng(seed)
    k = n // 2
    if poses == 1:
        pos = np.tile([0.05, -0.25, 0.70], (k, 1))
        az = np.full(k, 0.3)
    else:
        pos = np.c_[rng.uniform(-0.1, 0.1, k), rng.uniform(-0.3, 0.3, k), rng.uniform(0.6, 0.8, k)]
        az = rng.uniform(-1.5, 1.5, k)
    stroke = np.resize(np.asarray(strokes, float), k)
    pos, az, stroke = np.repeat(pos, 2, axis=0), np.repeat(az, 2), np.repeat(stroke, 2)

    def batch(s: np.ndarray) -> ThrowBatch:
        return ThrowBatch.build(stroke=s, position=pos, elevation=0.7, azimuth=az, shape=0,
                                mass=0.06, size=[0.05, 0.05, 0.05])  # fmt: skip

    true = predict_landing(batch(stroke + DELTA_M), DEFAULT_EE)
    logged = predict_landing(batch(stroke), DEFAULT_EE)
    land = np.c_[true.x, true.y] + rng.normal(0.0, NOISE_M, (n, 2))
    return {"stroke": stroke, "pos": pos, "az": az, "land": land,
            "shift": np.c_[true.x - logged.x, true.y - logged.y]}  # fmt: skip


def _diagnose(tmp_path: Path, w: dict) -> dict:
    path = tmp_path / "throws.csv"
    with path.open("w", newline="") as fh:
        out = csv.writer(fh)
        out.writerow(HEADER)
        for i, (s, p, a, xy) in enumerate(
            zip(w["stroke"], w["pos"], w["az"], w["land"], strict=True)
        ):
            out.writerow([f"T{i:04d}", "cube50", "cube", 0.06, 0.05, 0.05, 0.05, s, *p, 0.7, a,
                          0.0, 0, 0, 0, "arm", 0, 0.0, *(f"{v:.6f}" for v in xy)])  # fmt: skip
    d, _ = diagnose_log(read_throws_csv(path), DEFAULT_EE)
    return d.report


def _along(w: dict) -> float:
    """The world's mean landing shift along the throw [m] (from the model's landings at the
    true and the logged stroke, without scatter)."""
    return float(np.mean(w["shift"][:, 0] * np.cos(w["az"]) + w["shift"][:, 1] * np.sin(w["az"])))


def _check_unknown(rep: dict, w: dict, scope: str) -> None:
    one = rep["one_configuration"]
    assert rep["verdict"]["effects"] == ["unknown"], rep["verdict"]
    assert one["scope"] == scope
    # the speed-changing launch effects tie: each is named as a partial
    assert {"stroke_offset", "band_damping"} <= set(one["explained_alike"]), one
    assert rep["verdict"]["partial_effects"] == one["explained_alike"]
    assert one["would_name"] and one["would_name"][0] in one["explained_alike"]
    # the shift reported is the world's, within the scatter's standard error (3 σ)
    se = NOISE_M / np.sqrt(len(w["az"]))
    assert abs(one["shift_along_m"] - _along(w)) < 3 * se, (one["shift_along_m"], _along(w))
    assert abs(one["shift_across_m"]) < 3 * se
    word = "beyond" if _along(w) > 0 else "short of"
    assert f"land {abs(one['shift_along_m']):.4f} m {word} the model's landing" in one["why"]
    assert rep["where"]["evidence"] == "no tracks; " + one["why"]


def test_one_throw_repeated_is_unknown_with_the_effects_that_explain_it(tmp_path: Path) -> None:
    """One object, stroke, elevation and release pose: main named one of the tied launch
    effects (`stroke_offset` and `band_damping` predict alike to the bit)."""
    w = _world([0.07], poses=1)
    _check_unknown(_diagnose(tmp_path, w), w, "all")


def test_one_launch_from_many_poses_is_unknown(tmp_path: Path) -> None:
    """One object, stroke and elevation from 60 release poses (the lab's L11): the launch
    effects are one change of one launch velocity, whatever the poses."""
    w = _world([0.07], poses=60)
    _check_unknown(_diagnose(tmp_path, w), w, "launch")


def test_two_strokes_are_diagnosed_as_before(tmp_path: Path) -> None:
    """The same world with two strokes: `stroke_offset` named (main's verdict on it), its
    δ within its interval of the world's 5 mm, and no `one_configuration`."""
    w = _world([0.06, 0.09], poses=60)
    rep = _diagnose(tmp_path, w)
    assert "one_configuration" not in rep
    assert rep["verdict"]["effects"] == ["stroke_offset"], rep["verdict"]
    lo, hi = rep["verdict"]["params_ci95"]["stroke_offset"]["delta_m"]
    assert lo <= DELTA_M <= hi, (lo, hi)
