"""The grip constraint's polytope rows built at once (`_coefficients`) are, bit for bit, the
rows built one direction and sign at a time (the form before 2026-11-29), so a carry shaped
by the grip is the same trajectory; and the constraint toppra gets carries them."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from cell.errors import TrajectoryError
from cell.robot.grip_constraint import _coefficients, grip_constraint
from cell.robot.grip_hold import GripHold, _sphere_directions
from cell.robot.model import load_robot


def _row_by_row(mass_kg: float, force_n: float, torque_nm: float) -> np.ndarray:
    dirs, cover = _sphere_directions()
    rows = [np.r_[mass_kg * d / (cover * force_n), sg] for d in dirs for sg in (1, -1)]
    coef = np.array(rows)
    if torque_nm > 0.0:
        coef[:, 3] /= torque_nm
    else:
        coef[:, 3] *= 1e6
    return coef


@pytest.mark.parametrize(
    ("mass_kg", "force_n", "torque_nm"),
    [(0.048, 3.7, 0.0), (0.048, 3.7, 0.021), (0.31, 9.81, 0.3), (1.7, 41.3, 1e-4), (0.2, 5.5, 0.0)],
)
def test_rows_equal_bit_for_bit(mass_kg: float, force_n: float, torque_nm: float) -> None:
    got = _coefficients(mass_kg, force_n, torque_nm)
    want = _row_by_row(mass_kg, force_n, torque_nm)
    assert got.shape == want.shape == (256, 4)
    assert got.tobytes() == want.tobytes()
    assert not got.flags.writeable  # shared by every carry of the hold


def test_constraint_carries_the_rows() -> None:
    robot = load_robot("panda")
    hold = GripHold(3.7, 0.021, 0.048, 1e-5, (0.0, 0.0, 0.03), 0.03)
    c = grip_constraint(robot, hold, 0.8)
    q = np.zeros(robot.dof)
    assert c.constraint_F(q).tobytes() == _row_by_row(0.048, 3.7, 0.021).tobytes()
    assert np.all(c.constraint_g(q) == 0.8)


def _as_toppra_takes_it(c: object) -> object:
    """The same constraint handed to toppra as before: F a grid point each (not
    `identical`), toppra's solver multiplying it out."""
    old = copy.copy(c)
    old.identical = False  # type: ignore[attr-defined]
    old.compute_constraint_params = c.colloc_params  # type: ignore[attr-defined]
    return old


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_carries_shaped_by_the_grip_are_the_same_trajectories(name: str) -> None:
    """plan_path with the grip constraint multiplied out gives the trajectory toppra gives
    with it a grid point at a time, bit for bit (durations and samples), on random paths
    of both arms, holds with and without a couple, bounds that bind."""
    from cell.robot.motion import plan_path

    rb = load_robot(name)
    rng = np.random.default_rng(7)
    holds = [
        GripHold(1.3, 0.2, 0.048, 1e-5, (0.0, 0.0, 0.03), 0.03),
        GripHold(3.0, 0.1, 0.12, 1e-4, (0.0, 0.01, 0.05), 0.03, 0.02, 0.05, 1e-4, 0.02),
        GripHold(1.6, 0.0, 0.048, 2e-5, (0.0, 0.0, 0.02), 0.02),
    ]
    compared = slowed = 0
    for k in range(6):
        q0 = np.clip(rb.home + rng.uniform(-0.5, 0.5, rb.dof), rb.limits.lower, rb.limits.upper)
        q1 = np.clip(q0 + rng.uniform(-1.2, 1.2, rb.dof), rb.limits.lower, rb.limits.upper)
        way = [q0, np.clip((q0 + q1) / 2 + 0.1, rb.limits.lower, rb.limits.upper), q1]
        hold = holds[k % len(holds)]
        for bound in (0.77, 0.5):
            c = grip_constraint(rb, hold, bound)
            try:
                old = plan_path(way, rb, constraints=[_as_toppra_takes_it(c)])
            except TrajectoryError:
                with pytest.raises(TrajectoryError):
                    plan_path(way, rb, constraints=[c])
                continue
            new = plan_path(way, rb, constraints=[c])
            assert new.duration == old.duration
            ts = np.linspace(0.0, old.duration, 301)
            for a, b in zip(new.sample_many(ts), old.sample_many(ts), strict=True):
                assert a.tobytes() == b.tobytes()
            compared += 1
            slowed += new.duration > plan_path(way, rb).duration + 1e-3
    assert compared >= 4  # most cases are planned, not refused
    assert slowed >= 2  # and the grip binds in some: the constraint shapes them


def test_rows_times_the_identity_are_blass_product() -> None:
    """`_TimesIdentity.dot`, what toppra's seidel set-up multiplies F a, F b, F c by (Fᵀ,
    the identity): BLAS's product bit for bit, on one BLAS thread and two, for rows with
    -0.0 and +0.0 among their entries, all-zero rows, rows with a NaN or an infinity (the
    product itself), and by another matrix (an ordinary product)."""
    from threadpoolctl import threadpool_limits

    from cell.robot.grip_constraint import _identity, _TimesIdentity

    rng = np.random.default_rng(67)
    for n, k in ((512, 131), (512, 2), (8, 40)):
        x = rng.normal(0.0, 3.0, (k, n))
        x[rng.random((k, n)) < 0.2] = -0.0
        x[rng.random((k, n)) < 0.1] = 0.0
        x[0] = -0.0
        rows = x.view(_TimesIdentity)
        eye = _identity(n)
        other = rng.normal(size=(n, n))
        for threads in (1, 2):
            with threadpool_limits(threads):
                got = rows.dot(eye.T)
                assert type(got) is np.ndarray
                assert got.tobytes() == x.dot(eye.T).tobytes()
                assert rows.dot(other).tobytes() == x.dot(other).tobytes()
        bad = x.copy()
        bad[1, 3], bad[-1, 0] = np.nan, np.inf
        with np.errstate(invalid="ignore"):
            got, want = bad.view(_TimesIdentity).dot(eye.T), bad.dot(eye.T)
        assert np.array_equal(np.isnan(got), np.isnan(want))
        assert np.array_equal(got[~np.isnan(got)], want[~np.isnan(want)])
