"""Calibration in the scene: identify the η_ee (and η_o) the planner uses for the scene.

A campaign of catalogue throws is made in the scene (cell.sim.campaign), and
the two-stage identification (cell.identify, thesis Algorithm 1) fits the
nominal model to their landings. The simulated launch comes out of the band
physics (energy of the stretched band shared with the moving carriage,
finger contact, the item's rotation), not from the nominal impulse law, so
the nominal model misses it by a mass-dependent amount: `gap_summary`
measures that gap before the fit and what is left after it.

The nominal push gives v = f_o Δt / m, the band gives v ≈ √(2E / (m + m_b))
(E the band's energy, m_b the mass moving with the item). The identified
effective masses of the campaign's objects follow m_eff = κ √(m + m_b)
closely, so `mass_rule` fits κ and m_b to them and `extend_objects` gives
every other catalogue object (never thrown in the campaign) the effective
mass the rule predicts from its catalogue mass, so the planner's nominal
model also carries over to objects outside the campaign.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from cell.catalogue import catalogue
from cell.errors import InvalidInput
from cell.identify import IdentifyOptions, IdentifyResult, identify
from cell.identify.report import predicted_landing, reach
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.params import ModelParams

__all__ = [
    "GapSummary",
    "MassRule",
    "gap_summary",
    "mass_rule",
    "extend_objects",
    "calibrate_table",
    "OBJECT_BOUND",
]

OBJECT_BOUND = 0.7  # η_o factors may move by ±70 %: the sim's effective masses need it


@dataclass(frozen=True)
class GapSummary:
    """Model vs scene on a set of throws.

    Attributes:
        rmse_m: landing RMSE [m].
        reach_bias: mean of (model reach − scene reach) / scene reach.
        reach_rel_rms: RMS of that relative reach error.
        by_object: object id -> mean relative reach error.
    """

    rmse_m: float
    reach_bias: float
    reach_rel_rms: float
    by_object: dict[str, float]

    def as_dict(self) -> dict[str, Any]:
        """Plain numbers for JSON."""
        return {
            "rmse_m": self.rmse_m,
            "reach_bias": self.reach_bias,
            "reach_rel_rms": self.reach_rel_rms,
            "by_object": dict(self.by_object),
        }


def gap_summary(table: ThrowTable, params: ModelParams) -> GapSummary:
    """How far the model with `params` lands from the scene's landings."""
    pred = predicted_landing(table, params)
    obs = table.landed
    r_obs = reach(table, obs)
    rel = (reach(table, pred) - r_obs) / r_obs
    ids = table.text("object_id")
    by = {o: float(np.mean(rel[[i == o for i in ids]])) for o in sorted(set(ids))}
    return GapSummary(
        rmse_m=float(np.sqrt(np.nanmean(np.sum((pred - obs) ** 2, axis=1)))),
        reach_bias=float(np.nanmean(rel)),
        reach_rel_rms=float(np.sqrt(np.nanmean(rel**2))),
        by_object=by,
    )


@dataclass(frozen=True)
class MassRule:
    """Effective mass of the nominal model for the scene: m_eff = κ √(m + m_b).

    Attributes:
        kappa: κ [kg^½].
        band_mass_kg: m_b [kg], the mass that moves with the item.
        rms_log_error: RMS of log(rule / identified) over the fitted objects.
    """

    kappa: float
    band_mass_kg: float
    rms_log_error: float

    def __call__(self, mass_kg: float) -> float:
        """m_eff [kg] for a catalogue mass [kg]."""
        return float(self.kappa * np.sqrt(mass_kg + self.band_mass_kg))


def mass_rule(identified: dict[str, ObjectParams], nominal: dict[str, ObjectParams]) -> MassRule:
    """Fit m_eff = κ √(m + m_b) to identified effective masses (log least squares).

    Args:
        identified: identified η_o by object id.
        nominal: the catalogue's η_o by object id (the same ids).

    Raises:
        InvalidInput: fewer than two objects.
    """
    ids = sorted(set(identified) & set(nominal))
    if len(ids) < 2:
        raise InvalidInput(f"the mass rule needs two or more identified objects, got {ids}")
    m = np.array([nominal[k].mass for k in ids])
    me = np.array([identified[k].mass for k in ids])

    def res(z: np.ndarray) -> np.ndarray:
        return np.log(z[0] * np.sqrt(m + z[1])) - np.log(me)

    sol = least_squares(res, [0.15, 0.01], bounds=([1e-4, 0.0], [10.0, 1.0]))
    return MassRule(
        kappa=float(sol.x[0]),
        band_mass_kg=float(sol.x[1]),
        rms_log_error=float(np.sqrt(np.mean(res(sol.x) ** 2))),
    )


def extend_objects(params: ModelParams, rule: MassRule) -> ModelParams:
    """Add every catalogue object the parameters lack, with the rule's effective mass.

    Identified objects keep their values; the others keep their catalogue
    shape and extents.
    """
    objects = dict(params.objects)
    for oid, entry in catalogue().items():
        if oid not in objects:
            o = entry.params
            objects[oid] = ObjectParams(shape=o.shape, mass=rule(o.mass), size=o.size, name=oid)
    return replace(params, objects=objects)


def calibrate_table(
    table: ThrowTable, *, max_iter: int = 12, progress: Any = None
) -> tuple[IdentifyResult, GapSummary, GapSummary, MassRule]:
    """Identify the scene's parameters from a campaign log.

    Args:
        table: the campaign's throws.
        max_iter: most outer identification iterations.
        progress: passed to cell.identify.identify.

    Returns:
        (identification result whose parameters cover every catalogue object and
        carry a note, gap of the nominal model, gap after the fit, the mass rule).
    """
    nominal = gap_summary(table, ModelParams())
    res = identify(
        table,
        options=IdentifyOptions(object_bound=OBJECT_BOUND, max_iter=max_iter),
        progress=progress,
    )
    fitted = gap_summary(table, res.params)
    cat = {k: e.params for k, e in catalogue().items()}
    rule = mass_rule(res.params.objects, cat)
    extended = extend_objects(res.params, rule)
    note = (
        f"PyBullet cell scene calibration (cell calibrate): {len(table)} throws of "
        f"{len(nominal.by_object)} catalogue objects, end-effector held at each release pose, "
        f"landing = centre of mass crossing z = land_z. {res.params.note}. Nominal model vs "
        f"scene: RMSE {nominal.rmse_m:.3f} m, reach error {100 * nominal.reach_rel_rms:.1f} % "
        f"RMS; after the fit: RMSE {fitted.rmse_m:.3f} m, {100 * fitted.reach_rel_rms:.1f} % RMS. "
        f"Objects not in the campaign get m_eff = kappa sqrt(m + m_b), kappa = {rule.kappa:.4f}, "
        f"m_b = {rule.band_mass_kg:.4f} kg, fitted to the identified masses "
        f"({100 * rule.rms_log_error:.1f} % RMS), with their catalogue extents."
    )
    res = replace(
        res,
        params=replace(extended, note=note, mass_rule=(rule.kappa, rule.band_mass_kg)),
    )
    return res, nominal, fitted, rule
