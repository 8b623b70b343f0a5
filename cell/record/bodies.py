"""What a PyBullet body looks like and where its links are, as plain data for a recording.

`body_visuals` reads a body's visual shapes (boxes, spheres, cylinders,
capsules, meshes) with their frames in the link frame; `link_poses` reads
where each link frame is in the world frame W now. A recording logs the
visuals once (static, under the link's entity) and the link poses over time.
Collada meshes (the Panda's visual `.dae`) are replaced by the description's
collision STL of the same name, which Rerun reads; a mesh Rerun cannot read
and that has no such twin is drawn as nothing (logged once at INFO level).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

__all__ = ["Visual", "body_visuals", "link_poses", "readable_mesh"]

log = logging.getLogger(__name__)

# PyBullet geometry types (pybullet.GEOM_*)
_SPHERE, _BOX, _CYLINDER, _MESH, _PLANE, _CAPSULE = 2, 3, 4, 5, 6, 7
_MESH_SUFFIXES = (".stl", ".obj", ".glb", ".gltf")


@dataclass(frozen=True)
class Visual:
    """One visual shape of one link.

    Attributes:
        link: PyBullet link index (-1: the base).
        kind: "box", "sphere", "cylinder", "capsule" or "mesh".
        size: box half extents [m]; sphere (r, r, r); cylinder and capsule
            (radius, radius, length/2) [m]; mesh: its scale per axis.
        mesh: the mesh file ("" for primitives).
        position: the shape's frame in the link frame [m].
        quat_xyzw: its orientation in the link frame.
        rgba: colour (0..255 each).
    """

    link: int
    kind: str
    size: tuple[float, float, float]
    mesh: str
    position: tuple[float, float, float]
    quat_xyzw: tuple[float, float, float, float]
    rgba: tuple[int, int, int, int]


def readable_mesh(path: str) -> str:
    """A mesh file Rerun reads for `path`: itself, or the collision STL twin of a `.dae`; ""."""
    p = Path(path)
    if p.suffix.lower() in _MESH_SUFFIXES and p.is_file():
        return str(p)
    twin = p.parent.parent / "collision" / (p.stem + ".stl")
    if twin.is_file():
        return str(twin)
    log.info("mesh %s: no format Rerun reads; not drawn", path)
    return ""


def body_visuals(client: Any, body: int) -> list[Visual]:
    """The visual shapes of a body, invisible ones (alpha 0) left out."""
    out = []
    for v in client.getVisualShapeData(body):
        link, geom, dims, fname, pos, orn, rgba = v[1], v[2], v[3], v[4], v[5], v[6], v[7]
        if rgba[3] <= 0.0 or geom == _PLANE:
            continue
        mesh = ""
        if geom == _BOX:
            kind, size = "box", (dims[0] / 2, dims[1] / 2, dims[2] / 2)
        elif geom == _SPHERE:
            kind, size = "sphere", (dims[0], dims[0], dims[0])
        elif geom in (_CYLINDER, _CAPSULE):
            kind = "cylinder" if geom == _CYLINDER else "capsule"
            size = (dims[1], dims[1], dims[0] / 2)
        elif geom == _MESH:
            mesh = readable_mesh(fname.decode() if isinstance(fname, bytes) else str(fname))
            if not mesh:
                continue
            kind, size = "mesh", (dims[0], dims[1], dims[2])
        else:
            continue
        out.append(
            Visual(
                link=int(link),
                kind=kind,
                size=tuple(float(s) for s in size),  # type: ignore[arg-type]
                mesh=mesh,
                position=tuple(float(p) for p in pos),  # type: ignore[arg-type]
                quat_xyzw=tuple(float(q) for q in orn),  # type: ignore[arg-type]
                rgba=tuple(int(round(255 * c)) for c in rgba),  # type: ignore[arg-type]
            )
        )
    return out


def link_poses(
    client: Any, body: int, links: list[int]
) -> dict[int, tuple[tuple[float, ...], tuple[float, ...]]]:
    """Each link's frame in W now: {link: (position [m], quaternion x y z w)}; -1 is the base.

    The base's frame is its URDF link frame (PyBullet reports the base's centre
    of mass; the inertial offset is taken back out).
    """
    out: dict[int, tuple[tuple[float, ...], tuple[float, ...]]] = {}
    rest = [k for k in links if k >= 0]
    if -1 in links:
        p, o = client.getBasePositionAndOrientation(body)
        info = client.getDynamicsInfo(body, -1)
        ip, io = client.invertTransform(info[3], info[4])
        out[-1] = tuple(client.multiplyTransforms(p, o, ip, io))  # type: ignore[assignment]
    if rest:
        states = client.getLinkStates(body, rest)  # read only: no forward kinematics here
        for k, st in zip(rest, states, strict=True):
            out[k] = (tuple(st[4]), tuple(st[5]))
    return out
