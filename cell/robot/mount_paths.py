"""Where a mount file's URDFs are: `arm_urdf` and `end_effector` relative to their library
folders (example-robot-data's `robots/`, the cell's `robots/`) as the shipped mounts name
them, else to the mount file's own folder (a URDF of the user's own kept beside it), or
absolute (docs/arms.md)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from cell.errors import InvalidParameter
from cell.robot.paths import example_robot_data_dir, robots_dir

if TYPE_CHECKING:
    from cell.robot.mount import MountSpec

__all__ = ["arm_urdf_file", "end_effector_file"]


def _urdf_file(spec: MountSpec, field: str, library: Path, hint: str) -> Path:
    """The file a mount's URDF field names: an absolute path as it is; a relative one under
    the library folder (example-robot-data's robots/ for the arm, the cell's robots/ for
    the end-effector; no `..` there), else from the mount file's own folder (a URDF of the
    user's own kept beside it).

    Raises:
        InvalidParameter: no such file, naming the field and the places looked in.
    """
    given = getattr(spec, field)
    own = Path(spec.path).parent
    if Path(given).is_absolute():
        looked = [Path(given)]
    else:
        looked = [library / given] if ".." not in Path(given).parts else []
        looked.append(own / given)
    for path in looked:
        if path.is_file():
            return path
    places = " or ".join(str(p) for p in looked)
    raise InvalidParameter(
        f"{spec.path}: field '{field}': {given!r} is not a file ({places}); give a "
        f"path relative to {library}, to the mount file's folder, or an absolute one{hint}"
    )


def arm_urdf_file(spec: MountSpec) -> Path:
    """The arm's URDF: `arm_urdf` under example-robot-data's robots/ folder, else from the
    mount file's folder, or absolute (`_urdf_file`)."""
    return _urdf_file(spec, "arm_urdf", example_robot_data_dir(), "")


def end_effector_file(spec: MountSpec) -> Path:
    """The end-effector's URDF: `end_effector` under the cell's robots/ folder, else from
    the mount file's folder, or absolute (`_urdf_file`)."""
    hint = " (the throwing end-effector is throwing_ee/throwing_ee.urdf)"
    return _urdf_file(spec, "end_effector", robots_dir(), hint)
