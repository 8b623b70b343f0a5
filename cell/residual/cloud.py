"""The composite point cloud of the fingers gripping an object (thesis Fig. 5.3)
and fixed-length shape descriptors computed from it.

Object frame O: origin at the object's box centre (= centre of mass), x across
the band (the grip width a = size_x), z along the throw axis (the band pushes
on the object's rear, z < 0, towards +z). Every length is in metres.

The object's surface is sampled analytically for primitives (cube, cuboid,
cylinder with its axis along z, sphere) and area-weighted from the triangles of
a mesh. The composite cloud adds what touches the object in the grip: the two
finger pads (the object's points near the planes x = ±a/2) and the band's hoop,
which lies on the object's rear profile in the plane y = 0. Sampling is seeded,
so one object always gives the same cloud and the same descriptors.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cell.errors import InvalidInput
from cell.infile import check_input_file
from cell.model.objects import SHAPES

__all__ = [
    "DESCRIPTOR_NAMES",
    "ObjectGeometry",
    "sample_surface",
    "read_obj_mesh",
    "composite_cloud",
    "shape_descriptors",
]

N_POINTS = 1500  # surface samples per object
_PROFILE_BINS = 4  # width profile along z
_SEED = 20240517

DESCRIPTOR_NAMES = (
    "pc_extent_x_m",
    "pc_extent_y_m",
    "pc_extent_z_m",
    "pc_pca1_m",
    "pc_pca2_m",
    "pc_pca3_m",
    "pc_hull_fill",
    "pc_rear_flat_frac",
    "pc_pad_frac",
    "pc_wrap_excess",
    "pc_rear_depth",
    *(f"pc_width_z{i}" for i in range(_PROFILE_BINS)),
    "pc_composite_extent_z_m",
)


@dataclass(frozen=True)
class ObjectGeometry:
    """What the cloud of one object is made from.

    Attributes:
        shape: one of SHAPES.
        size: box extents (size_x, size_y, size_z) [m] in O.
        mesh: mesh file (absolute, or relative to pybullet_data) for shape "mesh", else "".
        mesh_scale: scale of the mesh's vertices.
        grip_yaw: rotation of the object about z_O in the grip [rad] (0 = as catalogued).
    """

    shape: str
    size: tuple[float, float, float]
    mesh: str = ""
    mesh_scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    grip_yaw: float = 0.0


# [B] the largest mesh file read: pybullet_data's largest OBJ (a whole scene) is 10 MB;
# a mesh is read into Python lists, some 8 times its size in memory
MAX_MESH_BYTES = 32 * 1024 * 1024


def read_obj_mesh(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (n, 3) and triangles (m, 3, int) of a Wavefront OBJ file.

    Polygons are fan-triangulated; `v/vt/vn` and negative indices are understood.

    Raises:
        InvalidInput: not a regular file or over `MAX_MESH_BYTES`, unreadable, a vertex
            without three finite numbers, a face naming a vertex the file does not have
            (OBJ counts from 1; negative counts back from the last), or no vertices or no
            faces; naming the line.
    """
    p = check_input_file(path, "mesh file (OBJ)", MAX_MESH_BYTES)
    verts: list[list[float]] = []
    tris: list[list[int]] = []
    n = 0
    top = (-1, 0)  # the highest vertex a face names (from 0), and its line

    def bad(msg: str) -> InvalidInput:
        return InvalidInput(f"mesh {p}, line {n}: {msg}")

    try:
        with open(p) as fh:
            for n, line in enumerate(fh, start=1):  # noqa: B007 (`bad` reads n)
                if line.startswith("v "):
                    xyz = line.split()[1:4]
                    try:
                        v = [float(x) for x in xyz]
                    except ValueError:
                        raise bad(f"vertex {xyz} is not three numbers") from None
                    if len(v) != 3 or not all(math.isfinite(x) for x in v):
                        raise bad(f"a vertex needs three finite numbers, not {xyz}")
                    verts.append(v)
                elif line.startswith("f "):
                    idx = []
                    for tok in line.split()[1:]:
                        try:
                            i = int(tok.split("/")[0])
                        except ValueError:
                            raise bad(f"face vertex {tok!r} is not a whole number") from None
                        k = i - 1 if i > 0 else len(verts) + i
                        if i == 0 or k < 0:
                            raise bad(
                                f"a face names vertex {i}, and {len(verts)} come before it "
                                "(OBJ counts vertices from 1; -1 is the last before)"
                            )
                        if k > top[0]:
                            top = (k, n)
                        idx.append(k)
                    for k in range(1, len(idx) - 1):
                        tris.append([idx[0], idx[k], idx[k + 1]])
    except InvalidInput:
        raise
    except (OSError, ValueError) as exc:
        raise InvalidInput(f"mesh {p}: not a readable OBJ file ({exc})") from None
    if not verts or not tris:
        raise InvalidInput(f"mesh {p}: needs vertices and faces (v and f lines)")
    if top[0] >= len(verts):
        raise InvalidInput(
            f"mesh {p}, line {top[1]}: a face names vertex {top[0] + 1}; the file has {len(verts)}"
        )
    return np.asarray(verts, float), np.asarray(tris, int)


def _box_surface(size: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    x, y, z = size
    areas = np.array([y * z, y * z, x * z, x * z, x * y, x * y])
    face = rng.choice(6, size=n, p=areas / areas.sum())
    p = (rng.random((n, 3)) - 0.5) * size
    axis = face // 2
    sign = np.where(face % 2 == 0, -0.5, 0.5)
    p[np.arange(n), axis] = sign * size[axis]
    return p


def _cylinder_surface(size: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    rx, ry, h = size[0] / 2, size[1] / 2, size[2]
    r = (rx + ry) / 2
    side, cap = 2 * math.pi * r * h, math.pi * r * r
    kind = rng.choice(3, size=n, p=np.array([side, cap, cap]) / (side + 2 * cap))
    th = rng.random(n) * 2 * math.pi
    rad = np.where(kind == 0, 1.0, np.sqrt(rng.random(n)))
    z = np.where(kind == 0, (rng.random(n) - 0.5) * h, np.where(kind == 1, -h / 2, h / 2))
    return np.stack([rx * rad * np.cos(th), ry * rad * np.sin(th), z], axis=-1)


def _ellipsoid_surface(size: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v * (size / 2)


def _mesh_surface(
    mesh: str, scale: tuple[float, float, float], n: int, rng: np.random.Generator
) -> np.ndarray:
    from cell.catalogue import mesh_path

    verts, tris = read_obj_mesh(mesh_path(mesh))
    verts = verts * np.asarray(scale, float)
    verts -= (verts.max(axis=0) + verts.min(axis=0)) / 2
    a, b, c = verts[tris[:, 0]], verts[tris[:, 1]], verts[tris[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    if not np.isfinite(area).all() or area.sum() <= 0:
        raise InvalidInput(f"mesh {mesh}: its faces have no area")
    t = rng.choice(len(tris), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u, v = np.where(flip, 1 - u, u), np.where(flip, 1 - v, v)
    return a[t] + u[:, None] * (b[t] - a[t]) + v[:, None] * (c[t] - a[t])


def sample_surface(geom: ObjectGeometry, n: int = N_POINTS) -> np.ndarray:
    """Seeded surface samples of the object in the grip pose [m, frame O], shape (n, 3).

    Raises:
        InvalidInput: an unknown shape, or a mesh object without a readable mesh.
    """
    return _sample_cached(geom, n).copy()


@functools.lru_cache(maxsize=256)
def _sample_cached(geom: ObjectGeometry, n: int) -> np.ndarray:
    rng = np.random.default_rng(_SEED)
    size = np.asarray(geom.size, float)
    if geom.shape in ("cube", "cuboid"):
        p = _box_surface(size, n, rng)
    elif geom.shape == "cylinder":
        p = _cylinder_surface(size, n, rng)
    elif geom.shape == "sphere":
        p = _ellipsoid_surface(size, n, rng)
    elif geom.shape == "mesh":
        if not geom.mesh:
            raise InvalidInput(
                "a mesh object needs its mesh file for the shape descriptors "
                "(a `mesh` column in the log, or a catalogue object id)"
            )
        p = _mesh_surface(geom.mesh, geom.mesh_scale, n, rng)
    else:
        raise InvalidInput(f"unknown shape {geom.shape!r}; valid: {', '.join(SHAPES)}")
    if geom.grip_yaw:
        c, s = math.cos(geom.grip_yaw), math.sin(geom.grip_yaw)
        p = p @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    p.setflags(write=False)
    return p


def _rear_profile(obj: np.ndarray, n_bins: int = 15) -> tuple[np.ndarray, np.ndarray]:
    """The object's rear profile z_rear(x) as the band sees it [m]: the lowest z of the
    points in each x bin, i.e. the lower envelope of the silhouette seen along y
    (bins without points are dropped)."""
    lo, hi = float(obj[:, 0].min()), float(obj[:, 0].max())
    edges = np.linspace(lo, hi, n_bins + 1)
    which = np.clip(np.searchsorted(edges, obj[:, 0], side="right") - 1, 0, n_bins - 1)
    xs, zs = [], []
    for b in range(n_bins):
        sel = which == b
        if sel.any():
            xs.append(0.5 * (edges[b] + edges[b + 1]))
            zs.append(float(obj[sel, 2].min()))
    return np.asarray(xs), np.asarray(zs)


def composite_cloud(geom: ObjectGeometry, hoop_width_m: float = 0.02) -> np.ndarray:
    """The composite cloud: the object's surface, the two finger pads and the band's
    hoop on the object's rear [m, frame O], shape (k, 4); column 3 labels the part
    (0 object, 1 finger pad, 2 band).

    Args:
        geom: the object and its pose in the grip.
        hoop_width_m: width d of the band's hoop [m].
    """
    obj = _sample_cached(geom, N_POINTS)
    ext = np.ptp(obj, axis=0)
    half_a = 0.5 * float(obj[:, 0].max() - obj[:, 0].min())
    pad_tol = max(0.05 * 2 * half_a, 5e-4)
    pads = obj[np.abs(np.abs(obj[:, 0]) - half_a) <= pad_tol]
    xs, zs = _rear_profile(obj)
    xb = np.linspace(-0.5 * max(hoop_width_m, 2 * half_a), 0.5 * max(hoop_width_m, 2 * half_a), 21)
    zb = np.interp(xb, xs, zs) if xs.size > 1 else np.full_like(xb, -0.5 * ext[2])
    band = np.stack([xb, np.zeros_like(xb), zb], axis=-1)
    parts = [np.c_[obj, np.zeros(len(obj))], np.c_[pads, np.ones(len(pads))]]
    parts.append(np.c_[band, np.full(len(band), 2.0)])
    return np.concatenate(parts, axis=0)


def _hull_fill(obj: np.ndarray) -> float:
    from scipy.spatial import ConvexHull, QhullError

    box = float(np.prod(np.ptp(obj, axis=0)))
    try:
        return float(ConvexHull(obj).volume) / box if box > 0 else 0.0
    except QhullError:
        return 0.0  # a flat cloud encloses no volume


def shape_descriptors(geom: ObjectGeometry) -> np.ndarray:
    """Fixed-length shape descriptors of the composite cloud, in the order of
    DESCRIPTOR_NAMES (lengths [m], the rest dimensionless):

    * extents of the object cloud along x, y, z of O;
    * principal standard deviations of the object cloud (largest first);
    * convex-hull volume / box volume (1 for a box, π/4 cylinder, π/6 sphere);
    * the fraction of object points within 5% of size_z of the rearmost point
      (a flat rear face that the band presses on);
    * the fraction of object points the finger pads touch (flat sides);
    * the band's wrap excess: (length of the rear profile between the fingers
      - chord) / chord, the extra band a curved rear takes up;
    * the rear depth: mean height of the rear profile above its lowest point / a;
    * the object's width across the band in 4 slabs along z, over a;
    * the composite cloud's extent along z [m].
    """
    return _descriptors_cached(geom).copy()


@functools.lru_cache(maxsize=256)
def _descriptors_cached(geom: ObjectGeometry) -> np.ndarray:
    comp = composite_cloud(geom)
    obj = comp[comp[:, 3] == 0, :3]
    n = len(obj)
    ext = np.ptp(obj, axis=0)
    a = max(float(ext[0]), 1e-6)
    centred = obj - obj.mean(axis=0)
    pca = np.sqrt(np.maximum(np.linalg.eigvalsh(centred.T @ centred / n)[::-1], 0.0))
    z_min = float(obj[:, 2].min())
    rear_flat = float(np.mean(obj[:, 2] <= z_min + 0.05 * ext[2]))
    pad_frac = float(np.sum(comp[:, 3] == 1)) / n
    xs, zs = _rear_profile(obj)
    if xs.size > 1:
        seg = np.hypot(np.diff(xs), np.diff(zs)).sum()
        chord = float(xs[-1] - xs[0])
        wrap = float(seg / chord - 1.0) if chord > 0 else 0.0
        depth = float(np.mean(zs - zs.min())) / a
    else:
        wrap, depth = 0.0, 0.0
    edges = np.linspace(obj[:, 2].min(), obj[:, 2].max(), _PROFILE_BINS + 1)
    which = np.clip(np.searchsorted(edges, obj[:, 2], side="right") - 1, 0, _PROFILE_BINS - 1)
    widths = [
        float(np.ptp(obj[which == b, 0])) / a if np.any(which == b) else 0.0
        for b in range(_PROFILE_BINS)
    ]
    out = np.array(
        [
            *ext,
            *pca,
            _hull_fill(obj),
            rear_flat,
            pad_frac,
            wrap,
            depth,
            *widths,
            float(np.ptp(comp[:, 2])),
        ]
    )
    out.setflags(write=False)
    return out
