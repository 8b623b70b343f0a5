"""Calibration in the scene: identify the η_ee (and η_o) the planner uses for the scene.

A campaign of catalogue throws is made in the scene (cell.workflows.campaign), and
the two-stage identification (cell.identify, thesis Algorithm 1) fits the
nominal model to their landings. The simulated launch comes out of the band
physics (energy of the stretched band shared with the moving carriage,
finger contact, the item's rotation), not from the nominal impulse law, so
the nominal model misses it by a mass-dependent amount: `gap_summary`
measures that gap before the fit and what is left after it.

The nominal push gives v = f_o Δt / m, the band gives v ≈ √(2E / (m + m_b))
(E the band's energy, m_b the mass moving with the item). The identified
effective masses of the campaign's objects follow m_eff = κ √(m + m_b)
closely; `extend_objects` gives every other catalogue object (never thrown in
the campaign) the effective mass the rule predicts from its catalogue mass, so
the planner's nominal model also carries over to objects outside the campaign.

Two things the catalogue campaign (20–70 g, 15–50°) cannot show decide the
envelope's edges (heavy items to 250 g, wide ones to 90 mm, elevations 0–65°):

* the scene's carriage runs on from the end of the push to its end stop with the
  item before it flies free, so the item is carried further along the throw axis and
  gravity's component along the axis takes 2 g sin(e) (L_e − L_s) from its speed
  squared: a slow (heavy) item thrown steeply loses most, a flat throw gains reach.
  `calibrate_table(release_m=...)` puts that ride into the model (η_ee's L_e, see
  `cell.model.throw.ride`) before η_ee is identified;
* the ratio of the model's push to the band's energy changes with the grip width, so
  the rule gets a width factor (a / a_ref)^β, and κ, m_b and β are fitted
  (`fit_mass_rule`) to the landings of ad-hoc items thrown over the whole envelope
  (`cell.workflows.campaign.adhoc_plan`, a random stream of its own: never the bench's).
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
from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.model.throw import predict_landing
from cell.params import WIDTH_REF_M, ModelParams, Validation

__all__ = [
    "GapSummary",
    "MassRule",
    "gap_summary",
    "mass_rule",
    "fit_mass_rule",
    "WIDTH_REF_M",
    "extend_objects",
    "calibrate_table",
    "OBJECT_BOUND",
    "validate",
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
    """Effective mass of the nominal model for the scene: m_eff = κ √(m + m_b) (a / a_ref)^β.

    The scene launches an item at v ≈ √(2 E(L_s, a) / (m + m_b)): the band's energy shared
    with the carriage and pads that move with it (m_b). The model launches it at
    f_o(L_s, a) Δt / m_eff, so m_eff grows as √(m + m_b), and the ratio of the model's push
    to the band's energy changes with the grip width a, which (a / a_ref)^β takes up
    (a_ref = WIDTH_REF_M; β = 0 is the width-free law of older files).

    Attributes:
        kappa: κ [kg^½].
        band_mass_kg: m_b [kg], the mass that moves with the item.
        rms_log_error: RMS of log(rule / identified) over the identified objects.
        width_exponent: β.
        rms_reach_error: RMS relative reach error on the throws the rule was fitted to
            (NaN when it was fitted to identified masses only).
    """

    kappa: float
    band_mass_kg: float
    rms_log_error: float
    width_exponent: float = 0.0
    rms_reach_error: float = float("nan")

    def __call__(self, mass_kg: Any, width_m: Any = WIDTH_REF_M) -> Any:
        """m_eff [kg] for a catalogue mass [kg] and grip width [m] (scalars or arrays)."""
        m_eff = self.kappa * np.sqrt(np.asarray(mass_kg, float) + self.band_mass_kg)
        m_eff = m_eff * (np.asarray(width_m, float) / WIDTH_REF_M) ** self.width_exponent
        return float(m_eff) if np.ndim(m_eff) == 0 else m_eff

    def as_tuple(self) -> tuple[float, float, float]:
        """(κ, m_b, β), as `ModelParams.mass_rule` holds it."""
        return (self.kappa, self.band_mass_kg, self.width_exponent)


def mass_rule(identified: dict[str, ObjectParams], nominal: dict[str, ObjectParams]) -> MassRule:
    """Fit m_eff = κ √(m + m_b) to identified effective masses (log least squares; β = 0).

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


WIDTH_EXPONENT_BOUND = 1.0  # |β| at most: the width changes m_eff by at most 3.6× over 25-90 mm


def fit_mass_rule(table: ThrowTable, ee: EndEffectorParams, start: MassRule) -> MassRule:
    """Fit κ, m_b and β of the mass rule to the landings of throws of objects it plans.

    Each throw is predicted by the nominal model with `ee` and the object's logged shape and
    extents with the rule's effective mass (as `ModelParams.model_object` plans an object
    outside the campaign); the fit minimises the relative reach errors.

    Args:
        table: throws of objects the identification did not fit (logged mass and extents).
        ee: the identified end-effector.
        start: the start values (e.g. the rule fitted to identified masses).

    Raises:
        InvalidInput: fewer than four usable throws.
    """
    stroke = table.num("stroke_m")
    ok = np.flatnonzero(np.isfinite(stroke) & np.all(np.isfinite(table.landed), axis=1))
    if ok.size < 4:
        raise InvalidInput(f"the mass rule needs four or more throws to fit, got {ok.size}")
    sub = table.take(ok)
    batch = sub.to_batch()
    r_obs = reach(sub, sub.landed)
    width = batch.size[:, 0]

    def res(z: np.ndarray) -> np.ndarray:
        rule = MassRule(float(z[0]), float(z[1]), float("nan"), float(z[2]))
        b = replace(batch, mass=np.asarray(rule(batch.mass, width)))
        land = predict_landing(b, ee, strict=False, check_stroke=False)
        rel = (reach(sub, land.xy) - r_obs) / r_obs
        return np.where(np.isfinite(rel), rel, 1.0)

    z0 = [start.kappa, start.band_mass_kg, start.width_exponent]
    lo = [1e-4, 0.0, -WIDTH_EXPONENT_BOUND]
    hi = [10.0, 1.0, WIDTH_EXPONENT_BOUND]
    z0 = list(np.clip(z0, lo, hi))
    sol = least_squares(res, z0, bounds=(lo, hi), x_scale=[0.05, 0.01, 0.1])
    return MassRule(
        kappa=float(sol.x[0]),
        band_mass_kg=float(sol.x[1]),
        rms_log_error=start.rms_log_error,
        width_exponent=float(sol.x[2]),
        rms_reach_error=float(np.sqrt(np.mean(sol.fun**2))),
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
            objects[oid] = ObjectParams(
                shape=o.shape, mass=rule(o.mass, o.width), size=o.size, name=oid
            )
    return replace(params, objects=objects)


def calibrate_table(
    table: ThrowTable,
    *,
    adhoc: ThrowTable | None = None,
    release_m: float = 0.0,
    max_iter: int = 12,
    progress: Any = None,
) -> tuple[IdentifyResult, GapSummary, GapSummary, MassRule]:
    """Identify the scene's parameters from a campaign log.

    Args:
        table: the campaign's throws of catalogue objects (η_ee and their η_o are identified).
        adhoc: throws of items outside the catalogue over the whole envelope (campaign
            `adhoc_plan`): the mass rule's κ, m_b and β are fitted to their landings with the
            identified η_ee. None: the rule is fitted to the identified masses (β = 0).
        release_m: L_e, the carriage position where the item leaves (0: the thesis model).
        max_iter: most outer identification iterations.
        progress: passed to cell.identify.identify.

    Returns:
        (identification result whose parameters cover every catalogue object and
        carry a note, gap of the nominal model, gap after the fit, the mass rule).
    """
    nominal = gap_summary(table, ModelParams())
    start = ModelParams(ee=replace(DEFAULT_EE, L_e=float(release_m)))
    res = identify(
        table,
        start,
        options=IdentifyOptions(object_bound=OBJECT_BOUND, max_iter=max_iter),
        progress=progress,
    )
    fitted = gap_summary(table, res.params)
    cat = {k: e.params for k, e in catalogue().items()}
    rule = mass_rule(res.params.objects, cat)
    if adhoc is not None:
        rule = fit_mass_rule(adhoc, res.params.ee, rule)
    extended = extend_objects(res.params, rule)
    ride = (
        f"The item rides the carriage to L_e = {release_m:.3f} m after the push. "
        if release_m > 0
        else ""
    )
    if adhoc is not None:
        law = (
            f"Objects not in the campaign get m_eff = kappa sqrt(m + m_b) (a / "
            f"{WIDTH_REF_M:.2f} m)^beta, kappa = {rule.kappa:.4f}, m_b = "
            f"{rule.band_mass_kg:.4f} kg, beta = {rule.width_exponent:.3f}, fitted to "
            f"{len(adhoc)} throws of ad-hoc items over the envelope "
            f"({100 * rule.rms_reach_error:.1f} % RMS reach error), with their catalogue extents."
        )
    else:
        law = (
            f"Objects not in the campaign get m_eff = kappa sqrt(m + m_b), kappa = "
            f"{rule.kappa:.4f}, m_b = {rule.band_mass_kg:.4f} kg, fitted to the identified "
            f"masses ({100 * rule.rms_log_error:.1f} % RMS), with their catalogue extents."
        )
    note = (
        f"PyBullet cell scene calibration (cell calibrate): {len(table)} throws of "
        f"{len(nominal.by_object)} catalogue objects, end-effector held at each release pose, "
        f"landing = centre of mass crossing z = land_z. {res.params.note}. {ride}Nominal model "
        f"vs scene: RMSE {nominal.rmse_m:.3f} m, reach error {100 * nominal.reach_rel_rms:.1f} % "
        f"RMS; after the fit: RMSE {fitted.rmse_m:.3f} m, {100 * fitted.reach_rel_rms:.1f} % RMS. "
        + law
    )
    res = replace(res, params=replace(extended, note=note, mass_rule=rule.as_tuple()))
    return res, nominal, fitted, rule


def validate(params: ModelParams, held: ThrowTable, seed: int) -> Validation:
    """The model's accuracy on held-out throws: per object, the RMS 2-D distance between
    the landings `params` predicts and the logged ones, over the throws `held` (which must
    be throws the parameters were not fitted to: `campaign_plan(held_out=True)`). The
    scene logs exact landings and repeats a throw to the bit, so this is the model's own
    misfit, with no tracker scatter in it. A throw the model says never lands is left out.

    Raises:
        InvalidInput: no held-out throw the model predicts.
    """
    miss = predicted_landing(held, params) - held.landed
    d2 = np.sum(miss * miss, axis=1)
    ids = np.array(held.text("object_id"))
    ok = np.isfinite(d2)
    out = {
        str(o): (float(np.sqrt(np.mean(d2[ok & (ids == o)]))), int(np.sum(ok & (ids == o))))
        for o in sorted(set(ids[ok]))
    }
    if not out:
        raise InvalidInput(f"validation: none of {len(held)} held-out throws is predicted")
    return Validation(objects=out, throws=int(ok.sum()), seed=int(seed))
