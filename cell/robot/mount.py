"""Mount files: the arms the cell knows, each described by one `mount.yaml`.

No list of arms is kept in the code: the arms are the mount files found under
`robots/*/mount.yaml` (each named by its `arm` field) and any mount file a job names
(`cell: {mount: path/to/mount.yaml}`). A robot is referred to by a *reference*: a name
(`"ur10"`, resolved by scanning robots/) or the path of a mount file. docs/arms.md says how
to add an arm; every field is checked here, and against the arm's URDF by
`check_against_urdf`, so that a wrong mount file is refused naming the file, the field and
what would be valid.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cell.errors import InvalidInput, InvalidParameter
from cell.robot.mount_paths import arm_urdf_file, end_effector_file
from cell.robot.paths import robots_dir
from cell.robot.urdf_scale import check_chain_scale

__all__ = [
    "MOUNT_FIELDS",
    "MountSpec",
    "check_against_urdf",
    "is_mount_path",
    "load_mount",
    "mount_files",
    "resolve_mount",
    "robot_names",
]

MOUNT_FILE = "mount.yaml"
REQUIRED = (
    "arm",
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
OPTIONAL = ("drop_below_flange", "facing_half_range_deg", "held_joints")
MOUNT_FIELDS = REQUIRED + OPTIONAL
"""Every field a mount file may hold (docs/arms.md describes each)."""
_NAME = re.compile(r"[a-z][a-z0-9_]{0,31}")
_MOVABLE = ("revolute", "continuous", "prismatic")
MAX_ACCELERATION = 1000.0  # [rad/s²] beyond any arm's motors: a typo (1e300)
MAX_JERK = 1.0e6  # [rad/s³]
# [rad/s²], [rad/s³] slower than any arm a cell could use: at 0.01 and 0.01 a UR5 took 58 s
# an item; at 1e-4 ruckig refused the moves (an error code its Python binding cannot name)
MIN_ACCELERATION = 0.1
MIN_JERK = 1.0


@dataclass(frozen=True)
class MountSpec:
    """One arm with the end-effector on its flange (the contents of a mount.yaml).

    Attributes:
        name: the arm's name (the file's `arm` field: "panda", "ur10").
        folder: the name of the folder that holds the mount file.
        path: the mount file, absolute.
        arm_urdf: the arm's URDF, relative to example-robot-data's robots/ folder, else to
            the mount file's folder, or absolute (`arm_urdf_file`).
        flange: the arm link the end-effector is bolted to.
        drop_below_flange: remove the links downstream of the flange (the arm's own tool).
        end_effector: the end-effector's URDF, relative to robots/, else to the mount
            file's folder, or absolute (`end_effector_file`).
        mount_xyz: ee_base origin in the flange frame [m].
        mount_rpy: ee_base roll, pitch, yaw in the flange frame [rad].
        arm_joints: the arm's actuated joints, base to flange.
        home: the home configuration [rad], one value per arm joint.
        acceleration_limits: joint acceleration limits [rad/s²], one per arm joint.
        jerk_limits: joint jerk limits [rad/s³], one per arm joint.
        facing_half_range_rad: half the range of azimuths about the base the arm may
            face a bin at [rad] (random layouts draw bins within it); π: all around.
        held_joints: (joint, position [rad or m]) of movable joints of the URDF that are
            not arm joints and are held at a position other than zero (a torso lift); every
            other joint not in `arm_joints` is held at zero.
    """

    name: str
    folder: str
    path: str
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
    facing_half_range_rad: float = math.pi
    held_joints: tuple[tuple[str, float], ...] = ()


def is_mount_path(ref: str) -> bool:
    """Whether a robot reference is a mount file's path (else it is an arm's name)."""
    return ref.endswith((".yaml", ".yml")) or "/" in ref or "\\" in ref


def _read(path: Path) -> dict[str, Any]:
    """A mount file's mapping (bounded, safe YAML); InvalidParameter naming the file."""
    from cell.yamlsafe import read_yaml_text, safe_load

    try:
        raw = safe_load(read_yaml_text(path, "mount file"), str(path))
    except InvalidInput as exc:
        raise InvalidParameter(str(exc)) from None
    if not isinstance(raw, dict):
        raise InvalidParameter(
            f"{path}: a mount file is a mapping with the fields {list(REQUIRED)}"
        )
    return raw


def mount_files() -> dict[str, Path]:
    """The arms under robots/: name (each file's `arm` field) -> its mount file.

    Raises:
        InvalidParameter: a mount file without a valid `arm` name, or two with the same.
    """
    out: dict[str, Path] = {}
    for path in sorted(robots_dir().glob(f"*/{MOUNT_FILE}")):
        name = _arm_name(_read(path), path)
        if name in out:
            raise InvalidParameter(
                f"{path}: field 'arm': {name!r} is also the arm of {out[name]}; "
                "give each mount file its own name"
            )
        out[name] = path
    return out


def robot_names() -> tuple[str, ...]:
    """The names of the arms under robots/, sorted."""
    return tuple(sorted(mount_files()))


def _as_written(raw: dict[str, Any], key: str, path: Path) -> str:
    """The job's words (`cell.yamltree.not_text`) for a text field YAML 1.1 read as a
    boolean, no value or a date (`arm: yes`, `flange: ~`): the value as written, what YAML
    made of it, and to quote it; "" for any other value."""
    import datetime

    import yaml

    from cell.yamlsafe import compose, read_yaml_text
    from cell.yamltree import not_text

    v = raw.get(key)
    if key not in raw or not (v is None or isinstance(v, (bool, datetime.date))):
        return ""
    root = compose(read_yaml_text(path, "mount file"))  # read again, for this message only
    written = [
        n.value
        for k, n in (root.value if isinstance(root, yaml.MappingNode) else ())
        if k.value == key and isinstance(n, yaml.ScalarNode) and not n.style
    ]
    return f"{path}: field '{key}': {not_text(v, written[0] if written else None)}"


def _arm_name(raw: dict[str, Any], path: Path) -> str:
    name = raw.get("arm")
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        rule = "lower-case letters, digits and _, starting with a letter, at most 32"
        said = _as_written(raw, "arm", path)
        raise InvalidParameter(
            f"{said} (the arm's name: {rule})"
            if said
            else f"{path}: field 'arm' must be the arm's name ({rule}), got {name!r}"
        )
    return name


def resolve_mount(ref: str) -> Path:
    """The mount file of a robot reference: a name under robots/, or a mount file's path.

    Raises:
        InvalidInput: an unknown name (naming the known ones) or a missing file.
    """
    if is_mount_path(ref):
        p = Path(ref).expanduser()
        if not p.is_file():
            raise InvalidInput(f"mount file {ref}: no such file")
        return p.resolve()
    files = mount_files()
    if ref not in files:
        raise InvalidInput(
            f"unknown robot {ref!r}; valid: {', '.join(sorted(files))} (the arms of "
            f"{robots_dir()}/*/{MOUNT_FILE}), or the path of a mount file"
        )
    return files[ref]


def _vector3(raw: dict[str, Any], key: str, path: Path) -> tuple[float, float, float]:
    v = raw[key]
    try:
        vals = tuple(float(x) for x in v) if isinstance(v, list) else ()
    except (TypeError, ValueError):
        vals = ()
    if len(vals) != 3 or not all(math.isfinite(x) and abs(x) <= 10.0 for x in vals):
        raise InvalidParameter(
            f"{path}: field '{key}' must be a list of 3 finite numbers (|x| ≤ 10), got {v!r}"
        )
    return (vals[0], vals[1], vals[2])


def _per_joint(raw: dict[str, Any], key: str, n: int, path: Path) -> tuple[float, ...]:
    v = raw[key]
    try:
        vals = tuple(float(x) for x in v) if isinstance(v, list) else ()
    except (TypeError, ValueError):
        vals = ()
    if len(vals) != n or not all(math.isfinite(x) for x in vals):
        raise InvalidParameter(
            f"{path}: field '{key}' must be {n} finite numbers (one per arm joint), got {v!r}"
        )
    top = {"acceleration_limits": MAX_ACCELERATION, "jerk_limits": MAX_JERK}.get(key)
    if top is not None and not all(0.0 < x <= top for x in vals):
        raise InvalidParameter(f"{path}: field '{key}' must be positive and ≤ {top:g}, got {v!r}")
    low = {"acceleration_limits": MIN_ACCELERATION, "jerk_limits": MIN_JERK}.get(key)
    if low is not None and not all(x >= low for x in vals):
        raise InvalidParameter(
            f"{path}: field '{key}' must be at least {low:g} per joint (slower than any arm "
            f"a cell could use: its moves would take minutes or fail), got {v!r}"
        )
    return vals


def _joints(raw: dict[str, Any], path: Path) -> tuple[str, ...]:
    joints = raw["arm_joints"]
    if (
        not isinstance(joints, list)
        or not 1 <= len(joints) <= 12
        or not all(isinstance(j, str) and j for j in joints)
        or len(set(joints)) != len(joints)
    ):
        raise InvalidParameter(
            f"{path}: field 'arm_joints' must be a list of 1 to 12 distinct joint names "
            f"(base to flange), got {joints!r}"
        )
    return tuple(joints)


def _text(raw: dict[str, Any], key: str, path: Path) -> str:
    v = raw[key]
    if not isinstance(v, str) or not v:
        said = _as_written(raw, key, path)
        raise InvalidParameter(said or f"{path}: field '{key}' must be a non-empty text, got {v!r}")
    return v


def _facing(raw: dict[str, Any], path: Path) -> float:
    v = raw.get("facing_half_range_deg", 180.0)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 10.0 <= v <= 180.0:
        raise InvalidParameter(
            f"{path}: field 'facing_half_range_deg' must be a number from 10 to 180 [deg], "
            f"got {v!r}"
        )
    return math.pi if v == 180.0 else math.radians(float(v))


def _held(
    raw: dict[str, Any], joints: tuple[str, ...], path: Path
) -> tuple[tuple[str, float], ...]:
    v = raw.get("held_joints", {})
    ok = isinstance(v, dict) and all(
        isinstance(k, str)
        and k
        and not isinstance(x, bool)
        and isinstance(x, (int, float))
        and math.isfinite(x)
        for k, x in v.items()
    )
    if not ok:
        raise InvalidParameter(
            f"{path}: field 'held_joints' must map joint names to positions [rad, or m for "
            f"a prismatic joint] (torso_lift_joint: 0.2), got {v!r}"
        )
    both = sorted(k for k in v if k in joints)
    if both:
        raise InvalidParameter(
            f"{path}: field 'held_joints': {both} are arm joints too; a joint is planned "
            "(arm_joints) or held (held_joints), not both"
        )
    return tuple((str(k), float(x)) for k, x in v.items())


def load_mount(ref: str) -> MountSpec:
    """The mount description of a robot, read from its mount file.

    Args:
        ref: an arm's name under robots/ ("panda", "ur10") or a mount file's path.

    Returns:
        The validated MountSpec (its fields; `check_against_urdf` checks it against the URDF).

    Raises:
        InvalidInput: unknown robot name or missing file.
        InvalidParameter: the mount file is missing a field or has a bad value (naming the
            file, the field and what would be valid).
    """
    path = resolve_mount(ref)
    raw = _read(path)
    unknown = sorted(str(k) for k in raw if k not in MOUNT_FIELDS)
    if unknown:
        raise InvalidParameter(
            f"{path}: unknown field(s) {unknown}; valid: {', '.join(MOUNT_FIELDS)}"
        )
    missing = [f for f in REQUIRED if f not in raw]
    if missing:
        raise InvalidParameter(f"{path}: missing field(s) {missing}; required: {list(REQUIRED)}")
    joints = _joints(raw, path)
    drop = raw.get("drop_below_flange", True)
    if not isinstance(drop, bool):
        raise InvalidParameter(f"{path}: field 'drop_below_flange' must be true or false")
    return MountSpec(
        name=_arm_name(raw, path),
        folder=path.parent.name,
        path=str(path),
        arm_urdf=_text(raw, "arm_urdf", path),
        flange=_text(raw, "flange", path),
        drop_below_flange=drop,
        end_effector=_text(raw, "end_effector", path),
        mount_xyz=_vector3(raw, "mount_xyz", path),
        mount_rpy=_vector3(raw, "mount_rpy", path),
        arm_joints=joints,
        home=_per_joint(raw, "home", len(joints), path),
        acceleration_limits=_per_joint(raw, "acceleration_limits", len(joints), path),
        jerk_limits=_per_joint(raw, "jerk_limits", len(joints), path),
        facing_half_range_rad=_facing(raw, path),
        held_joints=_held(raw, joints, path),
    )


def _chain(root: ET.Element, flange: str, where: str) -> list[ET.Element]:
    """The joints from the URDF's root link down to `flange`, base first.

    Raises:
        InvalidParameter: a link hanging from two joints, or joints in a loop (a URDF is a
            tree), named.
    """
    parent_joint: dict[str, ET.Element] = {}
    for j in root.findall("joint"):
        child = j.find("child")
        if child is not None:
            name = child.get("link", "")
            if name in parent_joint:
                raise InvalidParameter(
                    f"{where}: field 'arm_urdf': link {name!r} is the child of two joints, "
                    f"{parent_joint[name].get('name', '')!r} and {j.get('name', '')!r}; a URDF "
                    "is a tree, each link below one joint"
                )
            parent_joint[name] = j
    chain: list[ET.Element] = []
    seen = {flange}
    link = flange
    while link in parent_joint:
        j = parent_joint[link]
        chain.append(j)
        p = j.find("parent")
        link = p.get("link", "") if p is not None else ""
        if link in seen:
            loop = " -> ".join(repr(x.get("name", "")) for x in chain[::-1])
            raise InvalidParameter(
                f"{where}: field 'arm_urdf': its joints form a loop through link {link!r} "
                f"({loop}); a URDF is a tree with one root link"
            )
        seen.add(link)
    return chain[::-1]


def _check_limits(root: ET.Element, joints: tuple[str, ...], where: str) -> None:
    """InvalidParameter naming the joint when an arm joint of the URDF has no usable limits:
    a revolute or prismatic joint needs <limit> with lower < upper and a velocity > 0, a
    continuous one a velocity > 0, each a finite number (the planner reads them all)."""
    by_name = {j.get("name", ""): j for j in root.findall("joint")}
    for name in joints:
        j = by_name[name]
        kind = j.get("type", "")
        need = ("velocity",) if kind == "continuous" else ("lower", "upper", "velocity")
        lim = j.find("limit")
        what = f"{where}: field 'arm_urdf': joint {name!r} ({kind})"
        if lim is None:
            raise InvalidParameter(
                f"{what} has no <limit>; it needs one with {', '.join(need)} (rad, rad/s)"
            )
        vals = {}
        for k in need:
            try:
                vals[k] = float(lim.get(k, ""))
            except ValueError:
                vals[k] = math.nan
            if not math.isfinite(vals[k]):
                said = (
                    f"has no {k}" if lim.get(k) is None else f"{k}={lim.get(k)!r} is not a number"
                )
                raise InvalidParameter(
                    f"{what}: its <limit> {said}; it needs {', '.join(need)}, each a finite number"
                )
        if not vals["velocity"] > 0.0:
            raise InvalidParameter(f"{what}: its velocity limit {vals['velocity']} must be > 0")
        if kind != "continuous" and not vals["lower"] < vals["upper"]:
            locked = vals["lower"] == vals["upper"]  # a joint the URDF locks: held_joints
            held = f"; to hold it still, leave it out of arm_joints and give held_joints: {{{name}: {vals['lower']:g}}}"  # fmt: skip
            raise InvalidParameter(
                f"{what}: its position limits lower={vals['lower']} and upper={vals['upper']} "
                f"are the wrong way round or equal; lower must be under upper{held * locked}"
            )


def check_against_urdf(spec: MountSpec) -> tuple[Path, ET.Element]:
    """Check a mount against its arm's URDF: the file exists, the flange is one of its
    links, and the arm joints are the movable joints from the base to the flange, in order.

    Returns:
        (the arm's URDF file, its parsed root element).

    Raises:
        InvalidParameter: naming the mount file, the field and what would be valid.
    """
    where = spec.path
    arm_path = arm_urdf_file(spec)
    end_effector_file(spec)
    try:
        root = ET.parse(arm_path).getroot()
    except ET.ParseError as exc:
        raise InvalidParameter(
            f"{where}: field 'arm_urdf': {arm_path} is not XML ({exc})"
        ) from None
    links = [lk.get("name", "") for lk in root.findall("link")]
    if spec.flange not in links:
        raise InvalidParameter(
            f"{where}: field 'flange': {spec.flange!r} is not a link of {arm_path.name}; "
            f"its links: {', '.join(links)}"
        )
    movable = [j.get("name", "") for j in root.findall("joint") if j.get("type") in _MOVABLE]
    unknown = [j for j in spec.arm_joints if j not in movable]
    if unknown:
        raise InvalidParameter(
            f"{where}: field 'arm_joints': {unknown} are not movable joints of "
            f"{arm_path.name}; its movable joints: {', '.join(movable)}"
        )
    held = dict(spec.held_joints)
    unknown = [j for j in held if j not in movable]
    if unknown:
        raise InvalidParameter(
            f"{where}: field 'held_joints': {unknown} are not movable joints of "
            f"{arm_path.name}; its movable joints: {', '.join(movable)}"
        )
    joints = _chain(root, spec.flange, where)
    check_chain_scale(joints, where, arm_path.name)  # a URDF in millimetres
    chain = [j.get("name", "") for j in joints if j.get("type") in _MOVABLE]
    if [j for j in chain if j not in held] != list(spec.arm_joints):
        raise InvalidParameter(
            f"{where}: fields 'arm_joints' and 'flange': the movable joints from the base to "
            f"flange {spec.flange!r} are {chain}, not {list(spec.arm_joints)}; list those "
            "joints in order (or hold some still, held_joints), or name the link the tool "
            "is bolted to (below the last joint)"
        )
    _check_limits(root, spec.arm_joints, where)
    _check_home(spec, root)
    return arm_path, root


def _check_home(spec: MountSpec, root: ET.Element) -> None:
    """InvalidParameter naming the mount file when `home` or a held joint's position is
    outside a joint's position limits in the URDF (a continuous joint's are ±2π, as the
    cell plans it)."""
    joints = {j.get("name", ""): j for j in root.findall("joint")}
    pairs = [("home", n, q) for n, q in zip(spec.arm_joints, spec.home, strict=True)]
    pairs += [("held_joints", n, q) for n, q in spec.held_joints]
    for field, name, q in pairs:
        lim = joints[name].find("limit")
        if joints[name].get("type") == "continuous":
            lo, hi = -2.0 * math.pi, 2.0 * math.pi  # planned so: cell.robot.composite
        elif lim is None:
            continue
        else:
            lo, hi = float(lim.get("lower", "0")), float(lim.get("upper", "0"))
        if not lo - 1e-9 <= q <= hi + 1e-9:
            raise InvalidParameter(
                f"{spec.path}: field '{field}': {q} for {name} is outside its range "
                f"[{lo}, {hi}] (rad, or m if prismatic) in {spec.arm_urdf}"
            )
