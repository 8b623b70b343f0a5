"""The other implementation's world (`cell.gap.world_other`) lands each throw where it lands
alone: its integrator drops the throws that have landed while the others fly on, and no
throw's landing, flight time or impact velocity depends on the others thrown with it, to
the bit."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from cell.gap.world_other import Throws, draw_throws, landings


def _take(th: Throws, rows: np.ndarray) -> Throws:
    """The throws at rows, every array of theirs taken along."""
    arrays = {f.name: getattr(th, f.name)[rows] for f in fields(th) if f.name != "extra"}
    return replace(th, **arrays, extra={k: v[rows] for k, v in th.extra.items()})


def _e(kind: str, form: str = "const", **kw: object) -> dict:
    return {"kind": kind, "form": form, **kw}


@pytest.mark.parametrize(
    "effects",
    [
        [],
        # a downwash's column reads where the object is, at every stage
        [_e("downwash", w_mps=8.0, radius_m=0.4, depth_m=1.2), _e("wind", x_mps=1.0, y_mps=-0.5)],
        # the push's mass, a drag factor and a side force
        [
            _e("band_mass", value=0.02),
            _e("drag_scale", value=1.8),
            _e("side_force", x_mps2=0.0, y_mps2=0.25),
        ],
    ],  # fmt: skip
    ids=["nominal", "downwash+wind", "band_mass+drag+side"],
)
def test_a_throw_lands_where_it_lands_alone(effects: list[dict]) -> None:
    th = draw_throws(40, np.random.default_rng(2), drone_share=0.4)
    every = landings(th, effects)  # each effect at its deterministic part (no rng)
    t = every[1]
    # flights of different lengths: the rows drop out of the integration at different steps
    assert np.isfinite(t).all() and np.ptp(t) > 0.3
    for rows in (np.array([int(np.argmax(t))]), np.arange(39, -1, -3)):
        alone = landings(_take(th, rows), effects)
        for got, want in zip(alone, every, strict=True):
            assert got.tobytes() == want[rows].tobytes()


def test_the_other_world_lands_where_it_landed_before() -> None:
    """Every effect of this world at once (in two sets: each law form of the push's mass,
    the drag and the wind, a downwash's column, a side force, the stroke's offset, the
    release's pitch and yaw, a slide, a tracker's scale), drawn and at its deterministic
    part, gives the landings, flight times and impact velocities of the integrator before
    it dropped landed throws and took each throw's drag and push once
    (tests/world_other_before.py), to the bit."""
    from tests import world_other_before as before

    cd = {"cube50": 1.4, "cube30": 2.0, "cuboid_c": 1.2, "cyl50": 1.6, "cyl70": 1.3,
          "sphere40": 2.2, "sphere70": 1.5, "block40": 1.8}  # C_d by object  # fmt: skip
    sets = [
        [_e("band_mass", "throw", value=0.02, sd=0.004),
         _e("drag_scale", "object", value=1.6, per_object=cd),
         _e("wind", "throw", x_mps=1.0, y_mps=0.8, sd=0.3),
         _e("downwash", w_mps=8.0, radius_m=0.4, depth_m=1.2),
         _e("side_force", x_mps2=0.1, y_mps2=0.25),
         _e("release_pitch", "throw", value=0.07, sd=0.01),
         _e("slide", "friction", mu=1.2)],
        [_e("band_mass", "stroke", k=0.15), _e("band_damping", value=0.5),
         _e("drag_scale", "throw", value=1.8, sd=0.15), _e("wind", x_mps=1.2, y_mps=-0.6),
         _e("stroke_offset", value=0.004), _e("release_yaw", "stroke", k=1.0),
         _e("slide", tau_s=0.05), _e("tracking_scale", value=1.03)],
    ]  # fmt: skip
    th = draw_throws(60, np.random.default_rng(4), drone_share=0.4)
    # the first set drawn (each throw's own mass, drag and wind), the second at its
    # deterministic part
    for effects, seed in zip(sets, (5, None), strict=True):
        got = landings(th, effects, None if seed is None else np.random.default_rng(seed))
        want = before.landings(th, effects, None if seed is None else np.random.default_rng(seed))
        assert np.isfinite(got[1]).sum() > 50
        for g, w in zip(got, want, strict=True):
            assert g.tobytes() == w.tobytes()
