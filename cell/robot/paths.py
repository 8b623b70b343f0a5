"""Where the robot descriptions live: the cell's `robots/` folder and example-robot-data.

example-robot-data 6.x ships no Python module, only data under
`<site-packages>/cmeel.prefix/share/example-robot-data/robots/`; this module finds that
folder without importing anything from it.
"""

from __future__ import annotations

import os
import site
import sys
from functools import lru_cache
from pathlib import Path

from cell.errors import MissingDependency

__all__ = [
    "ERD_ENV",
    "ROBOTS_ENV",
    "example_robot_data_dir",
    "example_robot_data_share",
    "robots_dir",
]

ERD_ENV = "CELL_EXAMPLE_ROBOT_DATA"
"""Environment variable that may point at example-robot-data's `robots/` folder."""

ROBOTS_ENV = "CELL_ROBOTS_DIR"
"""Environment variable that may point at the cell's `robots/` folder."""

_ERD_SUBDIR = Path("cmeel.prefix", "share", "example-robot-data", "robots")


def _candidate_roots() -> list[Path]:
    roots: list[Path] = []
    try:
        from importlib.metadata import PackageNotFoundError, distribution

        try:
            roots.append(Path(str(distribution("example-robot-data").locate_file(""))))
        except PackageNotFoundError:
            pass
    except ImportError:  # pragma: no cover - stdlib always has it on 3.11
        pass
    try:
        roots.extend(Path(p) for p in site.getsitepackages())
    except AttributeError:  # pragma: no cover - some virtualenv site modules lack it
        pass
    roots.append(Path(site.getusersitepackages()))
    roots.extend(Path(p) for p in sys.path if p)
    return roots


@lru_cache(maxsize=1)
def example_robot_data_dir() -> Path:
    """The `robots/` folder of example-robot-data (holds panda_description, ur_description …).

    Looks at `$CELL_EXAMPLE_ROBOT_DATA` first, then under the installed distribution and every
    site-packages folder for `cmeel.prefix/share/example-robot-data/robots`.

    Returns:
        The absolute folder path.

    Raises:
        MissingDependency: the folder is nowhere to be found.
    """
    env = os.environ.get(ERD_ENV)
    if env:
        p = Path(env).expanduser()
        if (p / "panda_description").is_dir():
            return p.resolve()
        raise MissingDependency(
            f"${ERD_ENV}={env!r} is not example-robot-data's robots/ folder "
            "(it must contain panda_description/)"
        )
    seen: set[Path] = set()
    for root in _candidate_roots():
        cand = root / _ERD_SUBDIR
        if cand in seen:
            continue
        seen.add(cand)
        if (cand / "panda_description").is_dir():
            return cand.resolve()
    raise MissingDependency(
        "example-robot-data not found: no cmeel.prefix/share/example-robot-data/robots/ in "
        "site-packages. Install it with `pip install 'example-robot-data>=6'` (or set "
        f"${ERD_ENV} to its robots/ folder)"
    )


def example_robot_data_share() -> Path:
    """The folder that `package://example-robot-data/...` URIs are relative to's parent.

    Returns:
        `<...>/cmeel.prefix/share` (contains `example-robot-data/`).
    """
    return example_robot_data_dir().parents[1]


@lru_cache(maxsize=1)
def robots_dir() -> Path:
    """The cell's `robots/` folder (end-effector URDF, mount descriptions).

    `$CELL_ROBOTS_DIR` wins; otherwise the folder next to the `cell` package (the
    repository root; the package is installed in editable mode).

    Returns:
        The absolute folder path.

    Raises:
        MissingDependency: the folder does not exist.
    """
    env = os.environ.get(ROBOTS_ENV)
    p = Path(env).expanduser() if env else Path(__file__).resolve().parents[2] / "robots"
    if not (p / "throwing_ee").is_dir():
        raise MissingDependency(
            f"the cell's robots/ folder was not found at {p} (expected throwing_ee/ inside); "
            f"install the cell from its repository (`pip install -e .`) or set ${ROBOTS_ENV}"
        )
    return p.resolve()
