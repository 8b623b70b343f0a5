"""What a constant-wind fit of a scene wind campaign should find, measured in the world.

`cell gap check --worlds scene` compares the wind the diagnosis finds with the air
velocity the world blew. Two things set them apart, both measured here on a case's own
throws (thrown in the scene with and without the wind, the same jitter; no tracker):

- the configured model's drag constant k = ½ ρ C_d A / m differs from the scene's per
  object (robots/cell_scene/ee_params.yaml's identified masses against the catalogue's:
  k_configured / k_scene from 0.90 for cube30 to 2.41 for cyl70). The wind shift of a
  landing goes with k, so the configured model needs about w · k_scene / k_configured per
  object, and one wind over several objects is their least-squares compromise
  (`fitted_wind` without, and with the model's drag made the scene's per object);
- a wind drawn per throw (form `throw`) is fitted as one constant: to first order the
  least-squares constant is the draws' mean weighted by each throw's sensitivity,
  w* = (Σ JᵢᵀJᵢ)⁻¹ Σ JᵢᵀJᵢ wᵢ (Jᵢ = ∂ landing / ∂ wind, 2 × 2), whose scatter over redraws
  is σ² (Σ JᵀJ)⁻¹ Σ (JᵀJ)² (Σ JᵀJ)⁻¹ (`weighted_wind`). The quadratic law's own bias:
  to second order in σ, E over w of |u|u (u = v − w, w's horizontal part ~ N(w̄, σ² I₂))
  is |ū|ū times 1 + σ² (4 − |ū_h|²/|ū|²) / (2 |ū|²) across and 1 + σ² (2 − |ū_h|²/|ū|²)
  / (2 |ū|²) up (ū = v − w̄): the mean wind's drag made stronger, which a constant wind
  reads as a larger wind; its large-sample limit is `expected_shift` fitted.

`python -m cell.gap.scene_wind CASE [CASE ...]` prints the measurements as JSON.
"""

from __future__ import annotations

import json
import sys
from typing import Any

import numpy as np

from cell.model.effects import DragScale, Effect, Wind, WindLevel
from cell.model.effects_apply import predict_with_effects
from cell.model.throw import ThrowBatch

__all__ = ["expected_shift", "fitted_wind", "measure_case", "weighted_wind", "wind_jacobians"]


def _air(w: np.ndarray) -> Effect:
    """A level wind; one per throw when w is (n, 2) (`Effect.per_throw`'s arithmetic)."""
    w = np.asarray(w, float)
    if w.ndim == 1:
        return WindLevel(float(w[0]), float(w[1])) if len(w) == 2 else Wind(*map(float, w))
    out = object.__new__(Wind)
    for name, col in zip(
        ("x_mps", "y_mps", "z_mps"), (w[:, 0], w[:, 1], 0.0 * w[:, 0]), strict=True
    ):
        object.__setattr__(out, name, col)
    return out


def _drag(factor: np.ndarray | None) -> list[Effect]:
    """The model's drag times `factor` per throw (none when None)."""
    if factor is None:
        return []
    out = object.__new__(DragScale)
    object.__setattr__(out, "factor", np.asarray(factor, float))
    return [out]


def _k(obj: Any) -> float:
    """An object's C_d A / m [m²/kg]: its drag constant without ½ ρ."""
    return float(obj.cd * obj.area / obj.mass)


def _landing(batch: ThrowBatch, ee: Any, w: np.ndarray, factor: np.ndarray | None) -> np.ndarray:
    return np.asarray(predict_with_effects(batch, ee, [_air(w), *_drag(factor)]).xy, float)


def wind_jacobians(batch: ThrowBatch, ee: Any, w0: np.ndarray, h: float = 1e-3) -> np.ndarray:
    """∂ landing xy / ∂ level wind (n, 2, 2) [s] at the wind w0 [m/s], central differences."""
    w0 = np.asarray(w0, float)
    cols = [(_landing(batch, ee, w0 + h * e, None) - _landing(batch, ee, w0 - h * e, None)) / (2 * h)
            for e in np.eye(2)]  # fmt: skip
    return np.stack(cols, axis=-1)


def weighted_wind(jac: np.ndarray, winds: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """The constant wind a linear least-squares fit finds from throws each blown by its own
    wind: (w* [m/s] (2,), its covariance over redraws per unit draw variance (2, 2) [-],
    the effective number of throws (Σ tr JᵀJ)² / Σ (tr JᵀJ)²)."""
    a = np.einsum("nki,nkj->nij", jac, jac)
    s_inv = np.linalg.inv(a.sum(axis=0))
    w = s_inv @ np.einsum("nij,nj->i", a, np.asarray(winds, float))
    cov = s_inv @ np.einsum("nij,njk->ik", a, a) @ s_inv
    tr = np.trace(a, axis1=1, axis2=2)
    return w, cov, float(tr.sum() ** 2 / np.sum(tr**2))


def fitted_wind(batch: ThrowBatch, ee: Any, shift: np.ndarray, *, factor: np.ndarray | None = None,
                vertical: bool = False) -> tuple[np.ndarray, float]:  # fmt: skip
    """The constant wind [m/s] whose shift of the model's landings (with the drag times
    `factor` per throw) best matches `shift` (n, 2) [m] in least squares, and the RMS 2-D
    residual [m]."""
    from scipy.optimize import least_squares

    base = _landing(batch, ee, np.zeros(2), factor)

    def res(w: np.ndarray) -> np.ndarray:
        return ((_landing(batch, ee, w, factor) - base) - shift).ravel()

    r = least_squares(res, np.zeros(3 if vertical else 2), diff_step=1e-3)
    return r.x, float(np.sqrt(np.mean(np.sum(r.fun.reshape(-1, 2) ** 2, axis=1))))


def expected_shift(batch: ThrowBatch, ee: Any, mean: np.ndarray, sd: float, nodes: int = 9,
                   factor: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """E over w ~ N(mean, sd² I₂) of each throw's landing shift [m] (n, 2): Gauss–Hermite
    with nodes² points."""
    x, wq = np.polynomial.hermite_e.hermegauss(nodes)
    wq = wq / wq.sum()
    base = _landing(batch, ee, np.zeros(2), factor)
    out = np.zeros((len(batch), 2))
    for i, a in enumerate(x):
        for j, b in enumerate(x):
            w = np.asarray(mean, float) + sd * np.array([a, b])
            out += wq[i] * wq[j] * (_landing(batch, ee, w, factor) - base)
    return out


def measure_case(name: str, n: int = 80) -> dict[str, Any]:
    """A scene wind case's throws (as `cell gap check --worlds scene` draws them) thrown
    with and without the wind; the winds a constant-wind fit should find."""
    from cell.gap.check_scene import scene_cases
    from cell.gap.world_scene import _records, draw_plan, matched_objects, throw_plan
    from cell.log.table import ThrowTable
    from cell.params import load_params, scene_params_path
    from cell.sim.items import resolve_object

    mp = load_params(scene_params_path())
    case = scene_cases((name,), n=n)[0]
    rng = np.random.default_rng(case["world_seed"])
    wd = next(e for e in case["effects"] if e["kind"] == "wind")
    objects = None if case["options"].get("all_objects") else matched_objects(mp)
    plan = draw_plan(n, rng, objects=objects, drone_share=case["options"].get("drone_share", 0.0))
    seed = int(rng.integers(2**31))
    xy, tl, _ = throw_plan(plan, [wd], seed)
    xy0, _, _ = throw_plan(plan, [], seed)
    mean = np.array([wd["x_mps"], wd["y_mps"]], float)
    sd = float(wd.get("sd", 0.0)) if wd["form"] == "throw" else 0.0
    winds = np.tile(mean, (n, 1))
    if sd > 0:  # throw_plan's draws: one per planned throw, in order, from `seed`
        draw = np.random.default_rng(seed)
        winds += np.array([draw.normal(0.0, sd, 2) for _ in range(n)])
    ok = np.all(np.isfinite(xy), axis=1) & np.all(np.isfinite(xy0), axis=1)
    batch = ThrowTable.from_records(_records(plan, xy, tl, ok)).to_batch(objects=mp.objects)
    ids = [plan[i].object_id for i in np.flatnonzero(ok)]
    # the scene's k over the configured one per throw (as `matched_objects` takes it)
    factor = np.array([_k(resolve_object(k)[0]) / _k(mp.objects[k]) for k in ids])
    shift = (xy - xy0)[ok]
    out: dict[str, Any] = {"case": name, "throws": int(ok.sum()), "wind_mps": mean.tolist(),
                           "sd_mps": sd, "k_configured_over_scene": {
                               k: float(1 / f) for k, f in sorted(zip(ids, factor, strict=True))}}  # fmt: skip
    for label, fac in (("configured", None), ("scene_drag", factor)):
        for vert in (False, True):
            w, r = fitted_wind(batch, mp.ee, shift, factor=fac, vertical=vert)
            out[f"fit_{label}_{'vertical' if vert else 'level'}"] = {
                "wind_mps": w.tolist(),
                "rms_m": r,
            }
    if sd > 0:
        jac = wind_jacobians(batch, mp.ee, mean)
        w, cov, n_eff = weighted_wind(jac, winds[ok])
        lim, _ = fitted_wind(batch, mp.ee, expected_shift(batch, mp.ee, mean, sd))
        out |= {"draws_mean_mps": winds[ok].mean(axis=0).tolist(),
                "draws_weighted_mean_mps": w.tolist(),
                "weighted_mean_sd_mps": (sd * np.sqrt(np.diag(cov))).tolist(),
                "effective_throws": n_eff, "large_sample_fit_mps": lim.tolist()}  # fmt: skip
    return out


if __name__ == "__main__":  # pragma: no cover
    for arg in sys.argv[1:]:
        print(json.dumps(measure_case(arg)), flush=True)
