"""Issue 57 (the scene's downwash): the downwash family's round-jet member
(`cell.model.effects.DownwashJet`), checked against its closed form and a free jet's
momentum flux, and on the PyBullet scene's jet (`cell.sim.effect_scene.EffectScene.air`,
a law the tool's code did not write: centre speed ∝ 1 / (1 + depth / core), width
radius + 0.2 · depth), which the column and the decay members cannot take."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.model.effects import FAMILIES, JET_SPREAD, DownwashJet
from cell.model.effects_apply import flight_accel
from cell.model.throw import ThrowBatch


def _batch(p0: tuple[float, float, float]) -> ThrowBatch:
    from cell.log.records import throw_record
    from cell.log.table import ThrowTable
    from cell.sim.items import resolve_object

    obj, _ = resolve_object("cube30")
    rec = throw_record(
        "j0", obj, stroke_m=0.06, position_m=p0, elevation_rad=0.5, azimuth_rad=0.0,
        platform="drone", rotor_rpm=6000.0, land_z_m=0.1, landed_xy_m=(1.0, 0.0),
        t_flight_s=0.8, session="jet",
    )  # fmt: skip
    return ThrowTable.from_records([rec]).to_batch()


def test_the_jet_member_is_a_free_round_jet():
    """The air the member puts below the release: a Gaussian of width R + s·depth, centre
    speed w (rpm / 5000)^p · R / width, none above the release; its momentum flux
    (∝ ∫ w² 2πρ dρ = π/2 · centre² · width²) is the same at every depth."""
    assert DownwashJet in FAMILIES["downwash"]
    p0 = (0.2, -0.1, 1.6)
    eff = DownwashJet(speed_mps=12.0, radius_m=0.4, exponent=1.3)
    accel = flight_accel(_batch(p0), [eff], np.array([6000.0]))
    w0 = 12.0 * (6000.0 / 5000.0) ** 1.3
    flux = []
    for depth in (0.05, 0.3, 0.9, 1.5):
        width = 0.4 + JET_SPREAD * depth
        for rho in (0.0, 0.25, 0.6):
            p = np.array([[p0[0] + rho * 0.6, p0[1] + rho * 0.8, p0[2] - depth]])
            air, _ = accel(p, np.zeros((1, 3)), np.array([0]))
            want = w0 * 0.4 / width * math.exp(-((rho / width) ** 2))
            assert air[0, 2] == pytest.approx(-want, rel=1e-9)
            assert air[0, :2] == pytest.approx([0.0, 0.0], abs=1e-12)
        centre, _ = accel(
            np.array([[p0[0], p0[1], p0[2] - depth]]), np.zeros((1, 3)), np.array([0])
        )
        flux.append((centre[0, 2] * width) ** 2)
    assert flux == pytest.approx([flux[0]] * len(flux), rel=1e-9)
    above, _ = accel(np.array([[p0[0], p0[1], p0[2] + 0.1]]), np.zeros((1, 3)), np.array([0]))
    assert above[0] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)


def test_the_scene_jet_is_named_downwash_by_its_jet_law_in_flight():
    """The scene's strong jet (w 15 m/s, 1 / (1 + depth / 2 m), radius 1.5 m + 0.2 · depth,
    applied as a force field) on drone throws of the matched objects: named `downwash`,
    law `jet`, phase flight, its speed and radius within 30 % of the world's, and the
    held-out RMSE within 1.3 × the world's own floor. Before the jet member the verdict
    was `unknown` (the column and decay members stop at their bounds)."""
    pytest.importorskip("pybullet")
    from cell.gap.run import diagnose_log
    from cell.gap.world_scene import draw_scene_campaign, matched_objects
    from cell.log.table import ThrowTable
    from cell.params import load_params, scene_params_path

    path = scene_params_path()
    assert path is not None
    mp = load_params(path)
    jet = {"kind": "downwash", "form": "const", "w_mps": 15.0, "radius_m": 1.5, "core_m": 2.0}
    camp = draw_scene_campaign(
        [jet], np.random.default_rng(23), mp, n=80, drone_share=0.6, objects=matched_objects(mp)
    )
    d, _ = diagnose_log(ThrowTable.from_records(camp.records), mp.ee, objects=mp.objects)
    v = d.report["verdict"]
    assert v["effects"] == ["downwash"], d.report["candidates"][:2]
    assert v["laws"] == {"downwash": "jet"}
    assert v["phases"] == {"downwash": "flight"}
    got = v["params"]["downwash"]
    assert got["speed_mps"] == pytest.approx(15.0, rel=0.3)
    assert got["radius_m"] == pytest.approx(1.5, rel=0.3)
    assert v["heldout_rmse_robust_m"] <= 1.3 * camp.floor_m


def test_the_narrow_scene_jet_moves_no_landing():
    """Why `s:downwash` is `none` and `s:downwash+wind` is `wind` (cell/gap/check_scene.py):
    the narrow jet (0.25 m wide at the rotor) moves the drone throws' landings by well
    under a millimetre, against a tracker scatter of 25 mm, while the wide one moves them
    by centimetres. Measured on the same throws with and without each jet."""
    pytest.importorskip("pybullet")
    from cell.gap.check_scene import _JET, _JET_STRONG
    from cell.gap.world_scene import draw_plan, throw_plan

    plan = draw_plan(12, np.random.default_rng(5), drone_share=1.0, objects=("cube30", "sphere40"))
    assert all(t.rpm > 0 for t in plan)
    free, _, _ = throw_plan(plan, [], 3)
    moved = []
    for jet in (_JET, _JET_STRONG):
        xy, _, _ = throw_plan(plan, [{"kind": "downwash", "form": "const", **jet}], 3)
        moved.append(float(np.sqrt(np.mean(np.sum((xy - free) ** 2, axis=1)))))
    assert moved[0] < 0.002, moved
    assert moved[1] > 0.02, moved
