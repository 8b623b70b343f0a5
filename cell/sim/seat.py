"""Where an item sits in the pads when they grip it as it lies.

The physical pick (`cell.arm.pick.Pick._pick_once`) comes down over an item resting on
the station along its own axis (or less leaning, `Pick._grip_plan`), aimed at its centre
of mass, and closes the pads on it: the item keeps the orientation it lay in, and the
pads, closing from both sides at once, centre between them the part of its surface they
reach (|y| ≤ the pads' half width in the grip's frame E, and within the pads' length of
the carriage's face along E's z). The kinematic pick
moves the item into the grip (`PyBulletEndEffector.grasp`); `lying_seat` gives it that
same seat: the item's orientation in E as it lay in the frame the physical pick would
grip it with, its centre on the approach axis but for the strip's centring across the
pads, its surface nearest the carriage on the carriage's face. A mesh lying tilted
(shard_661, a wedge: its centre 12 mm off the axis where the pads reach its thick end)
is then held by either pick alike, where the kinematic pick had set it in its catalogue
frame, upright and upside down.
"""

from __future__ import annotations

import math

import numpy as np

from cell.model.objects import ObjectParams

__all__ = ["SEAT_GAP_M", "item_vertices", "lying_seat", "seated_rise_m"]

SEAT_GAP_M = 5e-4  # [m] the item's nearest point off the carriage's face as it is seated
_RING = 24  # points on a cylinder's rim, per rim; a sphere's meridians


def item_vertices(obj: ObjectParams) -> np.ndarray:
    """Points of the item's surface in its body frame [m], shape (n, 3), centred on its
    centre of mass (its box's centre): a mesh's vertices (`cell.catalogue.mesh_vertices`),
    a box's corners, a cylinder's rims, a sphere's points on 12 parallels."""
    from cell.catalogue import catalogue, mesh_vertices

    sx, sy, sz = obj.size
    if obj.shape == "mesh":
        entry = catalogue().get(obj.name or "")
        if entry is not None and obj.mesh:
            return np.asarray(mesh_vertices(obj.mesh, entry.mesh_scale), float)
    if obj.shape == "cylinder":
        a = np.linspace(0.0, 2 * math.pi, _RING, endpoint=False)
        rim = np.stack([sx / 2 * np.cos(a), sx / 2 * np.sin(a)], axis=1)
        return np.vstack([np.column_stack([rim, np.full(_RING, z)]) for z in (-sz / 2, sz / 2)])
    if obj.shape == "sphere":
        lat = np.linspace(-math.pi / 2, math.pi / 2, 13)
        lon = np.linspace(0.0, 2 * math.pi, _RING, endpoint=False)
        la, lo = np.meshgrid(lat, lon)
        r = sx / 2
        return np.column_stack(
            [
                (r * np.cos(la) * np.cos(lo)).ravel(),
                (r * np.cos(la) * np.sin(lo)).ravel(),
                (r * np.sin(la)).ravel(),
            ]
        )
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    return np.asarray(corners, float) * np.array([sx, sy, sz]) / 2


def lying_seat(
    obj: ObjectParams,
    rot_item: np.ndarray,
    grip_frame: np.ndarray,
    stroke_m: float,
    pad_half_width_m: float,
    pad_length_m: float,
    tip_clearance_m: float | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """The item's seat in the grip as the pads take it as it lies: (its centre [m] and
    rotation matrix (3, 3) in the end-effector's frame E, E's origin the carriage's
    hoop at stroke 0, E's z the throw axis out of the grip; the pads' opening [m] from
    the axis where they meet it).

    Args:
        obj: the item's body as the scene has it (its catalogue frame, not turned).
        rot_item: its orientation at rest [W] (rotation matrix).
        grip_frame: the orientation [W] of E the physical pick grips it with
            (`Pick._grip_plan`: down its own axis, its side across the pads).
        stroke_m: L_s [m]: the carriage's face at E's z = L_s.
        pad_half_width_m: [m] the pads' half width along E's y.
        pad_length_m: [m] the pads' length along E's z from the carriage's face.
        tip_clearance_m: [m] the physical pick's descent stops with the pads' tips this
            far short of the item's far side (the station it rests on): an item shorter
            than the pads along the axis is held off the carriage's face (None: on it).
    """
    seat = np.asarray(grip_frame, float).T @ np.asarray(rot_item, float)
    v = item_vertices(obj) @ seat.T  # the surface in E, about the item's centre
    v_face = float(v[:, 2].min()) - SEAT_GAP_M  # the carriage's face, item-centred [m]
    if tip_clearance_m is not None:
        v_face = min(v_face, float(v[:, 2].max()) - pad_length_m - tip_clearance_m)
    lo, hi = _hull_extent_x(v, pad_half_width_m, v_face + pad_length_m)
    centre = np.array([-(lo + hi) / 2, 0.0, stroke_m - v_face])
    return centre, seat, (hi - lo) / 2


def seated_rise_m(obj: ObjectParams, rot_item: np.ndarray, seat: np.ndarray) -> float:
    """How far [m] the item's centre rises as it is turned from how it lies (`rot_item`
    [W]) to its seat (rotation `seat` in E) in a grip pointing straight down, its lowest
    point kept SEAT_GAP_M over where it lay (the station's top): where the kinematic pick
    puts it, so that the turn does not sink it into the station."""
    v = item_vertices(obj)
    below = float((v @ np.asarray(rot_item, float).T)[:, 2].min())  # lowest, as it lay
    # in a grip pointing down E's z is the world's -z: its lowest point is E's farthest
    return SEAT_GAP_M + float((v @ np.asarray(seat, float).T)[:, 2].max()) + below


def _hull_extent_x(v: np.ndarray, half_width: float, z_top: float) -> tuple[float, float]:
    """(least, greatest) x [m] of the convex hull of the points v (n, 3) within the slab
    |y| ≤ half_width, z ≤ z_top: what the pads reach of the item as the scene collides
    it (a mesh body is its convex hull). Two linear programs; the points' own extent
    where the slab misses the hull."""
    from scipy.optimize import linprog
    from scipy.spatial import ConvexHull, QhullError

    try:
        eq = ConvexHull(v).equations
    except QhullError:  # flat or degenerate: its points
        return float(v[:, 0].min()), float(v[:, 0].max())
    a = np.vstack([eq[:, :3], [[0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]])
    b = np.concatenate([-eq[:, 3], [half_width, half_width, z_top]])
    free = [(None, None)] * 3
    ends = [linprog([sign, 0.0, 0.0], A_ub=a, b_ub=b, bounds=free) for sign in (1.0, -1.0)]
    if not all(r.success for r in ends):
        return float(v[:, 0].min()), float(v[:, 0].max())
    return float(ends[0].x[0]), float(ends[1].x[0])
