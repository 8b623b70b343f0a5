"""A camera's radial distortion proposed as such (`cell.gap.propose_radial`).

The outside lab's L06 (branch `robgap64`): landings read by a camera over (1.5, 0) m
whose lens moves each point along its radius by 0.012 r³. No term of the library was
radial about a point of the landing area, and the proposal was 11 terms led by a flight
force, to 1.33 × the floor. Here the landings of a world written without the model
(`cell.gap.world_other`) are moved by Brown's radial term about a point of their own
choice, and the proposal must name that term, its coefficient and its centre."""

from __future__ import annotations

import numpy as np
import pytest

from cell.gap.problem import build_problem
from cell.gap.propose import propose
from cell.gap.world_other import draw_other_campaign
from cell.log.table import ThrowTable
from cell.model.params import DEFAULT_EE

K = 0.012  # [1/m²] the lens' first radial coefficient
CENTRE = np.array([1.3, 0.2])  # [m, W] the point under the camera's axis
VIEW_M = 3.0  # [m] the camera sees the landings this far from its centre


def _log(k: float, seed: int = 11) -> tuple[ThrowTable, float]:
    camp = draw_other_campaign([], np.random.default_rng(seed), n=320)
    recs = []
    for r in camp.records:
        p = np.array([r["landed_x_m"], r["landed_y_m"]])
        d = p - CENTRE
        if float(d @ d) > VIEW_M**2:
            continue  # outside the camera's view: not logged
        q = CENTRE + d * (1.0 + k * float(d @ d))  # x' = c + (x − c)(1 + k r²)
        recs.append({**r, "landed_x_m": float(q[0]), "landed_y_m": float(q[1])})
    return ThrowTable.from_records(recs), camp.floor_m


def test_a_cameras_radial_distortion_is_proposed_with_its_coefficient_and_centre():
    table, floor = _log(K)
    prob = build_problem(table, DEFAULT_EE, seed=0)
    prop, _ = propose(prob, (), floor)
    top = prop["terms"][0]
    assert top["term"].startswith("landing radial distortion [1/m²] = k · r² d"), prop["law"]
    assert top["phase"] == "measurement" and prop["phase"] == "measurement"
    assert top["k"] == pytest.approx(K, rel=0.1), prop["law"]
    assert np.hypot(*(np.array(top["centre_m"]) - CENTRE)) < 0.1, top["centre_m"]
    assert len(prop["terms"]) <= 2, prop["law"]
    assert prop["heldout_rmse_after_m"] < 1.3 * floor, (prop["heldout_rmse_after_m"], floor)


def test_landings_of_an_undistorted_camera_get_no_radial_term():
    table, floor = _log(0.0)
    prob = build_problem(table, DEFAULT_EE, seed=0)
    prop, _ = propose(prob, (), floor)
    assert not any("radial" in t["term"] for t in prop["terms"]), prop["law"]
