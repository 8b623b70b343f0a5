"""A ball dropped from the landing plane onto the PyBullet scene's floor, to rest: what the
bounce's drop and roll law tests (tests/test_gap_drop.py, tests/test_gap_roll.py) throw."""

from __future__ import annotations

import numpy as np

PLANE_Z = 0.1  # [m] the landing plane above the scene's floor (world frame, z up)


def drop_ball(obj: str, vh: float, vz: float, floor: tuple[float, float, float],
              heights: list[float] | None = None
              ) -> tuple[float, float, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """A ball set with its centre on the landing plane moving at (v_h, 0, −v_z) [m/s], no
    spin, onto the scene's floor (restitution, friction, rolling friction [m]), stepped
    until it is at rest (30 steps under 0.01 m/s) or 3 s: (rest − start along x [m],
    across [m], and at every step the time [s], the velocity along x [m/s] and the spin
    about y times the radius, ω_y r [m/s]). `heights`, if given, receives the centre's
    height above the floor [m] after every step (a hop shows as a rise after the first
    touch)."""
    from cell.sim.effect_scene import EffectScene

    sc = EffectScene()
    try:
        sc.set_floor(*floor)
        item = sc.spawn_item(obj, position=(0.0, 0.0, PLANE_Z))
        r = item.obj.size[0] / 2
        sc.client.resetBaseVelocity(item.body, [vh, 0.0, -vz], [0.0, 0.0, 0.0])
        t, vx, wr, slow = [], [], [], 0
        while sc.t < 3.0 and slow < 30:
            sc.step()
            v, w = sc.item_velocity(item)
            t.append(sc.t)
            vx.append(v[0])
            wr.append(w[1] * r)
            slow = slow + 1 if np.linalg.norm(v) < 0.01 else 0
            if heights is not None:
                heights.append(float(sc.item_position(item)[2]))
        p = sc.item_position(item)
        return float(p[0]), float(p[1]), np.array(t), np.array(vx), np.array(wr)
    finally:
        sc.close()
