"""The law of an effect learned from the data: its parameter as a function of the throw.

An effect's parameter p (band_mass's `mass_kg`, release_pitch's `delta_rad`,
drag_scale's `factor`, the bounce's `inv_mu`, `tau_s` or `inv_mu_imp` in whichever of its
laws stands for it, ...) may follow one of these forms, c a logged covariate of the
throw (`stroke_m`, `mass_kg`, `size_x_m` the grip width):

| form | law | terms |
|---|---|---|
| constant | p = a | 1 |
| proportional | p = k · c | 1 |
| linear | p = a + k · c | 2 |

`law_class(base, covariate, intercept)` makes the form as an `Effect` class whose fields
are the form's coefficients; `Effect.per_throw` turns it into the base effect with one
value per throw (an array), which the model's effect code evaluates unchanged. A member of
two parameters takes a law in those its `law_params` name (the bounce's drop law: its 1/μ,
`inv_mu_drop = a + k · mass_kg`), its other parameters kept as fields of the form, one
value common to every throw (the drop law's depth, the cell's geometry); a one-parameter
effect takes it in its one parameter. The extra terms are counted over the member's own
parameters. The
diagnosis picks the form by held-out evidence with a penalty for each extra term
(`choose_law`): a form replaces the constant only when its held-out RMSE, raised by
TERM_PENALTY per extra term, is lower, and its cut over the constant has a bootstrap
interval above zero; a form that gives any logged throw a value outside the effect's
plausible range (or at a bound) is stretched and not chosen (`law_stretched`), as a
constant there is refused. On a log of two or more objects a law in a throw's quantity
must also hold whatever the object: it is refused where, with whole objects held out
(`objects_out`), it predicts them worse than the constant with a bootstrap interval below
zero (a law one object alone follows, or one taking up a partner's misfit that differs
from object to object). A covariate form is tried only where the covariate takes at least
MIN_LEVELS distinct values in the log: on two values (a log of two objects, say) a law in
the mass, one in the size and one per object are the same two numbers, so the difference
is the per-object form's, which pays for its second term.
"""

from __future__ import annotations

from dataclasses import make_dataclass, replace
from functools import partial
from typing import Any, ClassVar

import numpy as np

from cell.gap.fit import Score
from cell.gap.problem import GapProblem
from cell.model.effects import Effect
from cell.model.throw import ThrowBatch

__all__ = ["COVARIATES", "LAW_BASES", "MIN_LEVELS", "law_class", "law_params", "law_text", "levels",
           "TERM_PENALTY", "choose_law", "distinct", "law_range", "law_stretched"]  # fmt: skip

TERM_PENALTY = 0.03  # a form's held-out RMSE is raised by this share per extra term
MAX_OBJECTS = 12  # a per-object form is tried on logs of at most this many objects
MIN_LEVELS = 3  # a covariate form is tried where the covariate takes this many values
OBJECTS_OUT = "objects held out"  # the key of a form's RMSE on whole objects held out
# covariate name -> (how to read it off a batch, its typical largest value)
COVARIATES: dict[str, tuple[Any, float]] = {
    "stroke_m": (lambda b: b.stroke, 0.11),
    "mass_kg": (lambda b: b.mass, 0.12),
    "size_x_m": (lambda b: b.size[:, 0], 0.07),
}
LAW_BASES = ("band_mass", "release_pitch", "drag_scale", "band_damping", "bounce")
_CACHE: dict[tuple[type[Effect], str, bool, str], type[Effect]] = {}


def law_params(base: type[Effect]) -> tuple[str, ...]:
    """The parameters of a member a law of the throw may be given: those its `law_params`
    name, else the one parameter of a one-parameter member (none of a member of more)."""
    if base.law_params is not None:
        return tuple(base.law_params)
    names = base.param_names()
    return names if len(names) == 1 else ()


def _param(base: type[Effect], param: str | None) -> str:
    """The parameter a form's law is in: `param`, else the member's first law parameter."""
    if param is None:
        ps = law_params(base)
        if not ps:
            raise ValueError(f"effect {base.name} ({base.law}) takes no law of the throw")
        return ps[0]
    if param not in law_params(base):
        raise ValueError(f"effect {base.name}: {param!r} takes no law; valid: {law_params(base)}")
    return param


def _held(self: Any, base: type[Effect], out: Effect, vals: np.ndarray) -> Effect:
    """The base effect `out` with the law's values in its law parameter and the form's
    common values in the others."""
    for nm in base.param_names():
        object.__setattr__(out, nm, vals if nm == self.law_param else getattr(self, nm))
    return out


def law_text(base: type[Effect], covariate: str | None, intercept: bool,
             param: str | None = None) -> str:  # fmt: skip
    """The law as text: `mass_kg = k · stroke_m`, `delta_rad = a + k · mass_kg`."""
    p = _param(base, param)
    if covariate is None:
        return f"{p} = a"
    return f"{p} = a + k · {covariate}" if intercept else f"{p} = k · {covariate}"


def covariate_values(form: Any, batch: ThrowBatch) -> np.ndarray:
    """A form's covariate over a batch's throws: a logged quantity (`COVARIATES`), or one
    of the model's throw read with the end-effector the form carries
    (`cell.gap.law_speed.MODEL_COVARIATES`)."""
    from cell.gap.law_speed import MODEL_COVARIATES

    if form.covariate in MODEL_COVARIATES:
        return np.asarray(MODEL_COVARIATES[form.covariate][0](batch, form.ee), float)
    return np.asarray(COVARIATES[form.covariate][0](batch), float)


def _per_throw(self: Any, batch: ThrowBatch, permutation: np.ndarray | None = None) -> Effect:
    base: type[Effect] = self.law_base
    c = covariate_values(self, batch)
    if permutation is not None:
        c = c[permutation]
    lo, hi = base.bounds[base.param_names().index(self.law_param)]
    a = self.a if self.intercept else 0.0
    vals = np.clip(a + self.k * c, lo, hi)
    return _held(self, base, object.__new__(base), vals)


def _held_fields(base: type[Effect], param: str) -> tuple[list[tuple[str, type, Any]],
                                                           list[tuple[float, float]], list[float]]:  # fmt: skip
    """The fields, bounds and scales of a member's parameters other than `param` (kept
    common to every throw by a law in `param`), as the member has them."""
    names, neutral = base.param_names(), base.neutral().vector()
    i = [j for j, nm in enumerate(names) if nm != param]
    return ([(names[j], float, float(neutral[j])) for j in i], [base.bounds[j] for j in i],
            [base.scale[j] for j in i])  # fmt: skip


def law_class(base: type[Effect], covariate: str, intercept: bool,
              param: str | None = None, ee: Any = None) -> type[Effect]:  # fmt: skip
    """The effect class of `base` whose parameter `param` (by default its first of
    `law_params`) follows a + k · covariate (intercept) or k · covariate.

    Its fields: `a` (in the parameter's units, with intercept) and `k` (its units per
    covariate unit), then the base's other parameters, common to every throw; its law
    text is `law_text`. Its phase and name are the base's, and it hangs on the covariate
    (the permutation control shuffles the covariate). A covariate of the model's throw
    (`cell.gap.law_speed.MODEL_COVARIATES`) is read with the end-effector `ee`."""
    from cell.gap.law_speed import MODEL_COVARIATES

    param = _param(base, param)
    key = (base, covariate, intercept, param)
    if key in _CACHE and ee is None:
        return _CACHE[key]
    i = base.param_names().index(param)
    (lo, hi), sc = base.bounds[i], base.scale[i]
    cmax = {**COVARIATES, **MODEL_COVARIATES}[covariate][1]
    neutral = float(base.neutral().vector()[i])
    span = (hi - lo) / cmax
    k_bounds = (lo / cmax, hi / cmax) if not intercept else (-span, span)
    if not intercept and lo >= 0 and neutral > 0:
        k_bounds = (0.0, hi / cmax * 3)
    flds: list[tuple[str, type, Any]] = []
    bounds: list[tuple[float, float]] = []
    scale: list[float] = []
    if intercept:
        flds.append(("a", float, neutral))
        bounds.append((lo, hi))
        scale.append(sc)
    k0 = 0.0 if intercept else float(np.clip(neutral / (cmax / 2), *k_bounds))
    flds.append(("k", float, k0))
    bounds.append(k_bounds)
    scale.append(sc / cmax)
    hf, hb, hs = _held_fields(base, param)
    flds, bounds, scale = flds + hf, bounds + hb, scale + hs
    ns = {
        "name": base.name,
        "phase": base.phase,
        "bounds": tuple(bounds),
        "scale": tuple(scale),
        "hangs_on": covariate,
        "law": law_text(base, covariate, intercept, param),
        "plausible": None,
        "law_base": base,
        "law_param": param,
        "covariate": covariate,
        "intercept": intercept,
        "per_throw": _per_throw,
        "ee": ee,
    }
    cls_name = f"{base.__name__}_{'lin' if intercept else 'prop'}_{covariate}"
    cls_name += f"_{param}" if len(base.bounds) > 1 else ""
    cls = make_dataclass(cls_name, flds, bases=(Effect,), frozen=True, namespace=ns)
    for nm in ("name", "phase", "bounds", "scale", "hangs_on", "law", "plausible", "ee"):
        cls.__annotations__[nm] = ClassVar
    cls.__module__ = __name__
    if ee is None:
        _CACHE[key] = cls
    return cls


def _object_keys(batch: ThrowBatch) -> list[tuple[float, ...]]:
    """An object's key from its logged shape, mass and extents (a batch has no ids)."""
    a = np.c_[batch.shape, batch.mass * 1e6, batch.size * 1e6]
    r = np.round(np.asarray(a, float))
    return [tuple(float(x) for x in r[i]) for i in range(r.shape[0])]


def _per_object_throw(self: Any, batch: ThrowBatch, permutation: np.ndarray | None = None
                      ) -> Effect:  # fmt: skip
    base: type[Effect] = self.law_base
    vals = np.array([getattr(self, f"o{i}") for i in range(len(self.object_ids))], float)
    j = np.array([self.object_index.get(k, -1) for k in _object_keys(batch)])
    if permutation is not None:
        j = j[permutation]
    v = np.where(j >= 0, vals[np.clip(j, 0, None)], vals.mean())
    return _held(self, base, object.__new__(base), v)


def per_object_class(base: type[Effect], prob: GapProblem, param: str | None = None
                     ) -> type[Effect]:  # fmt: skip
    """The form of `base` with one value of `param` (by default its first of
    `law_params`) per object of the log (fields `o0`, `o1`, ... in the order of
    `object_ids`, then the base's other parameters, common); its law text is
    `p = a_object`."""
    param = _param(base, param)
    keys = _object_keys(prob.batch)
    oid = prob.table.text("object_id")
    index: dict[tuple[float, ...], int] = {}
    ids: list[str] = []
    for k, o in zip(keys, oid, strict=True):
        if k not in index:
            index[k] = len(ids)
            ids.append(str(o))
    i = base.param_names().index(param)
    neutral = float(base.neutral().vector()[i])
    hf, hb, hs = _held_fields(base, param)
    flds = [(f"o{j}", float, neutral) for j in range(len(ids))] + hf
    ns = {
        "name": base.name, "phase": base.phase,
        "bounds": (base.bounds[i],) * len(ids) + tuple(hb),
        "scale": (base.scale[i],) * len(ids) + tuple(hs), "hangs_on": "object_id",
        "law": f"{param} = a_object", "plausible": None, "law_base": base, "law_param": param,
        "covariate": "object_id", "intercept": False, "object_index": index,
        "object_ids": tuple(ids), "per_throw": _per_object_throw,
    }  # fmt: skip
    cls = make_dataclass(f"{base.__name__}_per_object", flds, bases=(Effect,), frozen=True,
                         namespace=ns)  # fmt: skip
    for nm in ("name", "phase", "bounds", "scale", "hangs_on", "law", "plausible"):
        cls.__annotations__[nm] = ClassVar
    cls.__module__ = __name__
    return cls


def shrunk(values: np.ndarray, ci: np.ndarray | None) -> tuple[np.ndarray, float, float]:
    """Per-object values shrunk toward their common value (empirical Bayes: each moves
    toward the precision-weighted mean by se² / (se² + τ²), τ² the spread the values
    have beyond their standard errors). Returns (shrunk values, common value, τ)."""
    v = np.asarray(values, float)
    se = (np.abs(ci[:, 1] - ci[:, 0]) / (2 * 1.96)) if ci is not None else np.zeros_like(v)
    se = np.maximum(se, 1e-12)
    w = 1 / se**2
    mean = float(np.sum(w * v) / np.sum(w))
    tau2 = max(float(np.var(v, ddof=1) - np.mean(se**2)) if v.size > 1 else 0.0, 0.0)
    b = tau2 / (tau2 + se**2)
    return mean + b * (v - mean), mean, float(np.sqrt(tau2))


def law_forms(base: type[Effect], batch: ThrowBatch | None = None,
              param: str | None = None) -> list[type[Effect]]:  # fmt: skip
    """Every covariate form of an effect's law parameter `param` (proportional and
    linear); with a batch, only those of covariates that take at least MIN_LEVELS values
    in it."""
    covs = [c for c in COVARIATES if batch is None or levels(batch, c) >= MIN_LEVELS]
    return [law_class(base, c, i, param) for c in covs for i in (False, True)]


def distinct(x: Any) -> int:
    """How many distinct values (to 1e-9 of their unit) `x` holds."""
    return int(np.unique(np.round(np.asarray(x, float), 9)).size)


def levels(batch: ThrowBatch, covariate: str) -> int:
    """How many distinct values (to 1e-9 of its unit) a covariate takes in a batch."""
    read, _ = COVARIATES[covariate]
    return distinct(read(batch))


def _warm(cls: type[Effect], p: float, cov_mean: float, held: dict[str, float]) -> np.ndarray:
    """A form's scaled start from the constant's fitted value p of its law parameter and
    the member's other parameters' values (held)."""
    sc = np.asarray(cls.scale, float)
    own = [p, 0.0] if getattr(cls, "intercept", False) else [p / max(cov_mean, 1e-9)]
    return np.array(own + list(held.values())) / sc


def law_range(eff: Effect, batch: ThrowBatch) -> tuple[float, float]:
    """The smallest and largest value a law's parameter takes over a batch's throws, as
    the law gives it (before the base effect's bounds clip it)."""
    if getattr(type(eff), "covariate", None) == "object_id":
        p: str = eff.law_param  # type: ignore[attr-defined]
        v = np.asarray(getattr(eff.per_throw(batch), p), dtype=float)
    else:
        a = eff.a if eff.intercept else 0.0  # type: ignore[attr-defined]
        v = a + eff.k * covariate_values(eff, batch)  # type: ignore[attr-defined]
    return float(np.min(v)), float(np.max(v))


def law_stretched(eff: Effect, batch: ThrowBatch) -> bool:
    """Whether a law gives any logged throw a value no real cell has: outside its base
    effect's plausible range, or within BOUND_TOL of a bound (`cell.gap.select`'s rule
    for a constant, applied throw by throw: a law that runs out of its range is one
    stretched to mimic something else)."""
    from cell.gap.select import BOUND_TOL

    base: type[Effect] = eff.law_base  # type: ignore[attr-defined]
    i = base.param_names().index(eff.law_param)  # type: ignore[attr-defined]
    (blo, bhi), tol = base.bounds[i], BOUND_TOL * (base.bounds[i][1] - base.bounds[i][0])
    plo, phi = (base.plausible or base.bounds)[i]
    lo, hi = law_range(eff, batch)
    return bool(lo < max(plo, blo + tol) or hi > min(phi, bhi - tol))


def _constant_member(cls: type[Effect]) -> type[Effect] | None:
    """The family member (`cell.model.effects.FAMILIES`) an effect's form is a law of: the
    class itself for a member (a bounce's friction or rolling law), its `law_base` for a
    covariate or per-object form."""
    from cell.model.effects import FAMILIES

    if cls in FAMILIES.get(cls.name, ()):
        return cls
    return getattr(cls, "law_base", None)


def objects_out(prob: GapProblem) -> GapProblem | None:
    """The problem scored with whole objects held out: its leave-objects-out folds (three
    or more objects), or each of two objects predicted from the other's throws; None for
    a log of one object."""
    objs = np.unique(prob.groups)
    if objs.size < 2:
        return None
    folds = prob.folds.get("object") or [
        (np.flatnonzero(prob.groups != o), np.flatnonzero(prob.groups == o)) for o in objs
    ]
    return replace(prob, folds={"object": folds})


def choose_law(
    prob: GapProblem,
    score: Score,
    tick: Any = None,
) -> tuple[Score, dict[str, dict[str, float]]]:
    """The law of each effect of a scored set chosen among its forms.

    Every effect of LAW_BASES in the set (at its constant form) is refitted with each
    covariate form of each of its `law_params` (a one-parameter member's one parameter;
    the drop law's 1/μ, its depth kept common; the others kept at their form,
    warm-started from the set's solution) and scored held-out; a form replaces the
    constant when its held-out RMSE, raised by TERM_PENALTY per term beyond the member's
    own, is the lowest, its cut over the constant
    has a bootstrap interval above zero, and it keeps every logged throw's value within
    the effect's plausible range and off its bounds (`law_stretched`); a covariate form
    (not the per-object one) is refused where, on a log of two or more objects, it
    predicts whole objects held out (`objects_out`) worse than the constant with a
    bootstrap interval below zero. Each form's RMSE with objects held out, where scored,
    is under `"<law>, objects held out"` (the constant's under `"constant, objects held
    out"`).

    Returns:
        (the set's score with the chosen forms; per effect, each form's held-out RMSE [m]).
    """
    from cell.gap.fit import score_set
    from cell.gap.law_speed import MODEL_FORMS
    from cell.gap.stats import bootstrap_cut
    from cell.model.flight_batch import together

    tick = tick or (lambda s: None)
    held = objects_out(prob)
    best = score
    tried: dict[str, dict[str, float]] = {}
    for j in range(len(score.full.effects)):
        eff = best.full.effects[j]
        base = _constant_member(type(eff))
        if eff.name not in LAW_BASES or base is None or not law_params(base):
            continue  # a member no law may be given keeps its form
        classes = [type(e) for e in best.full.effects]
        sizes = [len(c.bounds) for c in classes]
        at = int(np.sum(sizes[:j]))
        if type(eff) is not base:
            # a form chosen before a partner joined: start again from the constant
            on = eff.per_throw(prob.batch)
            own = np.array([float(np.mean(getattr(on, nm))) for nm in base.param_names()])
            own = own / np.asarray(base.scale, float)
            warm = np.r_[best.full.x[:at], own, best.full.x[at + sizes[j] :]]
            tick(f"{eff.name} (constant)")
            best = score_set(prob, classes[:j] + [base] + classes[j + 1 :], warm=warm)
            eff = best.full.effects[j]
            classes = [type(e) for e in best.full.effects]
        const, nb = eff.params(), len(base.bounds)
        rows = {"constant": best.heldout_rmse_m}
        const_held: Score | None = None
        pick, pick_val = best, best.heldout_rmse_m
        n_obj = len(set(_object_keys(prob.batch)))
        forms: list[type[Effect]] = []
        for param in law_params(base):
            forms += law_forms(base, prob.batch, param)
            forms += [
                law_class(base, c, False, param, prob.ee) for c in MODEL_FORMS.get(base.name, ())
            ]
            if 2 <= n_obj <= MAX_OBJECTS:
                forms.append(per_object_class(base, prob, param))
        fits = []
        for form in forms:
            p = const[form.law_param]  # type: ignore[attr-defined]
            common = {k: v for k, v in const.items() if k != form.law_param}  # type: ignore[attr-defined]
            if form.covariate == "object_id":  # type: ignore[attr-defined]
                own = np.r_[np.full(len(form.object_ids), p), list(common.values())]  # type: ignore[attr-defined]
                own = own / np.asarray(form.scale, float)
            else:
                cov = covariate_values(form, prob.batch)
                own = _warm(form, p, float(np.mean(cov)), common)
            warm = np.r_[best.full.x[:at], own, best.full.x[at + nb :]]
            tick(f"{eff.name} ({form.law})")
            cls_j = classes[:j] + [form] + classes[j + 1 :]
            fits.append(partial(score_set, prob, cls_j, warm=warm))
        # the forms' fits side by side (`cell.model.flight_batch`); the choice in order
        for form, sc in zip(forms, together(fits), strict=True):
            cls_j = classes[:j] + [form] + classes[j + 1 :]
            rows[form.law] = sc.heldout_rmse_m
            # the extra terms over the member's own parameters
            val = sc.heldout_rmse_m * (1.0 + TERM_PENALTY * (len(form.bounds) - nb))
            if val >= pick_val or law_stretched(sc.full.effects[j], prob.batch):
                continue
            _, lo, _ = bootstrap_cut(best.heldout, sc.heldout, seed=prob.seed + 3)
            refuted = False
            if lo > 0 and held is not None and form.covariate != "object_id":  # type: ignore[attr-defined]
                # a law in a throw's quantity holds whatever the object: refuted where
                # it predicts whole objects held out worse than the constant
                if const_held is None:
                    const_held = score_set(held, classes, warm=best.full.x)
                    rows[f"constant, {OBJECTS_OUT}"] = const_held.heldout_rmse_m
                sc_held = score_set(held, cls_j, warm=sc.full.x)
                rows[f"{form.law}, {OBJECTS_OUT}"] = sc_held.heldout_rmse_m
                _, _, hi = bootstrap_cut(const_held.heldout, sc_held.heldout, seed=prob.seed + 7)
                refuted = hi < 0
            if lo > 0 and not refuted:
                pick, pick_val = sc, val
        best = pick
        tried[eff.name] = rows
    return best, tried
