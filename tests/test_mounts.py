"""Any arm from a mount file (issue 59): the arms are the mount files under robots/ and any
a job names; a wrong mount file is refused by name; a job is checked whole against its arm
before it runs (every error in one report); the UR3 and the UR10 sort in the scene."""

from __future__ import annotations

import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import cell.kinds
from cell.errors import InvalidInput, InvalidParameter, JobError
from cell.jobs import load_job, parse_job
from cell.robot import paths
from cell.robot.composite import composite_urdf
from cell.robot.model import load_robot
from cell.robot.mount import load_mount, robot_names

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "robots"
BINS = (ROOT / "tasks" / "bins.yaml").read_text()


def _job_on(robot: str, text: str = BINS) -> str:
    return text.replace("robot: panda", f"robot: {robot}")


def test_the_arms_are_the_mount_files_under_robots() -> None:
    assert not hasattr(cell.kinds, "ROBOTS")
    found = {p.parent.name for p in ROBOTS.glob("*/mount.yaml")}
    assert {f"{n}_throwing" for n in robot_names()} == found
    assert {"panda", "ur3", "ur5", "ur10"} <= set(robot_names())
    for name in robot_names():
        assert (ROBOTS / f"{name}_throwing" / "README.md").is_file()


@pytest.mark.parametrize(
    ("name", "forearm_plus_upper_m"),
    # the UR datasheets' reach (UR3 500 mm, UR10 1300 mm) is the two long links plus the
    # wrists; the links' lengths of the ROS-Industrial descriptions: upper arm + forearm
    [("ur3", 0.24365 + 0.21325), ("ur10", 0.612 + 0.5723)],
)
def test_the_ur3_and_ur10_are_example_robot_datas(name: str, forearm_plus_upper_m: float) -> None:
    rb = load_robot(name)
    assert rb.dof == 6 and rb.spec.flange == "tool0"
    # stretched out level (shoulder lift and elbow 0) the wrist's centre is the two links
    # out from the shoulder: the TCP's distance from the shoulder, less the wrists and the
    # end-effector, bounds it
    p_home = rb.tcp_pose(rb.home)[0]
    assert p_home[2] > 0.1  # home holds the grip over the floor
    q = np.zeros(6)
    tcp = rb.tcp_pose(q)[0]
    shoulder_z = {"ur3": 0.1519, "ur10": 0.1273}[name]
    out = math.hypot(tcp[0], tcp[1], tcp[2] - shoulder_z)
    assert forearm_plus_upper_m < out < forearm_plus_upper_m + 0.5
    # the limits come from the mount file, acceleration and jerk positive, jerk 100x
    np.testing.assert_allclose(rb.limits.jerk, 100 * rb.limits.acceleration)
    assert np.all(rb.limits.velocity > 2.0)


def _copy_mount(tmp_path: Path, name: str = "ur3", edit=lambda s: s) -> Path:
    text = (ROBOTS / f"{name}_throwing" / "mount.yaml").read_text()
    p = tmp_path / "my_arm" / "mount.yaml"
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(edit(text))
    return p


def test_a_job_names_its_own_mount_file_relative_to_the_job(tmp_path: Path) -> None:
    mount = _copy_mount(tmp_path, edit=lambda s: s.replace("arm: ur3", "arm: my_ur3"))
    job_text = (ROOT / "tasks" / "bins_ur3.yaml").read_text()
    job_text = job_text.replace("robot: ur3", "mount: my_arm/mount.yaml")
    (tmp_path / "job.yaml").write_text(job_text)
    job = load_job(tmp_path / "job.yaml")
    assert job.robot == str(mount.resolve())
    rb = load_robot(job.robot)
    assert rb.name == "my_ur3"
    assert rb.tcp_pose(rb.home)[0] == pytest.approx(load_robot("ur3").tcp_pose(rb.home)[0])
    both = job_text.replace("  ee: pybullet", "  robot: ur3\n  ee: pybullet")
    with pytest.raises(JobError, match="cell.mount: give robot .* or mount .* not both"):
        parse_job(both, str(tmp_path / "job2.yaml"))


def test_a_mount_added_under_robots_is_found_by_name(monkeypatch, tmp_path: Path) -> None:
    shutil.copytree(ROBOTS / "throwing_ee", tmp_path / "throwing_ee")
    for name in ("panda", "ur10"):
        shutil.copytree(ROBOTS / f"{name}_throwing", tmp_path / f"{name}_throwing")
    _copy_mount(tmp_path, edit=lambda s: s.replace("arm: ur3", "arm: small"))
    monkeypatch.setenv(paths.ROBOTS_ENV, str(tmp_path))
    paths.robots_dir.cache_clear()
    try:
        assert robot_names() == ("panda", "small", "ur10")
        assert load_mount("small").folder == "my_arm"
        with pytest.raises(InvalidInput, match="unknown robot 'ur3'; valid: panda, small, ur10"):
            load_mount("ur3")
    finally:
        monkeypatch.delenv(paths.ROBOTS_ENV)
        paths.robots_dir.cache_clear()


def _drop_last_joint(text: str) -> str:
    """The mount file with its last joint left out of arm_joints and of every per-joint list."""
    out = []
    for line in text.splitlines():
        key = line.split(":")[0]
        if key in ("arm_joints", "home", "acceleration_limits", "jerk_limits"):
            head, rest = line.split("[", 1)
            body, tail = rest.split("]", 1)
            line = head + "[" + ", ".join(body.split(",")[:-1]) + "]" + tail
        out.append(line)
    return "\n".join(out) + "\n"


WRONG = [
    # (edit of the UR3's mount file, the field named, what the message offers as valid)
    (_drop_last_joint, "arm_joints", "the movable joints from the base to flange 'tool0' are"),
    (lambda s: s.replace("flange: tool0", "flange: tool9"), "flange", "its links: .*tool0"),
    (
        lambda s: s.replace("flange: tool0", "flange: wrist_2_link"),
        "arm_joints' and 'flange",
        "name the link the tool is bolted to",
    ),
    (
        lambda s: s.replace("shoulder_pan_joint,", "shoulder_spin_joint,"),
        "arm_joints",
        "its movable joints: shoulder_pan_joint",
    ),
    (lambda s: s.replace("[10.0, 10.0,", "[-10.0, 10.0,"), "acceleration_limits", "positive"),
    (lambda s: s.replace("home: [0.0,", "home: [9.0,"), "home", "shoulder_pan_joint"),
    (lambda s: s.replace("[1000.0, 1000.0,", "["), "jerk_limits", "6 finite numbers"),
    (lambda s: s + "speed: 3\n", "unknown field", "valid: arm, arm_urdf"),
    (
        lambda s: s.replace("arm_urdf: ur_description", "arm_urdf: ur_nothing"),
        "arm_urdf",
        "not a file",
    ),
]


@pytest.mark.parametrize(("edit", "field", "valid"), WRONG)
def test_a_wrong_mount_file_is_refused_by_name(
    tmp_path: Path, edit, field: str, valid: str
) -> None:
    mount = _copy_mount(tmp_path, edit=edit)
    with pytest.raises(InvalidParameter) as err:
        composite_urdf(str(mount))
    msg = str(err.value)
    assert msg.startswith(f"{mount.resolve()}: ") and field in msg
    assert __import__("re").search(valid, msg), msg
    # the same file named by a job: refused at the job's line, the mount's error quoted
    job = tmp_path / "job.yaml"
    job.write_text(
        (ROOT / "tasks" / "bins_ur3.yaml")
        .read_text()
        .replace("robot: ur3", "mount: my_arm/mount.yaml")
    )
    with pytest.raises(JobError, match=r"job.yaml, line 7, cell.mount: the arm's mount file"):
        load_job(job)


def test_a_wrong_mount_in_a_job_is_a_named_error_on_the_command_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from tests.cli_exit import cell_exit

    _copy_mount(tmp_path, edit=lambda s: s.replace("flange: tool0", "flange: tool9"))
    job = tmp_path / "job.yaml"
    job.write_text(_job_on("ur3").replace("robot: ur3", "mount: my_arm/mount.yaml"))
    monkeypatch.chdir(tmp_path)
    capsys.readouterr()
    code = cell_exit(["run", str(job), "--no-log"])  # in this process, as `python -m cell`
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("cell: error: ") and "Traceback" not in err
    assert "field 'flange': 'tool9' is not a link of ur3_robot.urdf" in err


def test_the_demo_on_the_ur3_is_refused_up_front_the_station_out_of_reach() -> None:
    with pytest.raises(JobError) as err:
        parse_job(_job_on("ur3"), "bins_ur3.yaml")
    msg = str(err.value)
    assert "bins_ur3.yaml, line 9, pick_station.position_m: the ur3 arm does not reach" in msg
    # the reach it states: the grip pointing down at the station's height, by IK
    reach = float(__import__("re").search(r"reaches about ([\d.]+) m out", msg).group(1))
    assert 0.4 < reach < math.hypot(0.45, -0.40)
    # the same job on the arms that reach it passes
    for robot in ("panda", "ur5", "ur10"):
        parse_job(_job_on(robot), f"bins_{robot}.yaml")


def test_every_error_of_a_job_is_in_one_report() -> None:
    text = _job_on("ur3").replace("name: warehouse demo", "nmae: warehouse demo")
    text = text.replace("size_m: [0.30, 0.30], rim_height_m: 0.12}", "size_m: [0.30, 0.30]}", 1)
    text = text.replace("{object: cyl50,", "{object: cyl51,")
    with pytest.raises(JobError) as err:
        parse_job(text, "j.yaml")
    lines = str(err.value).splitlines()
    assert lines[0] == "j.yaml: 4 errors:"
    assert any("unknown key 'nmae'" in ln for ln in lines)
    assert any("bins[0]: missing 'rim_height_m'" in ln for ln in lines)
    assert any("items[1].object: unknown catalogue id 'cyl51'" in ln for ln in lines)
    assert any("pick_station.position_m: the ur3 arm does not reach" in ln for ln in lines)
    assert all(ln.startswith("j.yaml, line ") for ln in lines[1:])


def test_a_bin_under_the_station_and_a_place_out_of_reach_are_refused() -> None:
    under = BINS.replace("position_m: [0.55, 0.30]", "position_m: [0.45, -0.15]")
    with pytest.raises(JobError, match=r"line 11, bins\[0\].position_m: bin 'tote_a' .* is under"):
        parse_job(under, "j.yaml")
    # policy place: every bin is placed into; the chutes 1.4-2.9 m out are beyond the arm
    with pytest.raises(JobError) as err:
        parse_job(BINS.replace("policy: auto", "policy: place"), "j.yaml")
    lines = str(err.value).splitlines()
    assert lines[0] == "j.yaml: 3 errors:"
    for i, chute in ((2, "chute_1"), (3, "chute_2"), (4, "chute_3")):
        assert any(
            f"bins[{i}].position_m: the panda arm cannot place into bin '{chute}'" in ln
            for ln in lines
        )
    # the UR3 under auto with the default place reach (0.75 m) would place into a bin it
    # cannot reach: it throws into it instead, with a warning saying why (how far the place
    # is missed); under policy: place the same bin is refused
    ur3 = (ROOT / "tasks" / "bins_ur3.yaml").read_text()
    far_tote = ur3.replace("[0.00, -0.42]", "[0.00, -0.70]").replace(
        "place_reach_m: 0.5", "place_reach_m: 0.75"
    )
    job = parse_job(far_tote, "j.yaml")
    (warning,) = job.warnings
    assert re.search(r"cannot place into bin 'tote_b'.*out of reach \(missed by \d+ mm", warning)
    assert warning.endswith("to have them placed, move the bin closer")
    assert job.thrown_bins == frozenset({"tote_b"})
    with pytest.raises(JobError, match=r"cannot place into bin 'tote_b'"):
        parse_job(far_tote.replace("policy: auto", "policy: place"), "j.yaml")


def test_max_items_below_the_items_listed_warns_how_many_are_left() -> None:
    job = parse_job(
        BINS.replace("item_time_limit_s: 20}", "item_time_limit_s: 20, max_items: 20}"), "j.yaml"
    )
    assert len(job.expanded_items()) == 20
    assert job.warnings == (
        "j.yaml: limits.max_items is 20 and the job lists 24 items: the first 20 are sorted, "
        "4 are left unsorted",
    )
    assert parse_job(BINS, "j.yaml").warnings == ()


def _sort(text: str, path: str):
    from cell.orchestrator import Orchestrator

    orch = Orchestrator(parse_job(text, path))
    try:
        return orch.run()
    finally:
        orch.close()


def test_the_ur10_sorts_the_demos_kinds_into_their_bins() -> None:
    """A throw to each chute and a place into a tote, on the UR10 (the whole demo: the
    figure the report gives, `cell run` on tasks/bins.yaml with robot: ur10)."""
    text = _job_on("ur10")
    head = text.split("items:")[0]
    items = (
        "items:\n  - {object: cube50, bin: chute_1}\n  - {object: sphere40, bin: chute_3}\n"
        "  - {object: cuboid_c, bin: tote_a}\n"
    )
    tail = "policy: auto\nseed: 0\nlimits: {place_reach_m: 0.75, item_time_limit_s: 20}\n"
    s = _sort(head + items + tail, "bins_ur10.yaml")
    assert (s.items, s.placed, s.thrown) == (3, 1, 2)
    assert s.in_bin == 3, [(r.target, r.landed_in, r.failure) for r in s.results]


def test_the_ur3_sorts_a_job_laid_out_within_its_reach() -> None:
    """tasks/bins_ur3.yaml's first items (a throw to the near chute, a place): in their bins."""
    text = (ROOT / "tasks" / "bins_ur3.yaml").read_text()
    head = text.split("items:")[0]
    items = "items:\n  - {object: cube50, bin: chute_1}\n  - {object: cyl70, bin: tote_b}\n"
    tail = "policy: auto\nseed: 0\nlimits: {place_reach_m: 0.5, item_time_limit_s: 20}\n"
    s = _sort(head + items + tail, "bins_ur3.yaml")
    assert (s.items, s.placed, s.thrown) == (2, 1, 1)
    assert s.in_bin == 2, [(r.target, r.landed_in, r.failure) for r in s.results]


def test_every_item_a_run_cannot_sort_is_in_one_report() -> None:
    """The planner's checks before a run (an item the pads cannot hold, a bin beyond every
    throw) name every such item at its line, not the first alone."""
    from cell.orchestrator import Orchestrator

    text = (
        "bins:\n  - {id: moon, position_m: [6.0, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.1}\n"
        "items:\n  - {object: cube50, bin: moon}\n  - {object: cyl50, bin: moon}\n"
        "policy: throw\n"
    )
    with pytest.raises(JobError) as err:
        Orchestrator(parse_job(text, "moon.yaml"))
    lines = str(err.value).splitlines()
    assert lines[0] == "moon.yaml: 2 errors:"
    assert lines[1].startswith("moon.yaml, line 4: item cube50 to bin 'moon'")
    assert lines[2].startswith("moon.yaml, line 5: item cyl50 to bin 'moon'")
