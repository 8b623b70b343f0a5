"""The gap fit's stacked Jacobian is bitwise scipy's '2-point' one, so the fits are the same."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.optimize._numdiff import approx_derivative

import cell.gap.fit as fit_mod
from cell.gap.fit import DIFF_STEP, _layout, _unpack, fit_set, score_set
from cell.gap.fit_jac import stackable, stacked_jacobian
from cell.gap.laws import law_class, per_object_class
from cell.gap.problem import GapProblem, build_problem
from cell.gap.run import _k_of
from cell.gap.tracks import fit_tracks, launch_arrays
from cell.gap.world import draw_campaign
from cell.gap.world_tracks import draw_tracked_campaign
from cell.model.effects import (
    BandDamping,
    BandMass,
    Bounce,
    Downwash,
    DownwashDecay,
    DragScale,
    Effect,
    ReleasePitch,
    ShapeStretch,
    Spin,
    StrokeOffset,
    Wind,
)
from cell.model.params import DEFAULT_EE


@pytest.fixture(scope="module")
def prob() -> GapProblem:
    camp = draw_campaign("drag_scale", np.random.default_rng(3), n=40)
    return build_problem(camp.table, DEFAULT_EE)


@pytest.fixture(scope="module")
def tracked() -> GapProblem:
    camp = draw_tracked_campaign((DragScale(1.3),), np.random.default_rng(5), n=30)
    tab = camp.table
    launch = launch_arrays(fit_tracks(tab.text("throw_id"), camp.tracks, _k_of(tab)))
    pr = build_problem(tab, DEFAULT_EE, launch=launch)
    assert pr.launch is not None and np.isfinite(pr.launch[2]).any()  # observed launches
    return pr


SETS: list[list[type[Effect]]] = [
    [BandMass, DragScale],
    [StrokeOffset, ReleasePitch, ShapeStretch, BandDamping],
    [law_class(BandMass, "mass_kg", True), DragScale],
    [Wind],
    [Downwash, Spin],
    [DownwashDecay, BandMass],
]


def _points(lo: np.ndarray, hi: np.ndarray, start: np.ndarray) -> list[np.ndarray]:
    """Inside, on a lower bound, next to an upper bound, and at zero where allowed."""
    rng = np.random.default_rng(0)
    inside = lo + (hi - lo) * rng.uniform(0.2, 0.8, lo.size)
    at_lo = inside.copy()
    at_lo[0] = lo[0]
    near_hi = inside.copy()
    near_hi[-1] = hi[-1] - 1e-4 * (hi[-1] - lo[-1])
    zero = np.clip(np.zeros_like(lo), lo, hi)
    return [start, inside, at_lo, near_hi, zero]


@pytest.mark.parametrize("which", range(len(SETS)))
def test_jacobian_bitwise_scipy(prob: GapProblem, tracked: GapProblem, which: int) -> None:
    classes = SETS[which]
    assert stackable(classes, permute=False)
    for pr in (prob, tracked):
        train = np.arange(0, len(pr), 2)  # a subset of the throws, in order
        scale, lo, hi, start = _layout(classes)

        def fun(
            x: np.ndarray, pr: GapProblem = pr, train: np.ndarray = train, sc: np.ndarray = scale
        ) -> np.ndarray:
            return pr.residual(train, _unpack(classes, x, sc)).ravel()

        jac = stacked_jacobian(pr, classes, train, scale, (lo, hi), DIFF_STEP)
        for x in _points(lo, hi, np.clip(start, lo, hi)):
            ref = approx_derivative(fun, x, method="2-point", rel_step=DIFF_STEP, bounds=(lo, hi))
            got = jac(x)
            assert got.shape == ref.shape == (2 * train.size, lo.size)
            # the effects move the landings (the tracked throws, from another launcher,
            # only by their flight)
            flight = any(c.phase == "flight" for c in classes)
            assert np.any(got != 0.0) or (pr is tracked and not flight)
            assert np.array_equal(got, ref)


def test_not_stackable() -> None:
    """Effects read as scalars (a bounce's switch, a per-object law) and the permutation
    control keep scipy's own differences."""
    assert not stackable([BandMass, Bounce], permute=False)
    assert not stackable([BandMass], permute=True)
    assert not stackable([], permute=False)


def test_per_object_not_stackable(prob: GapProblem) -> None:
    assert not stackable([per_object_class(BandMass, prob)], permute=False)


def test_fit_the_same(prob: GapProblem, monkeypatch: pytest.MonkeyPatch) -> None:
    """A whole fit with the stacked Jacobian is the fit with scipy's own differences."""
    classes: list[type[Effect]] = [BandMass, DragScale]
    train = np.arange(len(prob))
    fast, r_fast, j_fast = fit_set(prob, classes, train)
    monkeypatch.setattr(fit_mod, "stackable", lambda classes, permute: False)
    slow, r_slow, j_slow = fit_set(prob, classes, train)
    assert np.array_equal(fast.x, slow.x)
    assert np.array_equal(r_fast, r_slow)
    assert np.array_equal(j_fast, j_slow)
    assert fast.train_rmse_m == slow.train_rmse_m


@pytest.mark.parametrize("classes", [[BandMass, DragScale], [DownwashDecay]])
def test_score_the_same(
    prob: GapProblem, classes: list[type[Effect]], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The folds refitted and predicted in lockstep give each fold's own numbers: the
    held-out misses of the one-fold-at-a-time code, bitwise."""
    fast = score_set(prob, classes)
    monkeypatch.setattr(fit_mod, "stackable", lambda classes, permute: False)
    slow = score_set(prob, classes)
    assert np.array_equal(fast.full.x, slow.full.x)
    assert np.array_equal(fast.heldout, slow.heldout)
    assert fast.heldout_rmse_m == slow.heldout_rmse_m
    assert np.all(fast.heldout > 0.0)


def _scipys_own(one: Any, bounds: Any, rel_step: float) -> tuple[Any, str]:
    return one, "2-point"


@pytest.mark.parametrize(
    ("classes", "permute"), [([BandMass, Bounce], False), ([BandMass, DragScale], True)]
)
def test_side_by_side_fit_is_scipys(
    prob: GapProblem, classes: list[type[Effect]], permute: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A set that cannot be stacked (a bounce; the permutation control): its Jacobian's
    perturbed residuals evaluated side by side (`side_by_side_fun_jac`, their flights as
    one batch) and its folds refitted side by side give, bit for bit, the fit and the
    held-out misses of scipy's own differences and of the folds one after another."""
    assert not stackable(classes, permute)
    fast = score_set(prob, classes, permute=permute)
    monkeypatch.setattr(fit_mod, "side_by_side_fun_jac", _scipys_own)
    monkeypatch.setattr(fit_mod, "side_by_side", lambda thunks: [t() for t in thunks])
    slow = score_set(prob, classes, permute=permute)
    assert np.array_equal(fast.full.x, slow.full.x)
    assert np.array_equal(fast.full.ci, slow.full.ci)
    assert np.array_equal(fast.heldout, slow.heldout)
    assert np.all(fast.heldout > 0.0)
