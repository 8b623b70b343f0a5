"""Feature vectors for the residual ΔL_s: the object's parameters, the shape
descriptors of its composite grip cloud (`cloud.py`), its pose in the grip, and
the stroke the model plans.

The stroke feature is always the *model's* stroke for the landing in question:
in training, the inverse of the observed landing (`target.residual_targets`);
when planning, the planner's L_s. That is what is known at planning time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cell.errors import InvalidInput, LogFormatError
from cell.log.table import ThrowTable
from cell.model.band import band_angle, band_stretch
from cell.model.objects import SHAPES, ObjectParams, drag_area
from cell.model.params import EndEffectorParams
from cell.residual.cloud import DESCRIPTOR_NAMES, ObjectGeometry, read_obj_mesh, shape_descriptors

__all__ = [
    "FEATURE_NAMES",
    "GripPose",
    "geometry_of",
    "object_features",
    "feature_matrix",
    "table_geometries",
    "table_features",
]

OBJECT_NAMES = (
    "mass_kg",
    "size_x_m",
    "size_y_m",
    "size_z_m",
    "drag_area_m2",
    *(f"shape_{s}" for s in SHAPES),
)
THROW_NAMES = ("stroke_m", "band_stretch_m", "band_angle_rad", "elevation_rad", "grip_yaw_rad")
FEATURE_NAMES = (*OBJECT_NAMES, *DESCRIPTOR_NAMES, *THROW_NAMES)


@dataclass(frozen=True)
class GripPose:
    """How a throw holds its object.

    Attributes:
        stroke_m: the model's stroke L_s [m].
        elevation_rad: throw-axis elevation [rad].
        grip_yaw_rad: object rotation about the throw axis z_O in the grip [rad].
    """

    stroke_m: float
    elevation_rad: float = 0.0
    grip_yaw_rad: float = 0.0


def geometry_of(obj: ObjectParams, grip_yaw_rad: float = 0.0) -> ObjectGeometry:
    """The cloud geometry of an object: a catalogue mesh keeps its catalogue scale,
    any other mesh is scaled to the object's box extents.

    Raises:
        InvalidInput: a mesh object with no mesh file.
    """
    if obj.shape != "mesh":
        return ObjectGeometry(obj.shape, tuple(obj.size), grip_yaw=grip_yaw_rad)  # type: ignore[arg-type]
    from cell.catalogue import catalogue, mesh_path

    cat = catalogue()
    entry = cat.get(obj.name)
    if entry is not None and entry.params.mesh and (not obj.mesh or obj.mesh == entry.params.mesh):
        return ObjectGeometry("mesh", obj.size, entry.params.mesh, entry.mesh_scale, grip_yaw_rad)
    if not obj.mesh:
        raise InvalidInput(
            f"object {obj.name or '(ad hoc)'}: a mesh object needs its mesh file for the shape "
            "descriptors (a catalogue id or a mesh path)"
        )
    verts, _ = read_obj_mesh(mesh_path(obj.mesh))
    ext = np.ptp(verts, axis=0)
    if np.any(ext <= 0):
        raise InvalidInput(f"mesh {obj.mesh}: its vertices span no volume")
    scale = tuple(float(s) for s in np.asarray(obj.size) / ext)
    return ObjectGeometry("mesh", obj.size, obj.mesh, scale, grip_yaw_rad)  # type: ignore[arg-type]


def object_features(obj: ObjectParams, geom: ObjectGeometry | None = None) -> np.ndarray:
    """The per-object part of the feature vector (OBJECT_NAMES then DESCRIPTOR_NAMES)."""
    geom = geometry_of(obj) if geom is None else geom
    onehot = [1.0 if obj.shape == s else 0.0 for s in SHAPES]
    area = float(drag_area(np.array([obj.code]), np.array([obj.size]))[0])
    return np.concatenate([[obj.mass, *obj.size, area], onehot, shape_descriptors(geom)])


def feature_matrix(
    objects: list[ObjectParams],
    poses: list[GripPose],
    ee: EndEffectorParams,
    geometries: list[ObjectGeometry] | None = None,
) -> np.ndarray:
    """Feature vectors in the order of FEATURE_NAMES, shape (n, len(FEATURE_NAMES)).

    Args:
        objects: the object of each throw.
        poses: the grip pose and model stroke of each throw.
        ee: end-effector parameters (band stretch and angle at the stroke).
        geometries: the cloud geometry of each throw; from `geometry_of` when None.
    """
    if len(objects) != len(poses):
        raise InvalidInput(f"{len(objects)} objects but {len(poses)} grip poses")
    n = len(objects)
    if geometries is None:
        geometries = [geometry_of(o, p.grip_yaw_rad) for o, p in zip(objects, poses, strict=True)]
    cache: dict[tuple[ObjectParams, ObjectGeometry], np.ndarray] = {}
    rows = np.empty((n, len(OBJECT_NAMES) + len(DESCRIPTOR_NAMES)))
    for i, (o, g) in enumerate(zip(objects, geometries, strict=True)):
        key = (o, g)
        if key not in cache:
            cache[key] = object_features(o, g)
        rows[i] = cache[key]
    stroke = np.array([p.stroke_m for p in poses], float)
    width = np.array([o.size[0] for o in objects], float)
    throw = np.stack(
        [
            stroke,
            band_stretch(stroke, width, ee),
            band_angle(stroke, width, ee),
            np.array([p.elevation_rad for p in poses], float),
            np.array([p.grip_yaw_rad for p in poses], float),
        ],
        axis=-1,
    )
    return np.concatenate([rows, throw], axis=1)


def table_geometries(table: ThrowTable) -> tuple[list[ObjectParams], list[ObjectGeometry]]:
    """The object and cloud geometry of every row of a throw log.

    A mesh row uses the `mesh` column (a path relative to the log) when present,
    else the catalogue object of its object_id.

    Raises:
        LogFormatError: a mesh row with neither, naming the row.
    """
    from cell.catalogue import catalogue

    cat = catalogue()
    has_mesh = "mesh" in table.data
    has_yaw = "grip_yaw_rad" in table.data
    yaw = table.num("grip_yaw_rad") if has_yaw else np.zeros(len(table))
    base = Path(table.path).parent if table.path else Path(".")
    mass, shape, oid = table.num("mass_kg"), table.text("shape"), table.text("object_id")
    size = np.stack([table.num("size_x_m"), table.num("size_y_m"), table.num("size_z_m")], -1)
    objs: list[ObjectParams] = []
    geoms: list[ObjectGeometry] = []
    memo: dict[tuple, tuple[ObjectParams, ObjectGeometry]] = {}
    for i in range(len(table)):
        mesh = table.data["mesh"][i].strip() if has_mesh else ""
        key = (oid[i], shape[i], float(mass[i]), tuple(size[i]), mesh, float(yaw[i]))
        if key not in memo:
            if not math.isfinite(yaw[i]):
                raise LogFormatError(table.path, i + 1, "grip_yaw_rad", "is not a finite number")
            o = _row_object(oid[i], shape[i], float(mass[i]), size[i], mesh, base, cat)
            if o is None:
                raise LogFormatError(
                    table.path,
                    i + 1,
                    "mesh",
                    f"object {oid[i]!r} is a mesh but its mesh file {mesh!r} is neither next to "
                    "the log nor in pybullet_data, and the catalogue has no such mesh object; "
                    "the shape descriptors need its surface",
                )
            memo[key] = (o, geometry_of(o, float(yaw[i])))
        o, g = memo[key]
        objs.append(o)
        geoms.append(g)
    return objs, geoms


def _row_object(
    oid: str, shape: str, mass: float, size: np.ndarray, mesh: str, base: Path, cat: dict
) -> ObjectParams | None:
    """The object of a log row; for a mesh, where its surface comes from (None: nowhere).

    A mesh is looked for next to the log, then as the catalogue object of the same id
    (same mesh file or none named), then inside pybullet_data.
    """
    ext = tuple(float(s) for s in size)
    if shape != "mesh":
        return ObjectParams(shape=shape, mass=mass, size=ext)  # type: ignore[arg-type]
    entry = cat.get(oid)
    if mesh and not Path(mesh).is_absolute() and (base / mesh).is_file():
        return ObjectParams("mesh", mass, ext, mesh=str((base / mesh).resolve()))  # type: ignore[arg-type]
    if mesh and Path(mesh).is_file():
        return ObjectParams("mesh", mass, ext, mesh=mesh)  # type: ignore[arg-type]
    if (
        entry is not None
        and entry.params.mesh
        and (not mesh or Path(mesh).name == Path(entry.params.mesh).name)
    ):
        return ObjectParams("mesh", mass, ext, name=oid, mesh=entry.params.mesh)  # type: ignore[arg-type]
    if mesh:
        from cell.catalogue import mesh_path
        from cell.errors import CellError

        try:
            mesh_path(mesh)
        except CellError:
            return None
        return ObjectParams("mesh", mass, ext, mesh=mesh)  # type: ignore[arg-type]
    return None


def table_features(
    table: ThrowTable, model_stroke: np.ndarray, ee: EndEffectorParams
) -> np.ndarray:
    """Feature matrix of a throw log, with the model's strokes `model_stroke` [m] (n,)."""
    objs, geoms = table_geometries(table)
    yaw = table.num("grip_yaw_rad") if "grip_yaw_rad" in table.data else np.zeros(len(table))
    elev = table.num("elevation_rad")
    poses = [
        GripPose(float(s), float(e), float(y))
        for s, e, y in zip(np.asarray(model_stroke, float), elev, yaw, strict=True)
    ]
    return feature_matrix(objs, poses, ee, geoms)
