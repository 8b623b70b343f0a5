"""Issue 57: an effect whose one parameter varies from throw to throw (`cell.gap.param_throw`):
its mean and spread by maximum marginal likelihood, the floor its spread sets, and the
verdict it names where the floor from repeats undercounts the draws."""

from __future__ import annotations

import numpy as np
import pytest

from cell.gap.check_other import OTHER_CASES, other_cases
from cell.gap.run import diagnose_log
from cell.gap.wind_throw import REPEAT_LR, fit_marginal, repeat_test
from cell.gap.world_other import draw_other_campaign
from cell.log.table import ThrowTable
from cell.model.params import DEFAULT_EE


def _draws(rng: np.random.Generator, k: int, mu: float, s: float, per_throw: bool):
    """k configurations thrown twice (the same J), one parameter θ drawn per throw or per
    configuration about μ; y = J θ + e, e ~ N(0, σ² I₂), σ 10 mm."""
    jac = np.repeat(rng.uniform(0.05, 0.6, (k, 2, 1)) * rng.choice([-1, 1], (k, 2, 1)), 2, 0)
    th = mu + s * (
        rng.standard_normal(2 * k) if per_throw else np.repeat(rng.standard_normal(k), 2)
    )
    y = jac[:, :, 0] * th[:, None] + 0.01 * rng.standard_normal((2 * k, 2))
    return y, jac, np.arange(2 * k).reshape(k, 2)


def test_one_parameter_drawn_per_throw_is_recovered_in_its_own_units():
    """θ_i ~ N(μ, s²) with μ 0.004 and s 0.0008 (a parameter in kilograms, say): in the
    parameter's unit the fit finds μ, s and the noise σ; in the wind's unit (1, the grid's
    smallest spread 0.01) the spread falls under the fit's zero and is lost."""
    rng = np.random.default_rng(3)
    jac = rng.uniform(5.0, 60.0, (400, 2, 1)) * rng.choice([-1, 1], (400, 2, 1))  # [m/kg]
    th = 0.004 + 0.0008 * rng.standard_normal(400)
    y = jac[:, :, 0] * th[:, None] + 0.01 * rng.standard_normal((400, 2))
    mu, s, sig, _ = fit_marginal(y, jac, unit=0.004)
    assert mu[0] == pytest.approx(0.004, rel=0.05)
    assert s == pytest.approx(0.0008, rel=0.2)
    assert sig == pytest.approx(0.01, rel=0.2)
    assert fit_marginal(y, jac)[1] == 0.0


def test_the_repeats_show_a_parameter_drawn_per_throw_not_one_drawn_per_configuration():
    """One parameter, pairs of throws of one configuration: drawn per throw, the pairs'
    differences show the spread; drawn once per configuration (a deterministic misfit that
    grows with the sensitivity, as an effect outside the vocabulary leaves), a spread fits
    all throws as well but the pairs cancel it."""
    for per_throw in (True, False):
        y, jac, pairs = _draws(np.random.default_rng(5), 80, 1.8, 0.15, per_throw)
        _, s_all, _, ll1 = fit_marginal(y, jac, unit=1.8)
        assert s_all > 0.08 and ll1 > fit_marginal(y, jac, steady=True, unit=1.8)[3] + 10
        rep = repeat_test(y, jac, pairs, unit=1.8)
        assert (rep["lr"] > REPEAT_LR) == per_throw, rep
        assert rep["noise_sd_m"] == pytest.approx(0.01, rel=0.25)


@pytest.fixture(scope="module")
def drag_drawn():
    """The other implementation's world (its own integrator) with the drag factor drawn
    for every throw, N(1.8, 0.15²) (the `o:drag-throw` case), 240 throws: the world's own
    floor and the diagnosis."""
    case = other_cases(("o:drag-throw",), n=240)[0]
    camp = draw_other_campaign(case["effects"], np.random.default_rng(case["world_seed"]), n=240)
    d, _ = diagnose_log(ThrowTable.from_records(camp.records), DEFAULT_EE, seed=case["seed"])
    return camp, d.report


def test_a_drag_drawn_throw_to_throw_is_named_with_its_mean_and_spread(drag_drawn):
    """In this draw the repeats undercount the drag's scatter (the tool's floor from repeats
    41 mm against the world's 75 mm: the few throws the drag moves most drew alike in their
    repeats), so the one factor leaves the verdict `unknown`. The throw-to-throw form
    stands on held-out log density and in the repeats; the floor it sets is within 20 %
    of the world's own (computed by the world from its draws) and the verdict names the
    drag, its mean within 5 % of 1.8 and the sd's interval holding 0.15."""
    camp, rep = drag_drawn
    assert OTHER_CASES["o:drag-throw"][0][0]["sd"] == 0.15
    form = rep["parameter_throw_to_throw"]
    assert form["chosen"] and form["names"], form
    assert rep["noise_floor_m"] < 0.75 * camp.floor_on(None)
    assert form["floor_m"] == pytest.approx(camp.floor_on(None), rel=0.2)
    v = rep["verdict"]
    assert v["effects"] == ["drag_scale"]
    assert v["laws"]["drag_scale"] == "factor_i ~ N(mean, sd)"
    assert v["params"]["drag_scale"]["factor"] == pytest.approx(1.8, rel=0.05)
    lo, hi = v["params_ci95"]["drag_scale"]["sd"]
    assert lo <= 0.15 <= hi
    assert rep["outliers"]["rows"] == []


@pytest.fixture(scope="module")
def band_mass_drawn_with_outliers():
    """The other implementation's world with the band mass drawn for every throw,
    N(0.02, 0.004²) kg (the `o:bm-throw` case's world), and 5 % of the landings moved by
    0.3–1 m in a random direction, 240 throws: the campaign and the diagnosis."""
    case = other_cases(("o:bm-throw",), n=240)[0]
    rng = np.random.default_rng(case["world_seed"])
    camp = draw_other_campaign(case["effects"], rng, n=240, outliers=0.05)
    d, _ = diagnose_log(ThrowTable.from_records(camp.records), DEFAULT_EE, seed=case["seed"])
    return camp, d.report


def test_a_band_mass_drawn_per_throw_keeps_its_tails_and_flags_the_outliers(
    band_mass_drawn_with_outliers,
):
    """The verdict names the band mass by its one value; its misses flag the throws whose
    mass drew far from the mean as well as the moved landings (35 of them besides the 12
    before the tails were read as the draw's). Read as the mass drawn per throw, the
    tails are its spread: every moved landing (the world's own list) is still flagged and
    at most two other throws are; the mean and the sd are the world's (the sd's interval
    holds 0.004 kg), and the robust held-out RMSE is within 1.3 × the world's floor on
    the rows kept."""
    camp, rep = band_mass_drawn_with_outliers
    assert OTHER_CASES["o:bm-throw"][0][0]["sd"] == 0.004
    v = rep["verdict"]
    assert v["effects"] == ["band_mass"]
    moved = {i + 1 for i in camp.outliers}  # rows: 1 = the first data row
    flagged = set(rep["outliers"]["rows"])
    assert len(moved) == 12 and moved <= flagged
    assert len(flagged - moved) <= 2, sorted(flagged - moved)
    form = rep["parameter_throw_to_throw"]
    assert form["chosen"] and form["tried_for"] == "outliers", form
    assert v["laws"]["band_mass"] == "mass_kg_i ~ N(mean, sd)"
    assert v["params"]["band_mass"]["mass_kg"] == pytest.approx(0.02, rel=0.05)
    lo, hi = v["params_ci95"]["band_mass"]["sd"]
    assert lo <= 0.004 <= hi
    keep = np.ones(len(camp.records), bool)
    keep[np.asarray(sorted(flagged)) - 1] = False
    assert v["heldout_rmse_robust_m"] <= 1.3 * camp.floor_on(keep)
