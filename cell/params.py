"""Parameter files: the end-effector's η_ee, identified objects' η_o, and
switched-on model effects, as YAML.

    end_effector: {Ke1: 114.6, ...}      # any subset; the rest are defaults
    objects:                              # optional identified η_o by object id
      cube50: {shape: cube, mass_kg: 0.06, size_m: [0.05, 0.05, 0.05]}
    effects: {band_mass: {mass_kg: 0.01}} # optional (see cell.model.effects)
    note: free text on how the file was made
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cell.errors import InvalidInput, InvalidParameter
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.yamlsafe import read_yaml_text, safe_load

__all__ = ["ModelParams", "load_params", "save_params"]


@dataclass(frozen=True)
class ModelParams:
    """Everything a parameter file holds.

    Attributes:
        ee: end-effector parameters.
        objects: identified object parameters by object id.
        effects: effect name -> its parameters (empty = nominal model).
        note: how the file was made.
    """

    ee: EndEffectorParams = field(default_factory=EndEffectorParams)
    objects: dict[str, ObjectParams] = field(default_factory=dict)
    effects: dict[str, dict[str, float]] = field(default_factory=dict)
    note: str = ""


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
    valid = {"end_effector", "objects", "effects", "note"}
    unknown = sorted(set(raw) - valid)
    if unknown:
        raise InvalidInput(f"{p}: unknown key(s) {unknown}; valid: {sorted(valid)}")
    for key in ("end_effector", "objects", "effects"):
        if not isinstance(raw.get(key) or {}, dict):
            raise InvalidInput(
                f"{p}: {key}: {raw[key]!r} must be a mapping "
                + ("of parameter name to number" if key == "end_effector" else "by name")
            )
    ee = EndEffectorParams.from_dict(raw.get("end_effector") or {}, where=f"{p}: end_effector")
    objects: dict[str, ObjectParams] = {}
    for oid, spec in (raw.get("objects") or {}).items():
        try:
            if not isinstance(spec, dict):
                raise TypeError(f"{spec!r} is not a mapping")
            objects[str(oid)] = ObjectParams(
                shape=str(spec["shape"]),
                mass=float(spec["mass_kg"]),
                size=tuple(float(s) for s in spec["size_m"]),  # type: ignore[arg-type]
                name=str(oid),
            )
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
    return ModelParams(ee=ee, objects=objects, effects=effects, note=str(raw.get("note", "")))


def save_params(params: ModelParams, path: str | Path) -> None:
    """Write a parameter file (atomically)."""
    doc: dict[str, Any] = {"end_effector": params.ee.as_dict()}
    if params.objects:
        doc["objects"] = {
            k: {"shape": o.shape, "mass_kg": float(o.mass), "size_m": [float(s) for s in o.size]}
            for k, o in sorted(params.objects.items())
        }
    if params.effects:
        doc["effects"] = params.effects
    if params.note:
        doc["note"] = params.note
    tmp = Path(str(path) + ".tmp")
    tmp.write_text(yaml.safe_dump(doc, sort_keys=False))
    tmp.replace(path)
