"""Inputs a new user's cell gives, an eleventh round: an option abbreviated, two arms in
one job, a joint locked by its limits, bins written in millimetres, ids and catalogue
names in another case, a rim too low to keep a thrown item."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import cell
from cell.catalogue import catalogue
from cell.cli.cmd_bench import _robots
from cell.cli.cmd_job import job_yaml
from cell.cli.cmd_run import _table
from cell.errors import InvalidInput, InvalidParameter, JobError
from cell.jobs import load_job, parse_job
from cell.results import ItemResult, RunSummary
from cell.robot.model import load_robot
from cell.robot.mount import check_against_urdf, load_mount
from cell.robot.paths import example_robot_data_dir, robots_dir
from tests.cli_exit import cell_exit

ROOT = Path(cell.__file__).resolve().parents[1]


def test_an_abbreviated_option_is_refused_with_its_full_name(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cell run JOB --no-lo` was taken as `--no-log` (argparse's prefix matching): an
    abbreviation a later option could make ambiguous, or turn into another option,
    silently. Every option is now taken only as written; a prefix is refused naming the
    option it abbreviates. `cell throw --lis` printed the catalogue and exited 0."""
    assert cell_exit(["throw", "--lis"]) == 2
    err = capsys.readouterr().err
    assert "unrecognized arguments: --lis; did you mean --list?" in err, err
    assert err.startswith("usage: cell throw"), err
    assert cell_exit(["throw", "--list"]) == 0  # the full name, as before
    assert "cube50" in capsys.readouterr().out
    assert cell_exit(["bench", "sort", "--lay", "2"]) == 2  # was "did you mean --only?"
    assert "--lay 2; did you mean --layouts?" in capsys.readouterr().err


FAR = "{id: far, position_m: [1.60, 0.00], size_m: [0.40, 0.40], rim_height_m: 0.15}"


def _job(bins: list[str], items: list[str], head: str = "") -> str:
    return (
        f"{head}bins:\n"
        + "".join(f"  - {b}\n" for b in bins)
        + "items:\n"
        + "".join(f"  - {i}\n" for i in items)
    )


def _refused(text: str) -> str:
    with pytest.raises(JobError) as exc:
        parse_job(text, "j.yaml", check_reach=False)
    return str(exc.value)


def test_two_arms_in_one_job_are_refused_saying_why() -> None:
    """`cell: {robot: [panda, ur5]}` was "['panda', 'ur5'] must be a non-empty text"; a
    job runs one arm, at the world frame's origin, and the refusal now says so. One name
    loads (the shipped UR5's mount file, checked against its URDF)."""
    for key, given in (("robot", "[panda, ur5]"), ("mount", "[a/mount.yaml, b/mount.yaml]")):
        msg = _refused(_job([FAR], ["{object: cube50, bin: far}"], f"cell: {{{key}: {given}}}\n"))
        assert f"line 1, cell.{key}: a list of 2" in msg, msg
        assert "a job runs one arm" in msg and "a job of its own" in msg, msg
    job = parse_job(_job([FAR], ["{object: cube50, bin: far}"], "cell: {robot: ur5}\n"), "j.yaml")
    assert job.robot == "ur5"


def _ur5_mount(folder: Path, urdf: str, joints: int = 6, held: str = "") -> Path:
    """The shipped UR5 mount file, copied beside `urdf` (a copy of the UR5's URDF) and
    naming it; with `joints` 5 the wrist's roll is left out of the arm's joints (its
    limits, home, acceleration and jerk with it), and `held` added."""
    (folder / "ur5_copy.urdf").write_text(urdf)
    mount = (robots_dir() / "ur5_throwing/mount.yaml").read_text()
    mount = re.sub(r"(?m)^arm_urdf: .*$", "arm_urdf: ur5_copy.urdf", mount)
    mount = re.sub(r"(?m)^arm: ur5$", "arm: ur5_copy", mount)
    if joints == 5:
        mount = mount.replace(", wrist_3_joint]", "]")
        mount = re.sub(r", 1200\.0\]", "]", mount)
        mount = re.sub(r", 12\.0\]", "]", mount)
        mount = re.sub(r"(?m)^(home: \[.*), 0\.0\]", r"\1]", mount)
    path = folder / "mount.yaml"
    path.write_text(mount + held)
    return path


def test_a_joint_of_zero_range_is_told_how_to_hold_it_still(tmp_path: Path) -> None:
    """A URDF whose wrist roll has `lower="0.0" upper="0.0"` (a joint locked the URDF's
    way) was refused as "the wrong way round or equal"; the refusal now also says how a
    mount file holds a joint still (`held_joints`), and that advice loads: the arm's
    other five joints solve the grip pointing down (by their forward kinematics, at the
    asked point within 1 mm), and `cell bench sort --robots` takes its mount file."""
    src = (example_robot_data_dir() / "ur_description/urdf/ur5_robot.urdf").read_text()
    lines = src.splitlines()
    at = next(k for k, ln in enumerate(lines) if 'name="wrist_3_joint"' in ln)
    lim = next(k for k in range(at, len(lines)) if "<limit" in lines[k])
    lines[lim] = re.sub(r'lower="[^"]*" upper="[^"]*"', 'lower="0.0" upper="0.0"', lines[lim])
    urdf = "\n".join(lines)
    with pytest.raises(InvalidParameter) as exc:
        check_against_urdf(load_mount(str(_ur5_mount(tmp_path, urdf))))
    msg = str(exc.value)
    assert "joint 'wrist_3_joint' (revolute): its position limits lower=0.0 and upper=0.0" in msg
    assert "leave it out of arm_joints and give held_joints: {wrist_3_joint: 0}" in msg, msg
    held = _ur5_mount(tmp_path, urdf, 5, "held_joints: {wrist_3_joint: 0}\n")
    check_against_urdf(load_mount(str(held)))
    out = tmp_path / "r.json"
    at_m = (0.5, 0.1, 0.3)
    args = ["reach", "--robot", str(held), "--at", *map(str, at_m), "--elevation", "-1.5707"]
    assert cell_exit([*args, "--json", str(out)]) == 0
    q = np.asarray(json.loads(out.read_text())["q"], float)
    assert q.shape == (5,)
    tcp, _ = load_robot(str(held)).tcp_pose(q)
    assert np.allclose(tcp, at_m, atol=1e-3)
    # `cell bench sort --robots` took names only ("give arms from panda, ur10, ur3, ur5"):
    # the held arm's mount file is taken, the locked one refused with its file's reason
    assert _robots(f"panda,{held}") == ("panda", str(held.resolve()))
    locked = _ur5_mount(tmp_path, urdf)
    with pytest.raises(
        InvalidInput, match=r"--robots: .*mount.yaml: field 'arm_urdf'.*held_joints"
    ):
        _robots(str(locked))
    with pytest.raises(InvalidInput, match=r"give arms from panda, .*, or mount files"):
        _robots(str(tmp_path / "none.yaml"))


def test_a_bin_written_in_millimetres_is_refused_with_its_metres() -> None:
    """A bin `position_m: [1600, 0]` (millimetres) loaded, to be refused only by the
    planner ("it lies 1599.60 m from the release point"); a rim of 150 was "150.0 must be
    ≤ 1.0"; a pick station at [450, -400, 200] was "missed by 633043 mm". Each is now
    refused at load naming what reads as millimetres and the bin in metres, and the job
    written so loads, the bin where the metres put it."""
    msg = _refused(_job(["{id: far, position_m: [1600, 0], size_m: [0.3, 0.3], rim_height_m: 0.15}"], ["{object: cube50, bin: far}"]))  # fmt: skip
    assert "line 2, bins[0]: read in metres (a job's unit), the bin has its centre 1,600 m" in msg
    assert "written in millimetres? In metres: position_m [1.6, 0]" in msg, msg
    assert "size_m" not in msg.split("In metres")[1]  # the fields in metres are not named
    mm = "{id: far, position_m: [1600, 0], size_m: [300, 300], rim_height_m: 150}"
    msg = _refused(_job([mm], ["{object: cube50, bin: far}"]))
    said = "position_m [1.6, 0], size_m [0.3, 0.3], rim_height_m 0.15"
    assert f"and a rim 150 m high (at most 1 m); written in millimetres? In metres: {said}" in msg
    job = parse_job(_job([f"{{id: far, {said.replace(' [', ': [').replace('m 0', 'm: 0')}}}"],
                         ["{object: cube50, bin: far}"]), "j.yaml", check_reach=False)  # fmt: skip
    assert job.bins[0].position == (1.6, 0.0) and job.bins[0].rim_height == 0.15
    # the pick station in millimetres was "missed by 633043 mm" by the arm's reach check
    msg = _refused(_job([FAR], ["{object: cube50, bin: far}"], "pick_station: {position_m: [450, -400, 200]}\n"))  # fmt: skip
    assert "line 1, pick_station.position_m: read in metres (a job's unit), the pick " in msg
    assert "lies 634 m from the base (at most 100 m); written in millimetres? In metres: [0.45, -0.4, 0.2]" in msg  # fmt: skip
    # a rim over 1 m that is no millimetres (1.5 mm would be under the plate): the bound
    msg = _refused(_job(["{id: far, position_m: [1.6, 0], size_m: [0.3, 0.3], rim_height_m: 1.5}"], ["{object: cube50, bin: far}"]))  # fmt: skip
    assert "a rim 1.5 m high (at most 1 m)" in msg and "millimetres?" not in msg, msg


def test_names_in_another_case_are_told_the_name_and_two_ids_in_case_warned() -> None:
    """`Bins:`, `object: Cube50`, `ｃube50` (full-width), `cube-50`, `robot: Panda` and an
    item's `bin: NEAR` were refused with the valid names listed but none named; each now says the
    name it is near (`did you mean 'bins'?`). Two bins `near` and `Near` loaded as two
    bins without a word; they are now warned of. A mesh file given as `object` is told a
    job takes none."""
    msg = _refused("Bins:\n  - " + FAR + "\nitems:\n  - {object: cube50, bin: far}\n")
    assert "line 2, Bins: unknown key 'Bins'; did you mean 'bins'?" in msg, msg
    assert "needs its 'bins' list" not in msg  # said once, by the key written
    items = [f"{{object: {o}, bin: far}}" for o in ("Cube50", "ｃube50", "cube-50")]
    msg = _refused(_job([FAR], items))
    for k, o in enumerate(("Cube50", "ｃube50", "cube-50")):
        assert f"items[{k}].object: unknown catalogue id {o!r}; did you mean 'cube50'?" in msg
    msg = _refused(_job([FAR], ["{object: cube50, bin: far}"], "cell: {robot: Panda}\n"))
    assert "'Panda' is not an arm under robots/; did you mean 'panda'?" in msg, msg
    msg = _refused(_job([FAR], ["{object: parts/widget.stl, bin: far}"]))
    assert "(a file? a job takes no mesh of its own" in msg, msg
    msg = _refused(_job([FAR], ["{object: cube50, bin: Far}"]))
    assert "'Far' is not valid; choose one of far; did you mean 'far'?" in msg, msg
    near = "{id: near, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}"
    two = [near, FAR.replace("id: far", "id: Near")]
    job = parse_job(_job(two, ["{object: cube50, bin: Near}"]), "j.yaml", check_reach=False)
    assert [b.id for b in job.bins] == ["near", "Near"] and job.items[0].bin == "Near"
    (said,) = [w for w in job.warnings if "differ only in case" in w]
    assert "bins 'near' and 'Near' differ only in case, and are two bins" in said
    job = parse_job(_job([FAR], ["{object: cube50, bin: far}"]), "j.yaml", check_reach=False)
    assert not any("case" in w for w in job.warnings)


def test_a_rim_under_a_thrown_items_resting_centre_is_warned_of() -> None:
    """A bin 4 m out with a 0.02 m rim took a cube50 thrown to 0.011 m of its aim, which
    slid out over the wall, without a word. A thrown item whose centre rests higher above
    the floor plate (0.01 m) than the wall's top is now warned of, the rim that would keep
    it named; from the extents alone (a sphere40's radius, 20 mm; a cube50's half side,
    25 mm), not the warning's own rule: at 0.029 m both are warned, at 0.031 m the cube
    only, at 0.036 m neither; a placed item, never. No decision changes: the bins the
    job throws into are the same with the warning or without it."""

    def warned(rim: float, near: bool = False) -> list[str]:
        pos = "[0.55, 0.35]" if near else "[2.50, 0.00]"
        b = f"{{id: b, position_m: {pos}, size_m: [0.40, 0.40], rim_height_m: {rim}}}"
        items = ["{object: sphere40, bin: b}", "{object: cube50, bin: b}"]
        job = parse_job(_job([b], items), "j.yaml", check_reach=False)
        return [w for w in job.warnings if "slide or roll over the wall" in w]

    sphere, cube = catalogue()["sphere40"].params.size, catalogue()["cube50"].params.size
    assert sphere[0] / 2 == pytest.approx(0.020) and cube[0] / 2 == pytest.approx(0.025)
    both = warned(0.029)
    assert len(both) == 2, both
    assert "line 4: the wall of bin 'b' stands 19 mm above its floor plate" in both[0]
    assert "under the 20 mm at which sphere40's centre rests" in both[0]
    assert "a rim of at least 0.03 m keeps" in both[0]
    assert "under the 25 mm at which cube50's centre rests" in both[1]
    (one,) = warned(0.031)
    assert "line 5" in one and "cube50" in one
    assert warned(0.036) == []
    assert warned(0.029, near=True) == []  # placed (policy auto, within place_reach_m)


def _demo_summary() -> RunSummary:
    """The demo's run as `cell run tasks/bins.yaml --json` wrote it (docs/figures/run.json)."""
    d = json.loads((ROOT / "docs/figures/run.json").read_text())
    results = [ItemResult(**{k: v for k, v in r.items() if k in ItemResult.__dataclass_fields__}) for r in d["results"]]  # fmt: skip
    summary = {k: v for k, v in d.items() if k in RunSummary.__dataclass_fields__}
    return RunSummary(**{**summary, "results": results})


def test_the_run_table_on_a_narrow_terminal_is_broken_between_cells(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """At COLUMNS=60 the terminal wrapped the run's rows where the 60th column fell,
    inside a number (`0.` then `074 m`) and without an indent. On a terminal narrower
    than a row, the row is now broken between its cells, the rest indented; on no
    terminal (a file, a pipe) every row is whole, as before. Checked on the demo's
    run: each line at most 60 columns, and the same words in the same order as the
    whole rows, every `0.005 m` whole."""
    summary = _demo_summary()
    _table(summary, "tasks/bins.yaml", None)
    whole = capsys.readouterr().out
    _table(summary, "tasks/bins.yaml", None, 60)
    narrow = capsys.readouterr().out
    assert max(len(ln) for ln in whole.splitlines()) > 60  # the rows are wider
    assert max(len(ln) for ln in narrow.splitlines()) <= 60, narrow
    assert whole.split() == narrow.split()
    numbers = re.compile(r"\d+\.\d+ [ms]\b")
    assert numbers.findall(whole) == numbers.findall(narrow) != []
    assert re.search(r"\n {5}\d\.\d{3} m\n", narrow)  # a stroke on its row's second line
    assert "\n  planning per item    median" in narrow
    assert re.search(r"\n {23}max \d+\.\d+ s \(wall time", narrow), narrow  # under the value


def test_throw_and_plan_say_an_item_is_lighter_than_the_model_knows(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cell throw` of a 2 g paper ball (50 mm) printed a launch of 83 m/s, 12 m out,
    without a word; a job throwing it is warned of (lighter than any catalogue object).
    `cell throw` and `cell plan` now say the same; the lightest catalogue object, cube30
    at 20 g, is not warned of."""
    paper = ["--shape", "sphere", "--mass", "0.002", "--size", "0.05", "0.05", "0.05"]
    assert cell_exit(["throw", *paper, "--json", "-"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["launch_speed_mps"] > 20.0  # beyond any throw of the cell
    assert "cell: warning: sphere (2 g) is lighter than the lightest object the throw " in err
    assert "(cube30, 20 g)" in err, err
    assert cell_exit(["plan", *paper, "--target", "6", "0", "0.15", "--json", "-"]) == 0
    assert "(2 g) is lighter than the lightest object" in capsys.readouterr().err
    assert cell_exit(["throw", "--object", "cube30", "--json", "-"]) == 0
    assert "lighter" not in capsys.readouterr().err
    assert min(e.params.mass for e in catalogue().values()) == pytest.approx(0.020)


def test_a_random_job_asked_for_as_json_is_json(tmp_path: Path) -> None:
    """`cell job random -o job.json` wrote YAML into a file named .json, which a JSON tool
    refuses; it now writes JSON (`json.loads` reads it), the job `cell run` loads from it
    the same as from the YAML `cell job random` writes of it (JSON is YAML): its bins,
    items and counts."""
    as_json = tmp_path / "job.json"
    assert cell_exit(["job", "random", "--seed", "3", "-o", str(as_json)]) == 0
    doc = json.loads(as_json.read_text(encoding="utf-8"))
    assert doc["name"] == "random layout 3" and doc["bins"] and doc["items"]
    a, b = load_job(as_json), parse_job(job_yaml(doc), "job.yaml", check_reach=False)
    assert a.bins == b.bins and [(i.obj, i.count, i.bin) for i in a.items] == [
        (i.obj, i.count, i.bin) for i in b.items
    ]
