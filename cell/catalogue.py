"""The object catalogue: named objects with shape, mass and extents.

Primitives carry their extents; mesh objects name a mesh shipped with
pybullet_data and a scale, and their box extents are computed from the mesh's
vertices. The catalogue is a sorted registry of frozen `CatalogueEntry`s.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
import yaml

from cell.errors import InvalidInput, MissingDependency
from cell.model.objects import ObjectParams

__all__ = [
    "CatalogueEntry",
    "catalogue",
    "get_object",
    "mesh_path",
    "mesh_turn",
    "mesh_vertices",
    "pad_width_m",
]


@dataclass(frozen=True)
class CatalogueEntry:
    """One catalogue object.

    Attributes:
        params: the object's parameters η_o (extents in the object frame [m]).
        set: which group it belongs to (thesis14, fig33, unseen).
        mesh_scale: scale applied to the mesh's vertices (mesh objects only).
    """

    params: ObjectParams
    set: str
    mesh_scale: tuple[float, float, float] = (1.0, 1.0, 1.0)

    @property
    def name(self) -> str:
        """Catalogue id."""
        return self.params.name


def mesh_path(mesh: str) -> Path:
    """Absolute path of a mesh: absolute as given, else inside pybullet_data.

    Raises:
        MissingDependency: pybullet is not installed.
        InvalidInput: the file does not exist.
    """
    p = Path(mesh)
    if not p.is_absolute():
        try:
            import pybullet_data
        except ImportError:
            raise MissingDependency(
                "mesh objects need pybullet_data: pip install pybullet"
            ) from None
        p = Path(pybullet_data.getDataPath()) / mesh
    if not p.is_file():
        raise InvalidInput(f"mesh file {p} does not exist")
    return p


@functools.lru_cache(maxsize=64)
def mesh_vertices(mesh: str, scale: tuple[float, float, float]) -> np.ndarray:
    """Vertices of an OBJ mesh, scaled and centred on their box centre [m], shape (n, 3)."""
    verts = []
    with open(mesh_path(mesh)) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append([float(v) for v in line.split()[1:4]])
    if not verts:
        raise InvalidInput(f"mesh {mesh} has no vertices")
    v = np.asarray(verts) * np.asarray(scale)
    v = v - (v.max(axis=0) + v.min(axis=0)) / 2
    v.setflags(write=False)  # cached and shared by every caller in the process
    return v


def _entry(name: str, spec: dict, where: str) -> CatalogueEntry:
    valid = {"shape", "mass_kg", "size_m", "mesh", "mesh_scale", "set"}
    unknown = set(spec) - valid
    if unknown:
        raise InvalidInput(
            f"{where}: object {name}: unknown key(s) {sorted(unknown)}; valid: {sorted(valid)}"
        )
    mesh = str(spec.get("mesh", ""))
    scale = tuple(float(s) for s in spec.get("mesh_scale", (1.0, 1.0, 1.0)))
    if spec.get("shape") == "mesh" and "size_m" not in spec:
        ext = np.ptp(mesh_vertices(mesh, scale), axis=0)  # type: ignore[arg-type]
        size = tuple(round(float(e), 4) for e in ext)
    else:
        size = tuple(float(s) for s in spec.get("size_m", ()))
    params = ObjectParams(
        shape=str(spec.get("shape")),
        mass=float(spec.get("mass_kg", float("nan"))),
        size=size,  # type: ignore[arg-type]
        name=name,
        mesh=mesh,
    )
    return CatalogueEntry(params=params, set=str(spec.get("set", "")), mesh_scale=scale)  # type: ignore[arg-type]


@functools.lru_cache(maxsize=1)
def catalogue() -> dict[str, CatalogueEntry]:
    """The shipped catalogue, sorted by id."""
    text = resources.files("cell.data").joinpath("catalogue.yaml").read_text()
    raw = yaml.safe_load(text)["objects"]
    return {name: _entry(name, raw[name], "catalogue.yaml") for name in sorted(raw)}


def get_object(name: str) -> ObjectParams:
    """The catalogue object with this id.

    Raises:
        InvalidInput: an unknown id, listing the valid ones.
    """
    cat = catalogue()
    if name not in cat:
        raise InvalidInput(f"unknown object id {name!r}; the catalogue has: {', '.join(cat)}")
    return cat[name].params


def mesh_turn(obj: ObjectParams) -> tuple[ObjectParams, float]:
    """(the catalogue's object, the grip's turn [rad] about its vertical) of a mesh item
    as gripped: a mesh gripped a quarter turn round (`cell.arm.grip_side.turned`) has
    its catalogue sizes x and y swapped, and its vertices lie as the catalogue has them,
    so it is the catalogue's object turned π/2. Anything else: (obj, 0)."""
    entry = catalogue().get(obj.name or "")
    if obj.shape != "mesh" or entry is None or obj.mesh != entry.params.mesh:
        return obj, 0.0
    sx, sy, sz = entry.params.size
    if obj.size != entry.params.size and obj.size == (sy, sx, sz):
        return entry.params, math.pi / 2
    return obj, 0.0


def pad_width_m(obj: ObjectParams, pad_half_width_m: float | None = None) -> float:
    """The width [m] the pads close to on an object: its extent along x within the
    pads' strip |y| ≤ pad half width (default: the end-effector description's pads,
    cell.sim.mechanism). A box's or cylinder's is its size_x; a mesh's can be far less
    (a flat rock 48 mm wide is 16 mm thick where the pads meet it: the pads in the scene
    close to 19 mm on it). A mesh gripped a quarter turn round (`mesh_turn`): its extent
    along the catalogue's y within the strip |x| ≤ pad half width (that rock: 64 mm)."""
    entry = catalogue().get(obj.name or "")
    if obj.shape != "mesh" or entry is None or not obj.mesh:
        return obj.width
    if pad_half_width_m is None:
        from cell.sim.mechanism import DEFAULT_GEOMETRY

        pad_half_width_m = DEFAULT_GEOMETRY.pad_half_width_m
    v = mesh_vertices(obj.mesh, entry.mesh_scale)
    across, along = (1, 0) if mesh_turn(obj)[1] else (0, 1)
    strip = v[np.abs(v[:, along]) <= pad_half_width_m]
    return float(np.ptp(strip[:, across])) if len(strip) >= 3 else obj.width
