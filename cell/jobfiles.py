"""The files a sort job reads besides itself: the parameter file, learned model and
Dynamixel configuration its `cell` section names, and its arm's mount file with the two
URDFs that file names. `cell run` refuses an output that is one of them
(`cell.cli.guard.refuse_outputs_among`): a file asked to read is never written."""

from __future__ import annotations

from typing import Any

__all__ = ["job_files"]


def job_files(job: Any) -> list[tuple[str, str]]:
    """(what it is, path) of every file `job` (a `cell.jobs.Job`) reads besides itself."""
    from cell.robot.mount import is_mount_path, load_mount
    from cell.robot.mount_paths import arm_urdf_file, end_effector_file

    what = {
        "params": "parameter file",
        "residual": "learned model",
        "ee_config": "Dynamixel configuration",
    }
    out = [
        (f"the {what[key]} this run reads (cell.{key} of {job.path})", getattr(job, key))
        for key in ("params", "residual", "ee_config")
        if getattr(job, key)
    ]
    spec = load_mount(job.robot)
    named = (
        f"cell.mount of {job.path}"
        if is_mount_path(job.robot)
        else f"cell.robot {job.robot!r} of {job.path}"
    )
    out.append((f"the mount file this run reads ({named})", spec.path))
    out.append((f"the arm's URDF this run reads (its arm_urdf, {named})", str(arm_urdf_file(spec))))
    out.append((f"the end-effector's URDF this run reads ({named})", str(end_effector_file(spec))))
    return out
