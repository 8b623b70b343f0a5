"""The sort job's schema: the keys each section of a job file may hold (`cell.jobs` parses
them), and `job_keys`, every key as a dotted path, which the job-format page (docs/jobs.md)
documents and a test compares with that page."""

from __future__ import annotations

from cell.model.objects import SHAPES

__all__ = [
    "BIN_KEYS",
    "CELL_KEYS",
    "DRONE_KEYS",
    "ITEM_KEYS",
    "LIMIT_KEYS",
    "MOBILE_KEYS",
    "PICK_KEYS",
    "TOP_KEYS",
    "job_keys",
    "BIN_WALL_M",
    "BASE_SPEED_MAX_MPS",
    "PLACE_REACH_M",
]

# [m] a bin's wall and floor plate (the scene builds it so, `cell.sim.bins.BinSpec.wall`):
# a rim must stand above it
BIN_WALL_M = 0.01
# [m] limits.place_reach_m where a job gives none: `auto` places into a bin this near the base
PLACE_REACH_M = 0.75
# [m/s] the moving base's velocity limit (`cell.platforms.mobile.BaseLimits.velocity_mps`)
BASE_SPEED_MAX_MPS = 1.5

TOP_KEYS = (
    "cell",
    "pick_station",
    "bins",
    "items",
    "routing",
    "policy",
    "seed",
    "limits",
    "name",
    "description",
)
CELL_KEYS = (
    "robot",
    "mount",
    "ee",
    "ee_config",
    "params",
    "residual",
    "platform",
    "drone",
    "mobile",
)
BIN_KEYS = ("id", "position_m", "size_m", "rim_height_m")
ITEM_KEYS = ("object", "shape", "mass_kg", "size_m", "count", "bin")
LIMIT_KEYS = ("place_reach_m", "max_items", "item_time_limit_s")
DRONE_KEYS = ("hover_height_m", "rotor_rpm")
MOBILE_KEYS = ("speed_mps",)
PICK_KEYS = ("position_m",)


def job_keys() -> tuple[str, ...]:
    """Every key the parser accepts, as a dotted path (`cell.drone.rotor_rpm`, `bins[].id`,
    `routing.<shape>` for each shape class routing takes), in schema order. The job-format
    page (docs/jobs.md) documents each; a test compares the two."""
    nested = {
        "cell": tuple(f"cell.{k}" for k in CELL_KEYS)
        + tuple(f"cell.drone.{k}" for k in DRONE_KEYS)
        + tuple(f"cell.mobile.{k}" for k in MOBILE_KEYS),
        "pick_station": tuple(f"pick_station.{k}" for k in PICK_KEYS),
        "bins": tuple(f"bins[].{k}" for k in BIN_KEYS),
        "items": tuple(f"items[].{k}" for k in ITEM_KEYS),
        "routing": tuple(f"routing.{s}" for s in SHAPES),
        "limits": tuple(f"limits.{k}" for k in LIMIT_KEYS),
    }
    out: list[str] = []
    for top in TOP_KEYS:
        out.append(top)
        out.extend(nested.get(top, ()))
    return tuple(out)
