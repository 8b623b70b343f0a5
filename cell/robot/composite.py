"""Arm + throwing end-effector: the composite URDF, generated at run time.

A mount file (`robots/<folder>/mount.yaml` or one a job names: `cell.robot.mount`) names the arm's URDF in example-robot-data,
its flange link and the end-effector's pose on the flange. The composite is the arm's URDF
with everything below the flange removed (the Panda's own hand), the end-effector's links
and joints appended, a fixed joint `ee_mount_joint` from the flange to `ee_base`, and every
mesh URI rewritten to an absolute path (a mesh that is not a file refused, naming its link),
so that Pinocchio and PyBullet both load it without a package search path. A continuous joint of the arm
becomes a revolute one over ±2π rad (`CONTINUOUS_RANGE_RAD`).
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

from cell.errors import InvalidParameter
from cell.outfile import write_whole
from cell.robot.mount import MountSpec, check_against_urdf, load_mount
from cell.robot.mount_paths import end_effector_file
from cell.robot.paths import example_robot_data_share, robots_dir

__all__ = [
    "EE_URDF",
    "MountSpec",
    "cache_dir",
    "composite_urdf",
    "composite_urdf_text",
    "end_effector_urdf",
    "load_mount",
]

EE_URDF = Path("throwing_ee", "throwing_ee.urdf")
"""The end-effector's URDF, relative to robots/."""


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


CONTINUOUS_RANGE_RAD = 2.0 * math.pi
"""A continuous joint of the arm is planned as a revolute one over [-2π, 2π] rad: every
angle twice, so a move may turn either way and unwind."""


def _bounded_continuous(arm: ET.Element, spec: MountSpec) -> None:
    """Make the arm's continuous joints revolute over ±CONTINUOUS_RANGE_RAD (the Kinova
    Jaco's joints 1, 4 and 6, say): Pinocchio gives a continuous joint two position values
    (cos, sin), and the planner, its IK and its time scaling take one angle per joint. The
    URDF's velocity and effort limits are kept.

    Raises:
        InvalidParameter: a continuous arm joint without a velocity limit in its URDF.
    """
    for joint in arm.findall("joint"):
        name = joint.get("name", "")
        if joint.get("type") != "continuous" or name not in spec.arm_joints:
            continue
        lim = joint.find("limit")
        if lim is None or lim.get("velocity") is None:
            raise InvalidParameter(
                f"{spec.path}: field 'arm_urdf': the continuous joint {name!r} of "
                f"{spec.arm_urdf} has no velocity limit (<limit velocity=...>), which the "
                "cell's time scaling needs"
            )
        joint.set("type", "revolute")
        lim.set("lower", repr(-CONTINUOUS_RANGE_RAD))
        lim.set("upper", repr(CONTINUOUS_RANGE_RAD))
        lim.set("effort", lim.get("effort", "0"))


def _mesh_path(uri: str, urdf_dir: Path) -> Path | None:
    """The file a mesh URI names: `package://example-robot-data/...` (TALOS' URDFs write
    `package:///example-robot-data/...`, the path after `package://` led by a slash) under
    example-robot-data's share folder, `file://` and absolute paths as they are, a relative
    path from the arm's URDF's folder `urdf_dir`; None for another package, which no loader
    here can find."""
    if uri.startswith("package://"):
        rest = uri[len("package://") :].lstrip("/")
        pkg, _, inside = rest.partition("/")
        if pkg != "example-robot-data":
            return None
        return example_robot_data_share() / "example-robot-data" / inside
    return urdf_dir / (uri[len("file://") :] if uri.startswith("file://") else uri)


def _absolute_meshes(arm: ET.Element, spec: MountSpec, urdf_dir: Path) -> None:
    """Rewrite every mesh of the kept arm to its absolute path, so that Pinocchio and
    PyBullet load the composite without a package search path.

    Raises:
        InvalidParameter: a mesh that is not a file (PyBullet refuses the whole URDF then,
            with no word of which), naming the link, the URI and where it was looked for.
    """
    for link in arm.findall("link"):
        for mesh in link.iter("mesh"):
            uri = mesh.get("filename", "")
            path = _mesh_path(uri, urdf_dir)
            if path is None or not path.is_file():
                raise InvalidParameter(
                    f"{spec.path}: field 'arm_urdf': link {link.get('name', '')!r} of "
                    f"{spec.arm_urdf} has the mesh {uri!r}, "
                    + (f"not a file at {path}" if path is not None else "of another package")
                    + "; the cell finds package://example-robot-data/ meshes, absolute "
                    "paths and paths from the arm's URDF's folder (drop_below_flange removes "
                    "the links below the flange)"
                )
            mesh.set("filename", str(path))


def composite_urdf_text(robot: str) -> str:
    """The composite URDF (arm + end-effector) as text.

    Args:
        robot: an arm's name under robots/ ("panda", "ur10") or a mount file's path.

    Returns:
        URDF XML with absolute mesh paths.

    Raises:
        InvalidInput: unknown robot.
        InvalidParameter: the flange link is not in the arm's URDF.
        MissingDependency: example-robot-data or robots/ is missing.
    """
    spec = load_mount(robot)
    arm_path, arm = check_against_urdf(spec)
    ee = ET.parse(end_effector_file(spec)).getroot()
    if spec.drop_below_flange:
        drop_links, drop_joints = _descendants(arm, spec.flange)
        for el in list(arm):
            if (el.tag == "link" and el.get("name") in drop_links) or (
                el.tag == "joint" and el.get("name") in drop_joints
            ):
                arm.remove(el)
    _bounded_continuous(arm, spec)
    # Transmissions and simulator plug-ins are for ROS controllers; neither loader needs them.
    for el in list(arm):
        if el.tag in ("transmission", "gazebo"):
            arm.remove(el)
    _absolute_meshes(arm, spec, arm_path.parent)
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
        f"<!-- Generated by cell.robot.composite from {spec.arm_urdf} and "
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
        robot: an arm's name under robots/ ("panda", "ur10") or a mount file's path.

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
    path = cache_dir() / f"{load_mount(robot).folder}-{digest}.urdf"
    try:
        if path.read_text() == text:
            return path
    except OSError:
        pass
    write_whole(path, lambda p: p.write_text(text))
    return path
