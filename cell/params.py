"""Parameter files: the end-effector's η_ee, identified objects' η_o, and
switched-on model effects, as YAML.

    end_effector: {Ke1: 114.6, ...}      # any subset; the rest the reference values,
                                          # each named in a warning on stderr
    objects:                              # optional identified η_o by object id
      cube50: {shape: cube, mass_kg: 0.06, size_m: [0.05, 0.05, 0.05]}
    effects: {band_mass: {mass_kg: 0.01}} # optional (see cell.model.effects)
    mass_rule: {kappa: 0.143, band_mass_kg: 0.014, width_exponent: -0.08}
                                          # optional: m_eff = κ √(m + m_b) (a / 0.05 m)^β
    note: free text on how the file was made
    validation:                           # optional: the model's accuracy on held-out throws
      throws: 896                         # (`cell calibrate --validate`)
      seed: 1
      objects: {cube30: {heldout_rmse_m: 0.036, n: 64}, ...}

The validation section is what the identified model still misses on throws it was not
fitted to (RMS 2-D landing miss per object, no tracker scatter): the part of a campaign's
noise floor that repeats of a configuration cannot see (`cell.gap.noise`).

The mass rule (fitted by `cell calibrate`, see cell.workflows.calibrate) gives an
object the file does not list (an ad-hoc item of a job, a catalogue object
outside the campaign) the effective mass the identified objects follow, so
every item is planned with the same model of the scene.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import yaml

from cell.errors import InvalidInput, InvalidParameter, plural
from cell.model.objects import ObjectParams, denser_than_any_solid, lighter_than_air
from cell.model.params import EndEffectorParams
from cell.outfile import write_whole
from cell.yamlsafe import read_yaml_text, safe_load

__all__ = [
    "ModelParams",
    "Validation",
    "load_params",
    "save_params",
    "scene_params_path",
    "WIDTH_REF_M",
]

WIDTH_REF_M = 0.05  # [m] the grip width the mass rule's κ refers to


@dataclass(frozen=True)
class Validation:
    """The identified model's accuracy on held-out throws (never fitted to).

    Attributes:
        objects: object id -> (RMS 2-D landing miss of the model on its held-out
            throws [m], number of those throws).
        throws: held-out throws in all.
        seed: the seed of their draw (`cell calibrate --validate --seed`).
    """

    objects: dict[str, tuple[float, int]]
    throws: int
    seed: int

    def misfit_m(self, object_ids: list[str]) -> list[float]:
        """Each throw's object's held-out misfit [m]; NaN for an object not validated."""
        return [self.objects[o][0] if o in self.objects else float("nan") for o in object_ids]

    def as_dict(self) -> dict[str, Any]:
        """The section as the parameter file (and `cell calibrate --json`) writes it."""
        return {
            "throws": int(self.throws),
            "seed": int(self.seed),
            "objects": {
                k: {"heldout_rmse_m": float(x), "n": int(m)}
                for k, (x, m) in sorted(self.objects.items())
            },
        }


@dataclass(frozen=True)
class ModelParams:
    """Everything a parameter file holds.

    Attributes:
        ee: end-effector parameters.
        objects: identified object parameters by object id.
        effects: effect name -> its parameters (empty = nominal model).
        note: how the file was made.
        mass_rule: (κ [kg^½], m_b [kg], β) of m_eff = κ √(m + m_b) (a / a_ref)^β for
            objects not in `objects` (a their grip width, a_ref = WIDTH_REF_M), or None
            (they keep their own mass). A file without β (width_exponent) has β = 0.
        validation: the model's accuracy on held-out throws, or None.
    """

    ee: EndEffectorParams = field(default_factory=EndEffectorParams)
    objects: dict[str, ObjectParams] = field(default_factory=dict)
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    note: str = ""
    mass_rule: tuple[float, ...] | None = None
    validation: Validation | None = None

    def model_object(self, obj: ObjectParams) -> ObjectParams:
        """The η_o the planner uses for `obj`: the identified one when the file has
        it, else `obj` with the mass rule's effective mass (its own extents). An object
        gripped a quarter turn round (`ObjectParams.turned`: its catalogue sizes x and y
        swapped) is modelled so: the identified one turned the same way (cuboid_a,
        identified as 30 x 50 mm, is thrown across 50 mm)."""
        if obj.name and obj.name in self.objects:
            known = self.objects[obj.name]
            if _turned_from_catalogue(obj):
                sx, sy, sz = known.size
                return replace(known, size=(sy, sx, sz))
            return known
        if self.mass_rule is None:
            return obj
        kappa, m_b = self.mass_rule[0], self.mass_rule[1]
        beta = self.mass_rule[2] if len(self.mass_rule) > 2 else 0.0
        m_eff = kappa * (obj.mass + m_b) ** 0.5 * (obj.width / WIDTH_REF_M) ** beta
        return replace(obj, mass=float(m_eff))


def _turned_from_catalogue(obj: ObjectParams) -> bool:
    """Is `obj` its catalogue entry gripped a quarter turn round (`ObjectParams.turned`)?"""
    from cell.catalogue import catalogue

    entry = catalogue().get(obj.name)
    if entry is None:
        return False
    sx, sy, _ = entry.params.size
    return sx != sy and obj.size == entry.params.turned().size


MAX_FILE_MASS_KG = 1000.0  # [kg] an object of a parameter file: beyond is a typo (1e300)
MAX_FILE_SIZE_M = 10.0  # [m]
OBJECT_KEYS = ("shape", "mass_kg", "size_m")  # an object of a parameter file, as saved


def scene_params_path() -> str | None:
    """The scene's calibrated parameter file (robots/cell_scene/ee_params.yaml), if present."""
    from cell.robot.paths import robots_dir

    p = robots_dir() / "cell_scene" / "ee_params.yaml"
    return str(p) if p.is_file() else None


def load_params(path: str | Path | None) -> ModelParams:
    """Read a parameter file; None gives the reference defaults.

    Raises:
        InvalidInput: unreadable file, unknown top-level key, bad value (naming the field).
    """
    if path is None:
        return ModelParams()
    p = str(path)
    raw = safe_load(read_yaml_text(p, "parameter file"), p) or {}
    if not isinstance(raw, dict):
        raise InvalidInput(f"{p}: must be a mapping with keys end_effector, objects, effects, note")
    valid = {"end_effector", "objects", "effects", "mass_rule", "note", "validation"}
    unknown = sorted(set(raw) - valid)
    if unknown:
        raise InvalidInput(
            f"{p}: {plural(len(unknown), 'unknown key')} {unknown}; valid: {sorted(valid)}"
        )
    for key in ("end_effector", "objects", "effects"):
        if not isinstance(raw.get(key) or {}, dict):
            raise InvalidInput(
                f"{p}: {key}: {raw[key]!r} must be a mapping "
                + ("of parameter name to number" if key == "end_effector" else "by name")
            )
    given = raw.get("end_effector") or {}
    ee = EndEffectorParams.from_dict(given, where=f"{p}: end_effector")
    objects: dict[str, ObjectParams] = {}
    for oid, spec in (raw.get("objects") or {}).items():
        try:
            if not isinstance(spec, dict):
                raise TypeError(f"{spec!r} is not a mapping")
            extra = sorted(str(k) for k in set(spec) - set(OBJECT_KEYS))
            if extra:
                raise ValueError(
                    f"{plural(len(extra), 'unknown key')} {extra}; valid: {', '.join(OBJECT_KEYS)}"
                )
            objects[str(oid)] = ObjectParams(
                shape=str(spec["shape"]),
                mass=float(spec["mass_kg"]),
                size=tuple(float(s) for s in spec["size_m"]),  # type: ignore[arg-type]
                name=str(oid),
            )
            o = objects[str(oid)]
            if o.mass > MAX_FILE_MASS_KG or max(o.size) > MAX_FILE_SIZE_M:
                raise ValueError(
                    f"mass {o.mass:g} kg, size {max(o.size):g} m: an absurd magnitude; valid are "
                    f"masses up to {MAX_FILE_MASS_KG:g} kg and extents up to {MAX_FILE_SIZE_M:g} m"
                )
            impossible = denser_than_any_solid(o.mass, o.size) or lighter_than_air(o.mass, o.size)
            if impossible:
                raise ValueError(f"mass_kg: {impossible}")
        except (KeyError, TypeError, ValueError, InvalidParameter) as exc:
            raise InvalidInput(
                f"{p}: objects.{oid}: {exc}; each object needs shape, mass_kg, size_m [3 numbers]"
            ) from None
    effects = raw.get("effects") or {}
    if not isinstance(effects, dict):
        raise InvalidInput(f"{p}: effects must be a mapping of effect name to parameters")
    from cell.model.effects import effects_from_mapping

    try:
        effects_from_mapping(effects)  # validate names, parameters and ranges now
    except InvalidParameter as exc:
        raise InvalidInput(f"{p}: {exc}") from None
    out = ModelParams(
        ee=ee,
        objects=objects,
        effects=effects,
        note=str(raw.get("note", "")),
        mass_rule=_mass_rule(raw.get("mass_rule"), p),
        validation=_validation(raw.get("validation"), p),
    )
    missing = [f.name for f in fields(EndEffectorParams) if f.name not in given]
    if missing:  # said once the file is read whole: a refused file is not warned of too
        _warn_once(p, defaulted_warning(p, missing, ee))
    return out


# the unit of each end-effector parameter, for the messages
_EE_UNITS = {"phi": " rad", "Ke3": " N/m³", "Ke2": " N/m²", "Ke1": " N/m", "C": " N", "dt": " s"}
_WARNED: set[tuple[str, str]] = set()


def defaulted_warning(path: str, missing: list[str], ee: EndEffectorParams) -> str:
    """The warning for a parameter file whose end_effector leaves out the keys `missing`:
    each key and the reference value it takes (the thesis' values, not the scene's)."""
    taken = ", ".join(f"{k} = {getattr(ee, k):g}{_EE_UNITS.get(k, ' m')}" for k in missing)
    n_all = len(fields(EndEffectorParams))
    return (
        f"{path}: end_effector gives {n_all - len(missing)} of its {n_all} parameters; "
        f"{plural(len(missing), 'reference value')} taken (the thesis' end-effector, not the "
        f"scene's calibrated robots/cell_scene/ee_params.yaml): {taken}"
    )


def _warn_once(path: str, message: str) -> None:
    """Print `message` as a warning on standard error, once per file and message."""
    if (path, message) not in _WARNED:
        _WARNED.add((path, message))
        print(f"cell: warning: {message}", file=sys.stderr)


MAX_VALIDATION_M = 1.0  # [m] a held-out RMS miss beyond is no calibrated model (or a typo)
MAX_VALIDATION_THROWS = 1_000_000


def _count(node: Any, where: str, lo: int) -> int:
    """An integer count (not a bool, not a float) of at least lo, named in the error."""
    if (
        isinstance(node, bool)
        or not isinstance(node, int)
        or not lo <= node <= MAX_VALIDATION_THROWS
    ):
        raise InvalidInput(f"{where}: {node!r} must be an integer {lo}–{MAX_VALIDATION_THROWS}")
    return int(node)


def _validation(node: Any, path: str) -> Validation | None:
    """The file's validation section, checked field by field; None when absent."""
    if node is None:
        return None
    form = "{throws: N, seed: S, objects: {ID: {heldout_rmse_m: X, n: K}, ...}}"
    keys = {"throws", "seed", "objects"}
    if not isinstance(node, dict) or set(node) != keys:
        raise InvalidInput(f"{path}: validation must be {form}; got {node!r}")
    throws = _count(node["throws"], f"{path}: validation.throws", 1)
    seed = node["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int):
        raise InvalidInput(f"{path}: validation.seed: {seed!r} must be an integer")
    objs = node["objects"]
    if not isinstance(objs, dict) or not objs:
        raise InvalidInput(f"{path}: validation.objects: {objs!r} must be a non-empty mapping")
    out: dict[str, tuple[float, int]] = {}
    for oid, spec in objs.items():
        where = f"{path}: validation.objects.{oid}"
        if not isinstance(spec, dict) or set(spec) != {"heldout_rmse_m", "n"}:
            raise InvalidInput(f"{where}: {spec!r} must be {{heldout_rmse_m: X, n: K}}")
        x = spec["heldout_rmse_m"]
        if isinstance(x, bool) or not isinstance(x, (int, float)):
            raise InvalidInput(f"{where}.heldout_rmse_m: {x!r} must be a number")
        if not (math.isfinite(x) and 0.0 <= x <= MAX_VALIDATION_M):
            raise InvalidInput(
                f"{where}.heldout_rmse_m: {x!r} must be finite, 0–{MAX_VALIDATION_M:g} m"
            )
        out[str(oid)] = (float(x), _count(spec["n"], f"{where}.n", 1))
    total = sum(k for _, k in out.values())
    if total > throws:
        raise InvalidInput(
            f"{path}: validation.objects: {total} throws in all, more than validation.throws "
            f"{throws}"
        )
    return Validation(objects=out, throws=throws, seed=int(seed))


def _mass_rule(node: Any, path: str) -> tuple[float, float, float] | None:
    """The file's mass rule (κ, m_b, β), validated; None when absent (β = 0 when the file
    has no width_exponent, as files written before it had)."""
    if node is None:
        return None
    msg = (
        f"{path}: mass_rule must be {{kappa: K, band_mass_kg: M[, width_exponent: B]}} with "
        "0 < K <= 10 kg^0.5, 0 <= M <= 1 kg and |B| <= 1"
    )
    keys = {"kappa", "band_mass_kg"}
    if not isinstance(node, dict) or not keys <= set(node) <= keys | {"width_exponent"}:
        raise InvalidInput(f"{msg}; got {node!r}")
    try:
        kappa, m_b = float(node["kappa"]), float(node["band_mass_kg"])
        beta = float(node.get("width_exponent", 0.0))
    except (TypeError, ValueError):
        raise InvalidInput(f"{msg}; got {node!r}") from None
    if not (0.0 < kappa <= 10.0 and 0.0 <= m_b <= 1.0 and abs(beta) <= 1.0):
        raise InvalidInput(f"{msg}; got kappa={kappa}, band_mass_kg={m_b}, width_exponent={beta}")
    return kappa, m_b, beta


def save_params(params: ModelParams, path: str | Path) -> None:
    """Write a parameter file (atomically)."""
    # every end-effector key, L_e at 0 too (`as_dict` leaves it out when off): a file
    # `cell identify`, `cell synth --save-world` or `cell calibrate` writes gives them all,
    # and reading it warns of no reference value taken
    ee = {**params.ee.as_dict(), "L_e": float(params.ee.L_e)}
    doc: dict[str, Any] = {"end_effector": ee}
    if params.objects:
        doc["objects"] = {
            k: {"shape": o.shape, "mass_kg": float(o.mass), "size_m": [float(s) for s in o.size]}
            for k, o in sorted(params.objects.items())
        }
    if params.effects:
        doc["effects"] = params.effects
    if params.mass_rule is not None:
        doc["mass_rule"] = {
            "kappa": float(params.mass_rule[0]),
            "band_mass_kg": float(params.mass_rule[1]),
        }
        if len(params.mass_rule) > 2 and params.mass_rule[2] != 0:
            doc["mass_rule"]["width_exponent"] = float(params.mass_rule[2])
    if params.note:
        doc["note"] = params.note
    if params.validation is not None:
        doc["validation"] = params.validation.as_dict()
    text = yaml.safe_dump(doc, sort_keys=False)
    write_whole(path, lambda p: p.write_text(text))
