"""Identification that fits the noise (issue 61): residuals weighed by the documented
noise, object factors by cross-validated evidence, undetermined combinations held at the
prior, and intervals."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cell.cli import main
from cell.identify import IdentifyOptions, identify
from cell.identify.algorithm import joint_jacobian
from cell.identify.problem import ThrowData, ee_to_vector, whitening
from cell.model import DEFAULT_EE
from cell.params import ModelParams, save_params
from cell.synth import Campaign, NoiseModel, World, default_world, draw_campaign

FOUR = ("cube50", "cuboid_b", "cyl70", "sphere40")
FAR = replace(
    DEFAULT_EE, Ke2=0.75 * DEFAULT_EE.Ke2, Ke1=1.3 * DEFAULT_EE.Ke1, dt=0.85 * DEFAULT_EE.dt
)


def test_whitened_noise_has_unit_variance() -> None:
    """The synthetic noise mapped by `whitening` at the true landings is standard normal
    in both directions (the weights are the documented noise's, not a guess)."""
    world = replace(default_world(), ee=FAR)
    table = draw_campaign(world, Campaign(n=2000, objects=FOUR), seed=5)
    true = world.true_landing(table)
    batch = table.to_batch()
    w = whitening(batch.position[:, :2], true, batch.azimuth, NoiseModel())
    z = np.einsum("nij,nj->ni", w, table.landed - true)
    assert z.mean(axis=0) == pytest.approx([0, 0], abs=0.08)
    assert z.std(axis=0) == pytest.approx([1, 1], abs=0.05)
    # far throws spread more: the along-throw σ grows with the reach
    reach = np.hypot(*(true - batch.position[:, :2]).T)
    along = 1 / np.linalg.norm(w[:, 0], axis=1)
    assert np.all(np.diff(along[np.argsort(reach)]) >= -1e-12)


def test_joint_jacobian_matches_finite_differences() -> None:
    table = draw_campaign(default_world(), Campaign(n=40, objects=FOUR), seed=3)
    data = ThrowData.from_table(table)
    data.weigh(data.batch, FAR, NoiseModel())
    _, k = data.factor_columns()
    x = np.linspace(0.95, 1.05, k)
    z = ee_to_vector(FAR)
    jac = joint_jacobian(data, FAR, x)

    def f(theta: np.ndarray) -> np.ndarray:
        from cell.identify.problem import ee_from_vector

        ee = ee_from_vector(theta[:8], FAR)
        return data.wres(data.batch_with(data.objects_from_factors(theta[8:])), ee).ravel()

    theta = np.r_[z, x]
    h = 1e-6 * np.maximum(np.abs(theta), 0.1)
    fd = np.stack(
        [
            (f(theta + e * hh) - f(theta - e * hh)) / (2 * hh)
            for e, hh in zip(np.eye(theta.size), h, strict=True)
        ],
        axis=1,
    )
    scale = np.abs(fd).max(axis=0) + 1e-9
    assert np.max(np.abs(jac - fd) / scale) < 5e-3


def _ssr(world: World, table, params: ModelParams) -> float:  # noqa: ANN001
    """-2 log L (up to a constant) of a log's landings under these parameters, with the
    documented noise at the true reach (the likelihood the campaign was drawn from)."""
    from cell.identify.report import predicted_landing

    true = world.true_landing(table)
    b = table.to_batch()
    w = whitening(b.position[:, :2], true, b.azimuth, world.noise)
    r = np.einsum("nij,nj->ni", w, predicted_landing(table, params) - table.landed)
    return float(np.sum(r**2))


def test_training_error_falls_below_the_truths_only_by_the_parameter_count() -> None:
    """For a maximum-likelihood fit E[SSR_true − SSR_fit] ≈ p (the parameters it frees),
    with a spread of about √(2p): a fit that absorbs noise beats the truth by far more."""
    ee = replace(
        DEFAULT_EE, Ke3=0.7 * DEFAULT_EE.Ke3, Ke1=1.25 * DEFAULT_EE.Ke1, dt=1.15 * DEFAULT_EE.dt
    )
    world = replace(default_world(), ee=ee)
    table = draw_campaign(world, Campaign(n=300, objects=FOUR + ("cube30", "cyl50")), seed=11)
    result = identify(table)
    drop = _ssr(world, table, world.as_params()) - _ssr(world, table, result.params)
    kept = {c.object_id for c in result.objects if c.kept}
    free = 8 + sum(1 for k in result.intervals if "." in k and k.split(".")[0] not in kept)
    p = result.n_params  # the determined combinations: what the fit frees
    assert 2 <= p <= free
    assert drop <= p + 3 * np.sqrt(2 * p), (drop, p)
    # and the fit is not worse than the truth by more than the prior's pull explains
    assert drop >= -3 * np.sqrt(2 * p) - 10, (drop, p)


def test_catalogue_objects_keep_their_factors_at_one(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    """A campaign whose objects are exactly the catalogue's (η_ee far from the defaults):
    every object is kept at its catalogue values by cross-validation or has 1 within the
    95 % interval of each factor; the report says which and why."""
    world, throws, out = tmp_path / "w.yaml", tmp_path / "t.csv", tmp_path / "ee.yaml"
    save_params(ModelParams(ee=FAR), world)
    assert main(["synth", "-o", str(throws), "--n", "240", "--seed", "7", "--world", str(world),
                 "--objects", *FOUR]) == 0  # fmt: skip
    capsys.readouterr()
    # one identification: its text on standard output, its JSON written to a file
    rep_path = tmp_path / "rep.json"
    assert main(["identify", str(throws), "-o", str(out), "--json", str(rep_path)]) == 0
    text = capsys.readouterr().out
    rep = json.loads(rep_path.read_text())
    assert set(rep["object_choice"]) == set(FOUR)
    for oid, choice in rep["object_choice"].items():
        assert choice["reason"]
        facs = {k: v for k, v in rep["intervals_95"].items() if k.startswith(oid + ".")}
        assert len(facs) >= 2  # mass and at least one extent group
        for name, iv in facs.items():
            if choice["kept"]:
                assert iv["value"] == 1.0, name
            assert abs(iv["value"] - 1) <= iv["half_width"], (name, iv)
    assert rep["determined_combinations"] >= 2
    assert any(not d["determined"] for d in rep["directions"])
    # the text report names the choices and the combinations
    assert "held at the prior" in text and "cube50" in text and "catalogue" in text


def test_a_changed_object_is_fitted_and_the_others_kept_or_consistent() -> None:
    """Cross-validation is per object: a cube 25 % heavier than its catalogue mass is
    fitted; objects exactly the catalogue's keep their values or 1 within their interval."""
    cat = default_world()
    heavy = replace(cat.objects["cube50"], mass=1.25 * cat.objects["cube50"].mass)
    world = World(ee=FAR, objects={"cube50": heavy})
    table = draw_campaign(world, Campaign(n=300, objects=FOUR), seed=4)
    res = identify(table, options=IdentifyOptions())
    by = {c.object_id: c for c in res.objects}
    assert not by["cube50"].kept
    # relative to the others (the common mass scale trades with the push time)
    ratio = res.intervals["cube50.mass"][0] / np.mean(
        [res.intervals[f"{o}.mass"][0] for o in FOUR if o != "cube50"]
    )
    assert ratio > 1.12, ratio
    for oid in FOUR[1:]:
        for name, (v, h) in res.intervals.items():
            if name.startswith(oid + "."):
                assert abs(v - 1) <= h, (name, v, h)


def test_directions_hold_the_null_combination_and_give_the_map_intervals() -> None:
    """A linear problem whose parameters 2 and 3 enter only as their sum: their difference
    is named undetermined and held at the prior; the rest is kept; the intervals are the
    closed-form MAP covariance (JᵀJ + D⁻²)⁻¹ and the strengths J·D's singular values."""
    from cell.identify.directions import analyse

    rng = np.random.default_rng(0)
    jac = rng.normal(size=(50, 4))
    jac[:, 3] = jac[:, 2]
    prior_std = np.array([0.5, 0.3, 0.3, 0.3])
    theta0 = np.array([1.0, 2.0, 3.0, 4.0])
    theta = theta0 + np.array([0.1, -0.2, 0.3, 0.1])
    names = ["a", "b", "c", "d"]
    ana = analyse(jac, prior_std, prior_std, theta, theta0, names, 1.0)
    s = np.linalg.svd(jac * prior_std, compute_uv=False)
    np.testing.assert_allclose([d.strength for d in ana.directions], s, atol=1e-6)
    assert [d.determined for d in ana.directions] == [True, True, True, False]
    held = ana.directions[-1]
    assert {n for n, _ in held.components} == {"c", "d"}
    # the analysis splits after η_ee's 8 slots; here all 4 parameters are in the first part
    full = np.r_[ana.z, ana.factors][:4]
    dev = (full - theta0) / prior_std
    assert dev[2] - dev[3] == pytest.approx(0.0, abs=1e-9)  # held at the prior
    assert dev[2] + dev[3] == pytest.approx((0.3 + 0.1) / 0.3, abs=1e-9)  # the sum kept
    assert dev[:2] == pytest.approx([0.1 / 0.5, -0.2 / 0.3], abs=1e-9)
    cov = np.linalg.inv(jac.T @ jac + np.diag(1 / prior_std**2))
    std = np.r_[ana.std_z, ana.std_factors][:4]
    np.testing.assert_allclose(std, np.sqrt(np.diag(cov)), rtol=1e-6)


def test_bad_selection_options_are_refused(tmp_path: Path, capsys) -> None:  # noqa: ANN001
    from cell.errors import InvalidParameter

    throws = tmp_path / "t.csv"
    assert main(["synth", "-o", str(throws), "--n", "20", "--objects", "cube50"]) == 0
    capsys.readouterr()
    for flags, says in (
        (["--noise-floor", "0"], "--noise-floor"),
        (["--noise-along", "-1"], "along"),
    ):
        assert main(["identify", str(throws), "-o", str(tmp_path / "e.yaml"), *flags]) == 2
        err = capsys.readouterr().err
        assert "cell: error:" in err and says in err and "Traceback" not in err
    assert not (tmp_path / "e.yaml").exists()

    with pytest.raises(InvalidParameter, match="object_priors"):
        IdentifyOptions(object_priors=(0.0, -0.1))
    with pytest.raises(InvalidParameter, match="cv_folds"):
        IdentifyOptions(cv_folds=1)
    with pytest.raises(InvalidParameter, match="determined_ratio"):
        IdentifyOptions(determined_ratio=0.0)
