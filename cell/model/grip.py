"""What the pads can hold: friction against the band's grip force.

The band's two halves pull the pads together with f_g = f_e sin α each
(thesis §2, `cell.model.band`); with Coulomb friction μ on both pads the grip
holds an item of mass m while 2 μ f_g(L_s, a) ≥ s · m g, where s ≥ 1 is a safety
factor that covers the arm's accelerations while carrying. f_g falls as the
stroke L_s grows (the band turns toward the throw axis), and a narrow item is
held by a small angle, so the grip sets, per item, the longest stroke it may be
carried and thrown with, or refuses the item.
"""

from __future__ import annotations

import numpy as np

from cell.model.band import band_angle, band_force, band_stretch
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams, G

__all__ = [
    "PAD_FRICTION",
    "GRIP_SAFETY",
    "grip_friction",
    "holding_mass_kg",
    "max_grip_stroke",
]

# Coulomb friction between a pad and an item. The scene's pads have 1.2 and its items 0.7;
# Bullet combines two bodies' coefficients as their product, 0.84, and the scene holds
# 0.70-0.71 of what 1.2 predicts at every width and stroke measured (30-50 mm, 0.045-0.09 m).
PAD_FRICTION = 1.2 * 0.7
GRIP_SAFETY = 1.6  # weight multiple the grip must hold: carrying accelerates up to ~0.6 g


def grip_friction(obj: ObjectParams, pad_length_m: float, friction: float = PAD_FRICTION) -> float:
    """The friction coefficient the pads hold `obj` with along the throw axis.

    Flat pads touch a box or a cylinder's side flat: μ. A sphere of radius R longer than
    the pads (R > L_p, the pads reach from the carriage's face, where the sphere sits, to
    L_p) is touched at the pads' edges below its equator, where its surface faces back
    toward the carriage: the contact normal leans θ off the horizontal, sin θ = (R − L_p)/R,
    and the squeeze pushes the sphere out along the axis. Each pad is driven across the
    throw axis by the band's f_g; at the point of slipping the contact's force (normal N
    and friction μ N) leans the friction angle atan μ off its normal, so its axial part is
    f_g tan(atan μ − θ): a wedge. Returned as that coefficient (0 when the squeeze alone
    would push the sphere out).

    Measured with the scene's probe (`cell.sim.grip_probe`, pulled out along the throw
    axis at strokes 0.05 and 0.08 m): an 88 mm sphere held 0.74-0.75 of μ cos θ − sin θ
    (the pads' normal force taken as f_g), 0.90 of this; a 70 mm one 0.83-0.84 and 0.93;
    spheres within the pads 1.05-1.10 of μ, as boxes (tests/test_grip_probe.py).
    """
    if obj.shape != "sphere":
        return friction
    r = obj.size[0] / 2
    if r <= pad_length_m:
        return friction
    theta = float(np.arcsin((r - pad_length_m) / r))
    return max(0.0, float(np.tan(np.arctan(friction) - theta)))


def holding_mass_kg(
    ee: EndEffectorParams, stroke_m: float, width_m: float, friction: float = PAD_FRICTION
) -> float:
    """The heaviest item [kg] of width a the pads hold against gravity at stroke L_s."""
    a = max(width_m, ee.d)
    f_e = float(band_force(np.float64(band_stretch(stroke_m, a, ee)), ee))
    f_g = f_e * float(np.sin(band_angle(stroke_m, a, ee)))
    return 2.0 * friction * f_g / G


def max_grip_stroke(
    ee: EndEffectorParams,
    obj: ObjectParams,
    safety: float = GRIP_SAFETY,
    friction: float = PAD_FRICTION,
) -> float | None:
    """The longest stroke [m] in the end-effector's range at which the grip holds
    `safety` × the item's weight, or None when it cannot at any stroke."""
    need = safety * obj.mass
    strokes = np.linspace(ee.stroke_min, ee.stroke_max, 81)
    ok = [s for s in strokes if holding_mass_kg(ee, float(s), obj.width, friction) >= need]
    return float(max(ok)) if ok else None
