"""The checks of the figures the guide page docs/grip.md quotes (run by
tests/test_readme_figures.py): the margins and the items against the code's constants and
the catalogue, the refusal messages as the code gives them."""

from __future__ import annotations

import inspect
import re
from typing import Any

import pytest

from tests.figure_quotes import COVERED, close, page_text, quoted


# -- docs/grip.md ----------------------------------------------------------------------------
def _quoted_message(page: str, msg: str) -> None:
    """`msg`, produced by the code, is quoted on `page` (wrapped anywhere)."""
    m = re.search(re.escape(msg).replace(r"\ ", " ").replace(" ", r"\s+"), page_text(page))
    assert m, f"{page} no longer quotes {msg!r}"
    COVERED[page].append(m.span())


def _refusal(params: Any, obj: Any) -> str:
    from cell.arm.grip_side import holding_sides
    from cell.errors import CannotGrip

    with pytest.raises(CannotGrip) as err:
        holding_sides(params, obj)
    return str(err.value)


def _check_the_sides(page: str, params: Any) -> None:
    """How the side is chosen: the margins, cuboid_a's sides, the thin box."""
    from cell.arm import grip_limits
    from cell.arm.grip_side import holding_sides
    from cell.catalogue import get_object
    from cell.model.grip import grip_friction, holding_mass_kg
    from cell.model.objects import ObjectParams
    from cell.robot import grip_hold
    from cell.sim.mechanism import DEFAULT_GEOMETRY as GEO

    brisk, slow = quoted(page, r"the pads hold ([\d.]+) x the item's weight at some stroke .*? "
                         r"within the carry's bound only \(([\d.]+) x, see below\)")  # fmt: skip
    assert float(brisk) == grip_limits.BRISK_CARRY_SAFETY
    assert float(slow) == grip_hold.CARRY_MARGIN
    # cuboid_a: across 30 mm only slowly, across 50 mm briskly up to the longest stroke
    sx, sy, sz, mass, narrow, ask, across, wide = quoted(
        page,
        r"`cuboid_a` \((\d+) x (\d+) x (\d+) mm, (\d+) g\) is held across (\d+) mm only slowly "
        r"\(its weight asks ([\d.]+) of the pads' friction at the shortest stroke\) and across "
        r"(\d+) mm briskly up to the longest stroke: the cell grips it across (\d+) mm",
    )
    obj = get_object("cuboid_a")
    assert [float(v) / 1000 for v in (sx, sy, sz)] == pytest.approx(list(obj.size))
    assert float(mass) / 1000 == pytest.approx(obj.mass)
    assert float(narrow) / 1000 == pytest.approx(obj.width)
    mu = grip_friction(obj, GEO.pad_length_m)
    close(ask, obj.mass / holding_mass_kg(params.ee, params.ee.stroke_min, obj.width, mu), 2)
    assert grip_limits.grip_strokes(params, obj)[1] is False
    assert grip_limits.grip_strokes(params, obj.turned()) == (
        pytest.approx(params.ee.stroke_max),
        True,
    )
    sides = holding_sides(params, obj)
    assert [1000 * s.width_m for s in sides] == [pytest.approx(float(across))]
    assert float(wide) == float(across)
    g, a, b, c, taken = quoted(page, r"A (\d+) g box (\d+) x (\d+) x (\d+) mm, refused before, "
                               r"is gripped across (\d+) mm")  # fmt: skip
    box = ObjectParams("cuboid", float(g) / 1000, tuple(float(v) / 1000 for v in (a, b, c)))
    assert [1000 * s.width_m for s in holding_sides(params, box)] == [pytest.approx(float(taken))]


def _check_the_mesh_sides(page: str, params: Any) -> None:
    """A mesh's width where the pads meet its first side (`pad_width_m`) and its second
    (computed here from the vertices: its extent along y within the pads' strip about x),
    how the rock and the shard rest (`rest_shift`) against the pads' half width, the
    shard's height, and the egg's two widths."""
    import math

    import numpy as np

    from cell.arm.grip_side import MESH_SAME_WIDTH_M, grip_sides, holding_sides
    from cell.catalogue import catalogue, get_object, mesh_vertices, pad_width_m
    from cell.errors import CannotGrip
    from cell.sim.mechanism import DEFAULT_GEOMETRY
    from cell.sim.rest import rest_shift

    r0, s0, d, r1, s1 = quoted(
        page,
        r"`rock_000` is (\d+) mm where the pads meet it and `shard_661` (\d+) mm, under the "
        r"band's (\d+) mm anchor spacing; their second side is (\d+) and (\d+) mm across",
    )
    assert float(d) / 1000 == pytest.approx(params.ee.d)
    for name, first, second in (("rock_000", r0, r1), ("shard_661", s0, s1)):
        obj = get_object(name)
        close(first, 1000 * pad_width_m(obj), 0)
        entry = catalogue()[name]
        v = mesh_vertices(entry.params.mesh, entry.mesh_scale)
        strip = v[np.abs(v[:, 0]) <= DEFAULT_GEOMETRY.pad_half_width_m]
        close(second, 1000 * float(np.ptp(strip[:, 1])), 0)
    half, rock, side, h, tilt, shift = quoted(
        page,
        r"no more than the pads' half width, (\d+) mm .*?`rock_000` rests level \(([\d.]+) "
        r"mm\): it is gripped across its (\d+) mm side. `shard_661`, standing on its (\d+) mm "
        r"edge in its catalogue frame, tips (\d+) deg over \(its surface moves (\d+) mm\)",
    )
    close(half, 1000 * DEFAULT_GEOMETRY.pad_half_width_m, 0)
    rock_obj, shard = get_object("rock_000"), get_object("shard_661")
    close(rock, 1000 * rest_shift(rock_obj).shift_m, 1)
    assert [round(1000 * s.width_m) for s in holding_sides(params, rock_obj)] == [int(side)]
    close(h, 1000 * shard.size[2], 0)
    close(tilt, math.degrees(rest_shift(shard).tilt_rad), 0)
    close(shift, 1000 * rest_shift(shard).shift_m, 0)
    with pytest.raises(CannotGrip):
        holding_sides(params, shard)
    same, e0, e1 = quoted(
        page, r"within (\d+) mm \(the egg: ([\d.]+) and ([\d.]+) mm, its\s+facets\)"
    )
    close(same, 1000 * MESH_SAME_WIDTH_M, 0)
    egg = get_object("o7_egg")
    close(e0, 1000 * pad_width_m(egg), 1)
    close(e1, 1000 * pad_width_m(egg.turned()), 1)
    assert len(grip_sides(egg)) == 1


def _check_the_carry(page: str, params: Any) -> None:
    """The carry's bound and tilt, the tetrapack, the items held at points."""
    from cell.arm import grip_limits, planner
    from cell.arm.grip_side import holding_sides
    from cell.arm.tuning import TUNING, ArmTuning
    from cell.catalogue import get_object
    from cell.robot import grip_hold

    # the carry's bound, the pads held accelerated, the tilt
    bound, lo, hi = quoted(page, r"the grip's use stays within (1/[\d.]+) of what the pads hold "
                           r"\(the pads hold ([\d.]+)-([\d.]+) of their static friction")  # fmt: skip
    assert bound == f"1/{grip_hold.CARRY_MARGIN}"
    assert f"the pads hold {lo}-{hi} of what they hold at rest" in inspect.getsource(grip_hold)
    (over,) = quoted(page, r"asks more than ([\d.]+) of the grip with the tilt \(`TILT_SLOWS_OVER`")
    assert float(over) == grip_hold.TILT_SLOWS_OVER
    (headroom,) = quoted(page, r"within that plus ([\d.]+), and the slower")
    assert float(headroom) == grip_hold.TILT_HEADROOM
    (held,) = quoted(page, r"would ask more than ([\d.]+) of the grip \(`RELEASE_HELD_MAX`")
    assert float(held) == planner.RELEASE_HELD_MAX
    without, with_ = quoted(page, r"a carry that asked ([\d.]+) without it asked ([\d.]+) with it")
    assert f"asked {without} of it, {with_} with the tilt counted" in inspect.getsource(grip_hold)
    # the tetrapack: held only below the brisk margin, carried slowly, not refused
    t_g, old = quoted(page, r"the (\d+) g `o5_tetrapack`, refused before \(the pads hold it only "
                      r"below the old ([\d.]+)x margin\)")  # fmt: skip
    tetra = get_object("o5_tetrapack")
    assert float(t_g) / 1000 == pytest.approx(tetra.mass)
    assert float(old) == grip_limits.BRISK_CARRY_SAFETY
    assert [s.brisk for s in holding_sides(params, tetra)] and not any(
        s.brisk for s in holding_sides(params, tetra)
    )
    (no_longer,) = quoted(page, r"The ([\d.]+)x no longer refuses anything held by its faces")
    assert float(no_longer) == grip_limits.BRISK_CARRY_SAFETY
    # items held at points: the margin measured in the scene (ArmTuning's record of it)
    margin, d_mm, s_g, held, carries, layout = quoted(
        page,
        r"`ArmTuning.point_hold_margin` = ([\d.]+): an (\d+) mm, (\d+) g sphere the pads hold "
        r"with ([\d.]+) x its weight left them on all (\w+) of its carries of random layout (\d+)",
    )
    assert float(margin) == TUNING.point_hold_margin == ArmTuning().point_hold_margin
    doc = inspect.getsource(ArmTuning)
    assert f"an {d_mm} mm, {s_g} g sphere the" in doc and f"with {held} x its weight" in doc
    assert f"all {carries} of its\n            carries of random layout {layout}," in doc


def _check_the_slow_holds(page: str, params: Any) -> None:
    """The tetrapack placed at the shortest stroke; a sphere carried at it where the
    pads' measured hold leaves its carry no room."""
    from cell.arm.grip_limits import carry_safety, grip_force_n, mesh_grip, point_hold_use
    from cell.arm.tuning import TUNING
    from cell.catalogue import get_object
    from cell.model.objects import ObjectParams
    from cell.model.params import G
    from cell.robot import grip_hold

    tetra, short = get_object("o5_tetrapack"), params.ee.stroke_min
    s_pick, use_pick, bound, s_short, use_short = quoted(
        page,
        r"At (\d+) mm the tetrapack's weight alone asks ([\d.]+) of the grip, nearly all of "
        r"the carry's bound ([\d.]+),.*? At (\d+) mm its weight asks ([\d.]+)\.",
    )
    assert float(s_pick) / 1000 == pytest.approx(TUNING.pick_stroke_m)
    assert float(s_short) / 1000 == pytest.approx(short)
    close(use_pick, tetra.mass * G / grip_force_n(params, tetra, TUNING.pick_stroke_m), 2)
    close(use_short, tetra.mass * G / grip_force_n(params, tetra, short), 2)
    close(bound, 1.0 / grip_hold.CARRY_MARGIN, 2)
    groups = quoted(
        page,
        r"A sphere is thrown at strokes up to where the grip model holds ([\d.]+) x its weight.*?pull it out "
        r"at less than the model's force: ([\d.]+) of it for the (\d+) mm, (\d+) g sphere of "
        r"random layout (\d+) .*?asks more than (1/[\d.]+) at the throw's stroke.*?thrown at "
        r"(\d+) mm, where its weight asks ([\d.]+) of the measured hold.*?carried at (\d+) mm",
    )
    margin, ratio, d_mm, m_g, layout, margin2, s_mm, use, s_carry = groups
    sphere = ObjectParams("sphere", float(m_g) / 1000, (float(d_mm) / 1000,) * 3)
    assert float(margin) == float(margin2[2:]) == carry_safety(sphere)
    close(ratio, mesh_grip(params, sphere)[0], 2)
    close(use, point_hold_use(params, sphere, float(s_mm) / 1000), 2)
    assert float(s_carry) / 1000 == pytest.approx(short)
    test = inspect.getsource(__import__("tests.test_point_held_carry").test_point_held_carry)
    assert f"random layout {layout}, UR5" in test and f"a {s_mm} mm stroke" in test


def _check_the_steep_throw(page: str) -> None:
    """The steep rule's constants as the page gives them (`ArmTuning`)."""
    import math

    from cell.arm.tuning import TUNING

    rim, steep = quoted(page, r"rim is lower than ([\d.]+) m \(`ArmTuning.steep_rim_m`\) a throw "
                        r"is planned first with the throw axis at least (\d+)° up")  # fmt: skip
    assert float(rim) == TUNING.steep_rim_m
    assert int(steep) == round(math.degrees(TUNING.steep_elevation_rad))
    (logged,) = quoted(page, r"logged at info \(`the steep release \((\d+)° up\)")
    assert int(logged) == int(steep)
    (twist,) = quoted(page, r"turns the grip at most (\d+)° off the one rotation between its ends")
    assert int(twist) == round(math.degrees(TUNING.steep_twist_max_rad))


def check_the_grip_page() -> None:
    """The side choice, the carry's scaling and the refusals as docs/grip.md describes them
    are the code's: its margins, the catalogue's items and the messages it gives."""
    import dataclasses

    from cell.catalogue import get_object
    from cell.model.objects import ObjectParams
    from cell.params import load_params, scene_params_path

    page, params = "docs/grip.md", load_params(scene_params_path())
    _check_the_sides(page, params)
    _check_the_mesh_sides(page, params)
    _check_the_carry(page, params)
    _check_the_slow_holds(page, params)
    _check_the_steep_throw(page)
    # the refusals, each message the code's own
    cube = ObjectParams("cube", 0.3, (0.25,) * 3, name="item0_cube")
    thin = ObjectParams("cylinder", 0.05, (0.018, 0.018, 0.06), name="thin")
    for obj in (
        cube,
        thin,
        ObjectParams("cube", 0.3, (0.04,) * 3, name="cube"),
        dataclasses.replace(get_object("cuboid_a"), mass=0.5),
    ):
        _quoted_message(page, _refusal(params, obj))
    # a mesh whose other side is not offered, both sides named
    _quoted_message(page, _refusal(params, get_object("shard_661")))
    # the item held only slowly: placed, never thrown
    from cell.arm.grip_side import holding_sides, throw_sides
    from cell.errors import CannotGrip

    tetra = get_object("o5_tetrapack")
    with pytest.raises(CannotGrip) as err:
        throw_sides(holding_sides(params, tetra), tetra)
    _quoted_message(page, str(err.value))
