"""The item loop's seams: one loop for every platform, no PyBullet call above the plant,
the end-effector commanded through one in-step composite."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from cell.loop import Decision, ItemLoop, Platform
from cell.sim import CellScene
from cell.sim.frames import ee_pose_for_item_centre
from cell.sim.settle import crossing

CELL = Path(__file__).resolve().parents[1] / "cell"

# The plant and what renders or records it: the only code that talks to PyBullet.
PLANT = {
    "sim",  # the PyBullet cell
    "endeffector/pybullet_backend.py",  # the plant's end-effector
    "platforms/drone.py",  # the drone's scene (a CellScene)
    "platforms/mobile_scene.py",  # the moving base's scene (a CellScene)
    "record",  # the recorder draws the plant's bodies
    "catalogue.py",  # finds meshes in pybullet_data (a data path, no physics)
}


def _in_plant(path: Path) -> bool:
    rel = path.relative_to(CELL).as_posix()
    return any(rel == p or rel.startswith(p + "/") for p in PLANT)


def _pybullet_uses(path: Path) -> list[str]:
    """Imports of pybullet and uses of a `.client` (the PyBullet connection) in a file."""
    tree = ast.parse(path.read_text(), str(path))
    uses = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom):
            names = [a.name for a in node.names]
            mod = getattr(node, "module", None) or ""
            if any(n.split(".")[0] in ("pybullet", "pybullet_data") for n in [mod, *names]):
                uses.append(f"{path.name}:{node.lineno} imports pybullet")
        elif isinstance(node, ast.Attribute) and node.attr == "client":
            uses.append(f"{path.name}:{node.lineno} uses .client")
    return uses


def test_the_scan_finds_pybullet_where_it_is():
    """The check below is not blind: the plant's own files are flagged by it."""
    assert _pybullet_uses(CELL / "sim" / "scene.py")
    assert _pybullet_uses(CELL / "endeffector" / "pybullet_backend.py")


def test_no_pybullet_call_above_the_plant():
    """The loop, the platforms, the workflows, planning, the CLI: none talks to PyBullet;
    they ask the plant (cell.sim.CellScene) where items are and what touches them."""
    above = [p for p in sorted(CELL.rglob("*.py")) if not _in_plant(p)]
    assert len(above) > 50
    found = [u for p in above for u in _pybullet_uses(p)]
    assert not found, found


@pytest.mark.parametrize(
    "platform",
    [
        "cell.orchestrator:Orchestrator",
        "cell.platforms.runner:PlatformRunner",
        "cell.workflows.campaign:ReleasePose",
    ],
)
def test_every_platform_offers_the_loops_steps(platform):
    """The arm, the drone and moving base, and the campaign's release poses each give the
    loop every step of `cell.loop.Platform`, with its arguments; only the arm places
    (`cell.loop.Places`) and learns from landings (its own `landed`)."""
    import importlib
    import inspect

    mod, name = platform.split(":")
    cls = getattr(importlib.import_module(mod), name)
    for step in (
        "present",
        "decide",
        "pick",
        "carry",
        "release",
        "finish",
    ):
        want = list(inspect.signature(getattr(Platform, step)).parameters)
        got = list(inspect.signature(getattr(cls, step)).parameters)
        assert len(got) == len(want), (name, step, got, want)
    for attr in ("name", "overlaps", "rotor_rpm"):
        assert hasattr(cls, attr) or attr in cls.__annotations__, (name, attr)
    assert hasattr(cls, "after_place") == (name == "Orchestrator")  # `Places`
    assert hasattr(cls, "landed") == (name == "Orchestrator")


def test_a_campaign_throw_goes_through_the_loop_and_its_track_gives_its_landing():
    """`throw_once` (the campaign's platform in the item loop): the record's landing is
    where the observed track crosses the landing plane, the track starts at the release
    point, and the item is taken away after."""
    from cell.endeffector.factory import make_in_step
    from cell.workflows.campaign import throw_once

    with CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0)) as sc:
        ee = make_in_step(sc).sim
        track: list[np.ndarray] = []
        p0 = (0.0, 0.0, 0.7)
        rec = throw_once(
            sc,
            ee,
            "cube50",
            stroke=0.08,
            position=p0,
            elevation=math.radians(35),
            land_z=0.1,
            track=track,
        )
        assert not sc.items  # taken away
    tr = track[0]
    assert tr.shape[1] == 4 and np.all(np.diff(tr[:, 0]) > 0)
    assert np.linalg.norm(tr[0, 1:] - p0) < 0.03  # the launch's first steps
    x, y, t = crossing(tr, 0.1)
    assert (x, y) == pytest.approx((rec["landed_x_m"], rec["landed_y_m"]), abs=1e-12)
    assert rec["landed_x_m"] > 0.5  # it flew forward, it did not drop


def test_a_campaign_loop_has_no_job():
    from cell.errors import InvalidInput
    from cell.workflows.campaign import ReleasePose

    pf = ReleasePose(None, None, "cube50", 0.05, (0, 0, 1), 0.5)  # type: ignore[arg-type]
    loop = ItemLoop(None, pf, None)  # type: ignore[arg-type]
    with pytest.raises(InvalidInput, match="campaign"):
        _ = loop.job
    assert pf.decide(0, _obj("cube50"), None) == Decision("throw", 0.05)


def test_the_in_step_end_effector_drives_the_hardware_and_the_plant_in_order():
    """One composite commands both: the hardware (the Dynamixel back-end on an emulated
    Protocol 2.0 bus, through dynamixel-sdk) winds to the stroke the plant's grip holds
    the item at, opens its latch before the plant's (the plant then shows the launch the
    hardware made) and places after it."""
    from cell.endeffector.factory import make_end_effector, make_in_step

    hw = make_end_effector("dynamixel", emulate=True, time_scale=8.0)
    seen: list[tuple[str, bool]] = []
    with CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0)) as sc:
        eff = make_in_step(sc, hw)
        try:
            sim_throw, sim_place = eff.sim.throw, eff.sim.place

            def throw() -> None:
                seen.append(("sim throw", hw.status().latch_engaged))
                sim_throw()

            def place() -> None:
                seen.append(("sim place", hw.status().latch_engaged))
                sim_place()

            eff.sim.throw, eff.sim.place = throw, place  # type: ignore[method-assign]
            pose = ee_pose_for_item_centre((0, 0, 0.7), 0.6, 0.0, 0.07, _obj("cube50"))
            sc.hold_ee(*pose, teleport=True)
            item = sc.spawn_item("cube50")
            eff.grasp(0.07, item)
            assert eff.sim.holds_item()
            assert hw.stroke() == pytest.approx(0.07, abs=2e-3)  # the spool's encoder
            assert eff.stroke() == hw.stroke()
            eff.throw()
            assert not hw.status().latch_engaged and not eff.sim.holds_item()
            item2 = sc.spawn_item("cube50")
            eff.grasp(0.05, item2)
            eff.place()
        finally:
            eff.close()
    # the hardware's latch was open when the plant's throw came; engaged for the place
    assert seen == [("sim throw", False), ("sim place", True)]


def _obj(name: str):
    from cell.sim.items import resolve_object

    return resolve_object(name)[0]


def test_a_landing_on_a_pile_above_the_rim_is_scored_at_its_touchdown():
    """A throw into a low-rimmed bin can come down on the items the bin holds, above its
    rim plane: it is scored where it touched down (on that height's plane), not failed
    for never crossing the rim's plane; a normal descent is scored at the crossing."""
    from cell.results import landing
    from cell.sim.settle import Outcome

    t = np.linspace(0.0, 1.0, 101)
    x = 2.0 * t
    z_high = 1.0 - 0.9 * t  # ends at 0.10 m, never below a 0.05 m rim
    common = dict(touchdown_speed=3.0, touchdown_body=7, bin_id="b", rested=True, t_rest=1.2)
    pile = Outcome(
        touchdown_xyz=(2.0, 0.0, 0.10),
        rest_xyz=(2.0, 0.0, 0.10),
        t_touchdown=1.0,
        track=np.c_[t, x, 0 * t, z_high],
        **common,
    )
    (lx, ly, lt), plane = landing(pile, 0.05)
    assert (lx, ly, lt, plane) == (2.0, 0.0, 1.0, 0.10)
    through = Outcome(
        touchdown_xyz=(2.0, 0.0, 0.0),
        rest_xyz=(2.0, 0.0, 0.0),
        t_touchdown=1.0,
        track=np.c_[t, x, 0 * t, 1.0 - t],
        **common,
    )
    (lx, _, lt), plane = landing(through, 0.05)
    assert plane == 0.05 and lx == pytest.approx(1.9) and lt == pytest.approx(0.95)
