"""Arm + throwing end-effector: the composite URDF, generated at run time.

A mount (`robots/<arm>_throwing/mount.yaml`) names the arm's URDF in example-robot-data,
its flange link and the end-effector's pose on the flange. The composite is the arm's URDF
with everything below the flange removed (the Panda's own hand), the end-effector's links
and joints appended, a fixed joint `ee_mount_joint` from the flange to `ee_base`, and every
`package://example-robot-data/` mesh URI rewritten to an absolute path, so that Pinocchio
and PyBullet both load it without a package search path.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import yaml

from cell.errors import InvalidInput, InvalidParameter
from cell.kinds import ROBOTS
from cell.robot.paths import example_robot_data_dir, example_robot_data_share, robots_dir

__all__ = [
    "EE_URDF",
    "MOUNTS",
    "MountSpec",
    "cache_dir",
    "composite_urdf",
    "composite_urdf_text",
    "end_effector_urdf",
    "load_mount",
]

MOUNTS: dict[str, str] = {name: f"{name}_throwing" for name in ROBOTS}
"""Robot name -> mount folder under robots/."""

EE_URDF = Path("throwing_ee", "throwing_ee.urdf")
"""The end-effector's URDF, relative to robots/."""

_PKG = "package://example-robot-data/"


@dataclass(frozen=True)
class MountSpec:
    """One arm with the end-effector on its flange (the contents of a mount.yaml).

    Attributes:
        name: the robot name ("panda", "ur5").
        folder: the mount folder under robots/.
        arm_urdf: the arm's URDF, relative to example-robot-data's robots/ folder.
        flange: the arm link the end-effector is bolted to.
        drop_below_flange: remove the links downstream of the flange (the arm's own tool).
        end_effector: the end-effector's URDF, relative to robots/.
        mount_xyz: ee_base origin in the flange frame [m].
        mount_rpy: ee_base roll, pitch, yaw in the flange frame [rad].
        arm_joints: the arm's actuated joints, base to flange.
        home: the home configuration [rad], one value per arm joint.
        acceleration_limits: joint acceleration limits [rad/s²], one per arm joint.
        jerk_limits: joint jerk limits [rad/s³], one per arm joint.
    """

    name: str
    folder: str
    arm_urdf: str
    flange: str
    drop_below_flange: bool
    end_effector: str
    mount_xyz: tuple[float, float, float]
    mount_rpy: tuple[float, float, float]
    arm_joints: tuple[str, ...]
    home: tuple[float, ...]
    acceleration_limits: tuple[float, ...]
    jerk_limits: tuple[float, ...]


def _robot_name(robot: str) -> str:
    if robot not in MOUNTS:
        raise InvalidInput(f"unknown robot {robot!r}; valid: {', '.join(sorted(MOUNTS))}")
    return robot


def load_mount(robot: str) -> MountSpec:
    """The mount description of a robot, read from robots/<folder>/mount.yaml.

    Args:
        robot: "panda" or "ur5".

    Returns:
        The validated MountSpec.

    Raises:
        InvalidInput: unknown robot name.
        InvalidParameter: the mount file is missing a field or has a bad value.
    """
    folder = MOUNTS[_robot_name(robot)]
    path = robots_dir() / folder / "mount.yaml"
    try:
        raw = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise InvalidParameter(f"{path}: cannot read the mount file ({exc})") from None
    fields = (
        "arm_urdf",
        "arm_joints",
        "flange",
        "end_effector",
        "mount_xyz",
        "mount_rpy",
        "home",
        "acceleration_limits",
        "jerk_limits",
    )
    missing = [f for f in fields if not isinstance(raw, dict) or f not in raw]
    if missing:
        raise InvalidParameter(f"{path}: missing field(s) {missing}; required: {list(fields)}")
    vec: dict[str, tuple[float, float, float]] = {}
    for key in ("mount_xyz", "mount_rpy"):
        v = raw[key]
        if not isinstance(v, list) or len(v) != 3:
            raise InvalidParameter(f"{path}: field '{key}' must be a list of 3 numbers, got {v!r}")
        vec[key] = (float(v[0]), float(v[1]), float(v[2]))
    joints = raw["arm_joints"]
    if not isinstance(joints, list) or not joints or not all(isinstance(j, str) for j in joints):
        raise InvalidParameter(f"{path}: field 'arm_joints' must be a list of joint names")
    per_joint: dict[str, tuple[float, ...]] = {}
    for key in ("home", "acceleration_limits", "jerk_limits"):
        v = raw[key]
        try:
            vals = tuple(float(x) for x in v)
        except (TypeError, ValueError):
            vals = ()
        if len(vals) != len(joints) or not all(math.isfinite(x) for x in vals):
            raise InvalidParameter(
                f"{path}: field '{key}' must be {len(joints)} finite numbers (one per arm "
                f"joint), got {v!r}"
            )
        if key != "home" and min(vals) <= 0.0:
            raise InvalidParameter(f"{path}: field '{key}' must be positive, got {v!r}")
        per_joint[key] = vals
    return MountSpec(
        name=robot,
        folder=folder,
        arm_urdf=str(raw["arm_urdf"]),
        flange=str(raw["flange"]),
        drop_below_flange=bool(raw.get("drop_below_flange", True)),
        end_effector=str(raw["end_effector"]),
        mount_xyz=vec["mount_xyz"],
        mount_rpy=vec["mount_rpy"],
        arm_joints=tuple(joints),
        home=per_joint["home"],
        acceleration_limits=per_joint["acceleration_limits"],
        jerk_limits=per_joint["jerk_limits"],
    )


def end_effector_urdf() -> Path:
    """The end-effector's own URDF file (primitives only, loads stand-alone).

    Returns:
        Absolute path of robots/throwing_ee/throwing_ee.urdf.
    """
    return robots_dir() / EE_URDF


def _descendants(root: ET.Element, link: str) -> tuple[set[str], set[str]]:
    """Links strictly below `link` and the joints leading to them."""
    children: dict[str, list[tuple[str, str]]] = {}
    for j in root.findall("joint"):
        parent = j.find("parent")
        child = j.find("child")
        if parent is None or child is None:
            continue
        children.setdefault(parent.get("link", ""), []).append(
            (j.get("name", ""), child.get("link", ""))
        )
    links: set[str] = set()
    joints: set[str] = set()
    stack = [link]
    while stack:
        for jname, cname in children.get(stack.pop(), []):
            joints.add(jname)
            links.add(cname)
            stack.append(cname)
    return links, joints


def composite_urdf_text(robot: str) -> str:
    """The composite URDF (arm + end-effector) as text.

    Args:
        robot: "panda" or "ur5".

    Returns:
        URDF XML with absolute mesh paths.

    Raises:
        InvalidInput: unknown robot.
        InvalidParameter: the flange link is not in the arm's URDF.
        MissingDependency: example-robot-data or robots/ is missing.
    """
    spec = load_mount(robot)
    arm_path = example_robot_data_dir() / spec.arm_urdf
    if not arm_path.is_file():
        raise InvalidParameter(
            f"{robots_dir() / spec.folder / 'mount.yaml'}: arm_urdf {spec.arm_urdf!r} "
            f"not found under {example_robot_data_dir()}"
        )
    arm = ET.parse(arm_path).getroot()
    ee = ET.parse(robots_dir() / spec.end_effector).getroot()
    link_names = {lk.get("name") for lk in arm.findall("link")}
    if spec.flange not in link_names:
        raise InvalidParameter(
            f"mount '{spec.folder}': flange link {spec.flange!r} is not in {arm_path.name}"
        )
    if spec.drop_below_flange:
        drop_links, drop_joints = _descendants(arm, spec.flange)
        for el in list(arm):
            if (el.tag == "link" and el.get("name") in drop_links) or (
                el.tag == "joint" and el.get("name") in drop_joints
            ):
                arm.remove(el)
    # Transmissions and simulator plug-ins are for ROS controllers; neither loader needs them.
    for el in list(arm):
        if el.tag in ("transmission", "gazebo"):
            arm.remove(el)
    share = example_robot_data_share()
    for mesh in arm.iter("mesh"):
        fn = mesh.get("filename", "")
        if fn.startswith(_PKG):
            mesh.set("filename", str(share / "example-robot-data" / fn[len(_PKG) :]))
    arm_materials = {m.get("name") for m in arm.findall("material")}
    for el in ee:
        if el.tag == "material" and el.get("name") in arm_materials:
            continue
        arm.append(el)
    mount = ET.SubElement(arm, "joint", {"name": "ee_mount_joint", "type": "fixed"})
    ET.SubElement(mount, "parent", {"link": spec.flange})
    ET.SubElement(mount, "child", {"link": "ee_base"})
    ET.SubElement(
        mount,
        "origin",
        {
            "xyz": " ".join(repr(v) for v in spec.mount_xyz),
            "rpy": " ".join(repr(v) for v in spec.mount_rpy),
        },
    )
    arm.set("name", spec.folder)
    ET.indent(arm, space="  ")
    header = (
        f"<!-- Generated by cell.robot.composite from {spec.arm_urdf} (example-robot-data) and "
        f"{spec.end_effector}; do not edit. -->\n"
    )
    return '<?xml version="1.0"?>\n' + header + ET.tostring(arm, encoding="unicode") + "\n"


def cache_dir() -> Path:
    """A writable folder for generated descriptions.

    `$CELL_CACHE_DIR`, else `$XDG_CACHE_HOME/cell` (`~/.cache/cell`), else the temp folder.

    Returns:
        An existing folder `<cache>/robots`.
    """
    env = os.environ.get("CELL_CACHE_DIR")
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    candidates = [Path(env)] if env else []
    candidates += [Path(xdg) / "cell", Path(tempfile.gettempdir()) / f"cell-{os.getuid()}"]
    for base in candidates:
        d = base / "robots"
        try:
            d.mkdir(parents=True, exist_ok=True)
        except OSError:
            continue
        if os.access(d, os.W_OK):
            return d
    raise InvalidParameter(f"no writable cache folder among {[str(c) for c in candidates]}")


def composite_urdf(robot: str) -> Path:
    """Write (if changed) and return the composite URDF of an arm with the end-effector.

    The file is `<cache>/robots/<robot>_throwing-<hash of its content>.urdf`, written
    atomically when missing, so concurrent processes (of any version) may call this freely.

    Args:
        robot: "panda" or "ur5".

    Returns:
        Path of the URDF; load it with Pinocchio or PyBullet directly.

    Raises:
        InvalidInput: unknown robot.
        MissingDependency: example-robot-data or robots/ is missing.
    """
    text = composite_urdf_text(robot)
    # named by its content: processes of different versions (or descriptions) never load
    # each other's file while one of them rewrites it
    digest = hashlib.sha256(text.encode()).hexdigest()[:12]
    path = cache_dir() / f"{MOUNTS[robot]}-{digest}.urdf"
    try:
        if path.read_text() == text:
            return path
    except OSError:
        pass
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem, suffix=".tmp")
    with os.fdopen(fd, "w") as fh:
        fh.write(text)
    os.replace(tmp, path)
    return path
