"""The scene's per-step arithmetic on plain floats gives the bits the NumPy formulas gave:
the band law, the drag, the effect scene's forces, and the motor commands not sent again
(cell.sim.band, cell.sim.drag, cell.sim.effect_scene). Each is held against the NumPy
form it replaced, or against a scene that sends every command."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from cell.model.band import band_angle, band_force, band_stretch
from cell.model.params import DEFAULT_EE
from cell.sim import CellScene
from cell.sim.drag import apply_drag, drag_force, speed
from cell.sim.effect_scene import RHO, EffectScene, _cd_area


def _numpy_law(s: float, a: float) -> tuple[float, float, float, float]:
    """The band law as the scene evaluated it with the NumPy back-end."""
    ee = DEFAULT_EE
    a_eff = max(a, ee.d)
    stretch = float(band_stretch(s, a_eff, ee))
    f_e = float(band_force(np.float64(stretch), ee))
    alpha = float(band_angle(s, a_eff, ee))
    return stretch, f_e, float(2 * f_e * np.cos(alpha)), float(f_e * np.sin(alpha))


def _bits(values: Any) -> list[str]:
    return [float(v).hex() for v in values]


@pytest.fixture(scope="module")
def scene():
    sc = CellScene(robot=None, pick_station_xy=(-1.0, -1.0))
    yield sc
    sc.close()


def test_the_band_law_on_floats_is_the_numpy_law_to_the_bit(scene: CellScene) -> None:
    rng = np.random.default_rng(0)
    ee = DEFAULT_EE
    # strokes short of the band's origin L_t and beyond it (α past π/2), on it, and widths
    # inside the hoop (a = d: α = 0)
    strokes = np.r_[rng.uniform(-0.01, ee.L_t + 0.05, 3000), 0.0, ee.stroke_max, ee.L_t, ee.L_t]
    widths = np.r_[rng.uniform(0.0, 0.12, 3000), ee.d, 0.0, ee.d, 0.05]
    slack = 0
    for s, a in zip(strokes.tolist(), widths.tolist(), strict=True):
        got, want = scene.band.law(s, a), _numpy_law(s, a)
        assert _bits(got) == _bits(want), (s, a)
        slack += got[0] <= 0.0
    assert 0 < slack < len(strokes)  # both sides of the slack band were held


def test_drag_on_floats_is_the_numpy_drag_to_the_bit(scene: CellScene) -> None:
    rng = np.random.default_rng(1)
    vels = np.r_[rng.normal(0.0, 4.0, (3000, 3)), rng.normal(0.0, 1e-3, (500, 3)), np.zeros((1, 3))]
    for v in vels:
        assert speed(v) == float(np.linalg.norm(v))
    item = scene.spawn_item("cube50", position=(0.0, 0.0, 1.0))
    try:
        for v in vels[:200]:
            scene.client.resetBaseVelocity(item.body, v.tolist(), [0.0, 0.0, 0.0])
            got = apply_drag(scene.client, item.body, item.drag_c)
            assert _bits(got) == _bits(drag_force(item.drag_c, v))
    finally:
        scene.remove_item(item)


class _NumpyEffectScene(EffectScene):
    """The effect scene's forces as they were written on NumPy vectors (the reference)."""

    def _item_forces(self) -> None:
        cl = self.client
        for it in self.items:
            pos, _ = cl.getBasePositionAndOrientation(it.body)
            v = np.asarray(cl.getBaseVelocity(it.body)[0])
            rel = v - self.air(np.asarray(pos))
            cd, area = _cd_area(it.obj)
            c_f = self.drag_factor * 0.5 * RHO * cd * area
            f = -c_f * np.linalg.norm(rel) * rel + it.drag_c * np.linalg.norm(v) * v
            f = f + it.obj.mass * self.side_mps2
            if np.any(f != 0.0):
                cl.applyExternalForce(it.body, -1, f.tolist(), pos, cl.WORLD_FRAME)
        for it in self.items:
            if it.body not in self._kept:
                v = np.asarray(cl.getBaseVelocity(it.body)[0])
                f = drag_force(it.drag_c, v)
                if f.any():
                    pos, _ = cl.getBasePositionAndOrientation(it.body)
                    cl.applyExternalForce(it.body, -1, f.tolist(), pos, cl.WORLD_FRAME)


def _fly(sc: EffectScene) -> list[str]:
    """A sphere thrown through wind, a rotor's jet and a side force, onto the floor."""
    sc.wind = np.array([2.5, -1.2, 0.0])
    sc.drag_factor = 1.5
    sc.side_mps2 = np.array([0.3, -0.2, 0.0])
    sc.jet = (np.array([0.0, 0.0, 1.6]), 6000.0, {"w_mps": 9.0, "radius_m": 0.25, "core_m": 0.8})
    item = sc.spawn_item("sphere40", position=(0.0, 0.0, 1.5))
    sc.client.resetBaseVelocity(item.body, [2.0, 0.5, 3.0], [1.0, -2.0, 0.5])
    track = []
    for _ in range(1500):
        sc.step()
        p, o = sc.client.getBasePositionAndOrientation(item.body)
        v, w = sc.client.getBaseVelocity(item.body)
        track += _bits((*p, *o, *v, *w))
    return track


def test_the_effect_forces_on_floats_fly_the_numpy_flight_to_the_bit() -> None:
    with EffectScene() as new, _NumpyEffectScene() as ref:
        got, want = _fly(new), _fly(ref)
    assert got == want
    assert float.fromhex(got[-11]) < 0.05  # it reached the floor (z of the last sample)


def test_the_effect_forces_on_floats_are_the_numpy_forces_to_the_bit() -> None:
    """Each force applied, for items anywhere in the jet and out of it, at any velocity
    (one item kept in a bin: the effect's force, no drag), as the NumPy vectors gave it."""
    rng = np.random.default_rng(2)
    with EffectScene() as sc:
        sc.wind = np.array([2.5, -1.2, 0.0])
        sc.drag_factor = 1.5
        sc.side_mps2 = np.array([0.3, -0.2, 0.0])
        sc.jet = (
            np.array([0.1, -0.2, 1.6]),
            6000.0,
            {"w_mps": 9.0, "radius_m": 0.25, "core_m": 0.8},
        )
        items = [
            sc.spawn_item(k, position=(0.0, 0.0, 1.0 + i))
            for i, k in enumerate(("cube50", "sphere40", "cyl50"))
        ]
        sc._kept.add(items[2].body)
        calls: list[tuple[Any, ...]] = []
        sc.client.applyExternalForce = lambda *a: calls.append(a)  # recorded, not applied

        def forces(apply: Any) -> list[Any]:
            calls.clear()
            apply(sc)
            # per body, in the order applied (Bullet sums each body's forces in that order)
            per_body = sorted(calls, key=lambda c: c[0])
            return [(b, link, _bits(f), _bits(p), frame) for b, link, f, p, frame in per_body]

        for _ in range(400):
            for it in items:
                p = [*rng.uniform(-0.6, 0.6, 2), rng.uniform(0.0, 2.5)]
                sc.client.resetBasePositionAndOrientation(it.body, p, [0.0, 0.0, 0.0, 1.0])
                sc.client.resetBaseVelocity(it.body, rng.normal(0.0, 4.0, 3).tolist(), [0, 0, 0])
            got = forces(EffectScene._item_forces)
            assert got == forces(_NumpyEffectScene._item_forces)
            assert len(got) == 5  # the effect's force on each item, the drag on two


def _cycle(sc: CellScene, resend: bool) -> list[str]:
    """The band wound, released, the fingers opened to a width, closed and opened: the
    mechanism's joint states at every step."""
    band, out = sc.band, []

    def run(n: int) -> None:
        for _ in range(n):
            if resend:
                band._sent.clear()  # every command sent, as before
            sc.step()
            for js in sc.client.getJointStates(sc.ee_body, (0, 1, 2)):
                out.extend(_bits(js[:2]))

    band.reset(0.02, 0.03)
    band.wind(0.08, 0.5)
    run(200)
    sc.set_timestep(sc.launch_dt_s)
    band.latched = False
    run(200)
    sc.set_timestep(sc.dt_s)
    band.open_to_m = 0.02
    run(150)
    band.fingers_closing = True
    run(150)
    band.fingers_closing, band.open_to_m = False, None
    run(150)
    return out


def test_motor_commands_not_sent_again_change_no_step() -> None:
    with CellScene(robot=None) as a, CellScene(robot=None) as b:
        sc_a, sc_b = _cycle(a, resend=False), _cycle(b, resend=True)
    assert sc_a == sc_b
    assert not math.isclose(float.fromhex(sc_a[0]), float.fromhex(sc_a[-6]))  # it moved
