"""The `cell` section of a sort job: the platform and its settings, the arm (a name under
robots/ or a mount file, `cell.robot.mount`), the end-effector back-end and the files they
read (`cell.jobs.parse_job` calls `cell_section`)."""

from __future__ import annotations

import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cell.jobschema import BASE_SPEED_MAX_MPS, CELL_KEYS, DRONE_KEYS, MOBILE_KEYS
from cell.kinds import EE_BACKENDS, PLATFORMS
from cell.yamltree import Checker, Node, nearest, shown

__all__ = ["CellSpec", "cell_section"]


@dataclass(frozen=True)
class CellSpec:
    """The `cell` section, validated: robot, end-effector, files and platform."""

    robot: str
    ee: str
    ee_config: str
    params: str
    residual: str
    platform: str
    hover_height_m: float
    rotor_rpm: float
    base_speed_mps: float


def _platform(c: Checker, cell: dict[str, Node]) -> tuple[str, float, float, float]:
    """The platform and its settings.

    Returns:
        (platform, hover height [m], rotor speed [rpm], base speed [m/s]); the drone's
        and the mobile base's settings keep their defaults on other platforms.
    """
    platform = c.text(cell["platform"], "cell.platform", PLATFORMS) if "platform" in cell else "arm"
    drone = _platform_section(c, cell, platform, "drone", DRONE_KEYS)
    hover = _setting(c, drone, "cell.drone.hover_height_m", 2.0, 0.5, 10.0)
    rpm = _setting(c, drone, "cell.drone.rotor_rpm", 0.0, 0.0, 30000.0)
    mobile = _platform_section(c, cell, platform, "mobile", MOBILE_KEYS)
    speed = _setting(c, mobile, "cell.mobile.speed_mps", 0.0, 0.0, BASE_SPEED_MAX_MPS)
    return platform, hover, rpm, speed


def _platform_section(
    c: Checker, cell: dict[str, Node], platform: str, name: str, keys: Any
) -> dict[str, Node]:
    """The section `cell.<name>` of a platform's settings, known keys only ({} when absent);
    JobError when it is given for another platform."""
    if name not in cell:
        return {}
    if platform != name:
        raise c.fail(cell[name], f"cell.{name}", f"only for platform: {name}")
    return c.mapping(cell[name], f"cell.{name}", dict.fromkeys(keys, ""))


def _setting(
    c: Checker, sec: dict[str, Node], path: str, default: float, lo: float, hi: float
) -> float:
    """The number at `path` (cell.<section>.<key>) within [lo, hi]; `default` when absent."""
    key = path.rsplit(".", 1)[1]
    return c.number(sec[key], path, lo=lo, hi=hi) if key in sec else default


def _cell_file(c: Checker, cell: dict[str, Node], key: str, base: Path) -> str:
    """The file a `cell` key names, as given if it exists, else relative to the job's folder
    ("" when the key is absent).

    Raises:
        JobError: the file exists in neither place.
    """
    if key not in cell:
        return ""
    p = Path(c.text(cell[key], f"cell.{key}"))
    full = p if p.is_absolute() or p.exists() else base / p
    if not full.exists():
        raise c.fail(
            cell[key],
            f"cell.{key}",
            f"file {p} does not exist (relative to the current folder or to {base})",
        )
    _regular(c, cell[key], f"cell.{key}", full)
    return str(full)


def _regular(c: Checker, node: Node, fp: str, full: Path) -> None:
    """JobError when the path that exists is not a regular file (a folder, a device, a
    FIFO), said as such: told from `os.stat` alone, nothing opened."""
    from cell.infile import kind_of

    mode = full.stat().st_mode
    if not stat.S_ISREG(mode):
        raise c.fail(node, fp, f"{full} is {kind_of(mode)}; give a file")


def _robot(c: Checker, cell: dict[str, Node], base: Path) -> str:
    """The arm: `robot` names one under robots/ (default panda), `mount` a mount file
    (relative to the job's folder, else as given); either is checked whole (its fields,
    and against the arm's URDF), the mount file's own error quoted.

    Returns:
        The arm's name, or the mount file's absolute path (`cell.robot.mount`).
    """
    from cell.robot.mount import check_against_urdf, load_mount, mount_files

    if "robot" in cell and "mount" in cell:
        raise c.fail(cell["mount"], "cell.mount", "give robot (a name) or mount (a file), not both")
    for key, one in (("robot", "name"), ("mount", "mount file")):
        given = cell[key].value if key in cell else None
        if isinstance(given, list):  # `robot: [panda, ur5]`: two arms
            raise c.fail(
                cell[key],
                f"cell.{key}",
                f"a list of {len(given)} ({shown(given)}): a job runs one arm, its base at "
                f"the world frame's origin, from which every position of the job is "
                f"measured; give one {one}, and sort with another arm in a job of its own",
            )
    if "mount" in cell:
        node, fp = cell["mount"], "cell.mount"
        p = Path(c.text(node, fp)).expanduser()
        full = p if p.is_absolute() else base / p
        if not full.exists():
            raise c.fail(node, fp, f"mount file {p} does not exist (relative to {base})")
        _regular(c, node, fp, full)
        ref = str(full.resolve())
    else:
        node, fp = cell.get("robot", Node("panda", 0)), "cell.robot"
        ref = c.text(node, fp)
        try:
            names = mount_files()
        except ValueError as exc:
            raise c.fail(node, fp, str(exc)) from None
        if ref not in names:
            raise c.fail(
                node,
                fp,
                f"{ref!r} is not an arm under robots/{nearest(ref, names)}; choose one of "
                f"{', '.join(sorted(names))} or give cell.mount, a mount file (docs/arms.md)",
            )
    try:
        check_against_urdf(load_mount(ref))
    except ValueError as exc:  # InvalidParameter: a wrong mount file, named
        raise c.fail(node, fp, f"the arm's mount file is not valid: {exc}") from None
    from cell.robot.home import home_problem

    why = home_problem(ref)
    if why:
        raise c.fail(node, fp, f"the arm's mount file is not valid: {why}")
    return ref


def cell_section(c: Checker, top: dict[str, Node], tree: Node, path: str) -> CellSpec:
    """The `cell` section: platform, robot, end-effector back-end and the files they read."""
    cell = c.mapping(top["cell"], "cell", dict.fromkeys(CELL_KEYS, "")) if "cell" in top else {}
    platform, hover, rpm, speed = _platform(c, cell)
    robot = _robot(c, cell, Path(path).parent if path != "<job>" else Path("."))
    ee = c.text(cell["ee"], "cell.ee", EE_BACKENDS) if "ee" in cell else "pybullet"
    base = Path(path).parent if path != "<job>" else Path(".")
    ee_config = _cell_file(c, cell, "ee_config", base)
    params = _cell_file(c, cell, "params", base)
    residual = _cell_file(c, cell, "residual", base)
    if ee == "dynamixel" and not ee_config:
        raise c.fail(
            cell.get("ee", tree),
            "cell.ee_config",
            "the dynamixel back-end needs ee_config (e.g. robots/throwing_ee/dynamixel.yaml)",
        )
    return CellSpec(robot, ee, ee_config, params, residual, platform, hover, rpm, speed)
