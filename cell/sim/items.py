"""Catalogue items as PyBullet bodies.

Primitives become PyBullet primitives (a cylinder's axis and a box's size_z
along the body's z); a mesh object loads its OBJ file from pybullet_data with
the catalogue's scale, shifted so that the body origin is the centre of the
mesh's box (where the catalogue puts the centre of mass). Mass and inertia
come from the catalogue (a mesh is a solid box of its extents), not from
PyBullet's own estimate.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cell.catalogue import catalogue, get_object, mesh_path
from cell.errors import InvalidInput
from cell.model.objects import ObjectParams

__all__ = ["Item", "resolve_object", "spawn_item", "ITEM_FRICTION"]

ITEM_FRICTION = 0.7  # Coulomb friction of items (printed plastic)
_COLOURS = {
    "cube": (0.85, 0.2, 0.2, 1),
    "cuboid": (0.9, 0.6, 0.1, 1),
    "cylinder": (0.2, 0.65, 0.3, 1),
    "sphere": (0.55, 0.3, 0.75, 1),
    "mesh": (0.9, 0.85, 0.3, 1),
}


@dataclass(frozen=True)
class Item:
    """An item in the scene.

    Attributes:
        body: PyBullet body id.
        obj: its object parameters η_o.
        drag_c: ½ ρ C_d A [kg/m] for the drag law.
    """

    body: int
    obj: ObjectParams
    drag_c: float


def resolve_object(
    what: str | ObjectParams,
) -> tuple[ObjectParams, tuple[float, float, float]]:
    """The object parameters and mesh scale for a catalogue id or an ObjectParams.

    Raises:
        InvalidInput: an unknown catalogue id, or a mesh object without a mesh file.
    """
    if isinstance(what, str):
        entry = catalogue().get(what)
        if entry is None:
            get_object(what)  # raises InvalidInput listing the valid ids
            raise InvalidInput(f"unknown object id {what!r}")  # pragma: no cover
        return entry.params, entry.mesh_scale
    obj = what
    if obj.shape == "mesh":
        if not obj.mesh:
            raise InvalidInput(f"object {obj.name or '(ad hoc)'}: shape mesh needs a mesh file")
        entry = catalogue().get(obj.name)
        if entry is not None and entry.params.mesh == obj.mesh:
            return obj, entry.mesh_scale
        raise InvalidInput(
            f"object {obj.name or '(ad hoc)'}: a mesh object must be a catalogue entry "
            "(its scale is defined there)"
        )
    return obj, (1.0, 1.0, 1.0)


@functools.lru_cache(maxsize=64)
def _mesh_centre(mesh: str, scale: tuple[float, float, float]) -> tuple[float, float, float]:
    """Centre of the scaled mesh's box in the OBJ's own frame [m]."""
    verts = []
    with open(mesh_path(mesh)) as fh:
        for line in fh:
            if line.startswith("v "):
                verts.append([float(v) for v in line.split()[1:4]])
    v = np.asarray(verts) * np.asarray(scale)
    c = (v.max(axis=0) + v.min(axis=0)) / 2
    return (float(c[0]), float(c[1]), float(c[2]))


def spawn_item(
    client: Any,
    what: str | ObjectParams,
    position: Sequence[float],
    orientation: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
) -> Item:
    """Create an item body.

    Args:
        client: a pybullet BulletClient.
        what: a catalogue id or object parameters.
        position: centre of mass [m, W].
        orientation: quaternion (x, y, z, w) of the object frame in W.

    Returns:
        The item.
    """
    from cell.sim.drag import drag_coefficient_kg_per_m

    obj, scale = resolve_object(what)
    sx, sy, sz = obj.size
    rgba = list(_COLOURS[obj.shape])
    if obj.shape in ("cube", "cuboid"):
        col = client.createCollisionShape(client.GEOM_BOX, halfExtents=[sx / 2, sy / 2, sz / 2])
        vis = client.createVisualShape(
            client.GEOM_BOX, halfExtents=[sx / 2, sy / 2, sz / 2], rgbaColor=rgba
        )
    elif obj.shape == "cylinder":
        col = client.createCollisionShape(client.GEOM_CYLINDER, radius=sx / 2, height=sz)
        vis = client.createVisualShape(
            client.GEOM_CYLINDER, radius=sx / 2, length=sz, rgbaColor=rgba
        )
    elif obj.shape == "sphere":
        col = client.createCollisionShape(client.GEOM_SPHERE, radius=sx / 2)
        vis = client.createVisualShape(client.GEOM_SPHERE, radius=sx / 2, rgbaColor=rgba)
    else:
        path = str(mesh_path(obj.mesh))
        c = _mesh_centre(obj.mesh, scale)
        shift = [-c[0], -c[1], -c[2]]
        col = client.createCollisionShape(
            client.GEOM_MESH, fileName=path, meshScale=list(scale), collisionFramePosition=shift
        )
        vis = client.createVisualShape(
            client.GEOM_MESH,
            fileName=path,
            meshScale=list(scale),
            visualFramePosition=shift,
            rgbaColor=rgba,
        )
    body = client.createMultiBody(
        baseMass=obj.mass,
        baseCollisionShapeIndex=col,
        baseVisualShapeIndex=vis,
        basePosition=list(position),
        baseOrientation=list(orientation),
    )
    client.changeDynamics(
        body,
        -1,
        localInertiaDiagonal=[float(i) for i in obj.inertia],
        lateralFriction=ITEM_FRICTION,
        rollingFriction=0.0005,
        spinningFriction=0.0005,
        restitution=0.2,
        linearDamping=0.0,
        angularDamping=0.0,
    )
    return Item(body=int(body), obj=obj, drag_c=drag_coefficient_kg_per_m(obj))
