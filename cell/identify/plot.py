"""Reach-against-stroke plots of a model before and after identification (the kind
of the thesis' Figs. 4.1-4.3), as PNG files (matplotlib, Agg backend)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.model.throw import ThrowBatch, predict_landing
from cell.params import ModelParams

__all__ = ["plot_reach"]


def _curve(
    obj: ObjectParams, params: ModelParams, strokes: np.ndarray, pose: dict[str, float]
) -> np.ndarray:
    """Model reach [m] over strokes at one release pose (azimuth 0, from x = y = 0)."""
    o = params.objects.get(obj.name, obj)
    batch = ThrowBatch.build(
        stroke=strokes,
        position=np.c_[
            np.zeros_like(strokes), np.zeros_like(strokes), np.full_like(strokes, pose["z"])
        ],
        elevation=pose["elevation"],
        azimuth=0.0,
        shape=o.code,
        mass=o.mass,
        size=np.asarray(o.size)[None, :],
        land_z=pose["land_z"],
    )
    return predict_landing(batch, params.ee, strict=False, check_stroke=False).x


def _median_pose(table: ThrowTable, m: np.ndarray) -> dict[str, float]:
    """The median release height [m], elevation [rad] and landing plane [m] of the throws
    `m` of `table` (0.6 m, 0.5 rad, 0 m where there are none)."""
    return {
        "z": float(np.median(table.num("z_m")[m])) if m.any() else 0.6,
        "elevation": float(np.median(table.num("elevation_rad")[m])) if m.any() else 0.5,
        "land_z": float(np.median(table.num("land_z_m")[m])) if m.any() else 0.0,
    }


def _object_figures(
    plt: Any, panel: Callable[[Any, str], None], objects: list[str], out: Path
) -> list[Path]:
    """One reach-vs-stroke figure per object (`panel` draws it), written into `out`."""
    written = []
    for oid in objects:
        fig, ax = plt.subplots(figsize=(5, 3.6))
        panel(ax, oid)
        ax.legend(fontsize=7)
        ax.set_title(
            f"Stroke length vs reach: {oid} (curves at the median release pose)", fontsize=9
        )
        fig.tight_layout()
        path = out / f"reach_{oid}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def _overview(plt: Any, panel: Callable[[Any, str], None], objects: list[str], out: Path) -> Path:
    """The objects' panels on one grid, up to four a row, written into `out`."""
    cols = min(4, len(objects))
    rows = math.ceil(len(objects) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False)
    for ax, oid in zip(axes.ravel(), objects, strict=False):
        panel(ax, oid)
    for ax in axes.ravel()[len(objects) :]:
        ax.axis("off")
    axes[0, 0].legend(fontsize=6)
    fig.suptitle("Reach against stroke: model before and after identification vs observed")
    fig.tight_layout()
    path = out / "reach_overview.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_reach(
    table: ThrowTable,
    before: ModelParams,
    after: ModelParams,
    out_dir: str | Path,
    *,
    held_out: np.ndarray | None = None,
) -> list[Path]:
    """Write reach-vs-stroke plots: one PNG per object and an overview grid.

    Each panel shows the observed reach of every throw (held-out throws hollow)
    and the model's reach before and after identification as curves at the
    object's median release pose (height, elevation, landing plane).

    Args:
        table: the throws (with strokes and observed landings).
        before: the start parameters.
        after: the identified parameters.
        out_dir: directory to write into (created if missing).
        held_out: indices of held-out throws (drawn hollow).

    Returns:
        The files written.

    Raises:
        InvalidInput: the directory cannot be created.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cell.identify.report import reach

    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidInput(f"--plot {out}: cannot create the directory ({exc})") from None
    ids = np.array(table.text("object_id"))
    stroke = table.num("stroke_m")
    obs_reach = reach(table, table.landed)
    hollow = np.zeros(len(table), dtype=bool)
    if held_out is not None:
        hollow[np.asarray(held_out, dtype=int)] = True
    objects = sorted(set(ids))
    shape, mass = table.text("shape"), table.num("mass_kg")
    size = np.stack([table.num("size_x_m"), table.num("size_y_m"), table.num("size_z_m")], -1)

    def panel(ax: object, oid: str) -> None:
        m = (ids == oid) & np.isfinite(stroke) & np.isfinite(obs_reach)
        i0 = int(np.flatnonzero(ids == oid)[0])
        logged = ObjectParams(shape=shape[i0], mass=float(mass[i0]), size=tuple(size[i0]), name=oid)
        pose = _median_pose(table, m)
        lo, hi = (stroke[m].min(), stroke[m].max()) if m.any() else (0.03, 0.11)
        grid = np.linspace(lo, hi, 60)  # the strokes this object was thrown at
        b = _curve(logged, before, grid, pose)
        a = _curve(logged, after, grid, pose)
        fit = m & ~hollow
        ax.plot(stroke[fit], obs_reach[fit], "o", ms=3, color="0.35", label="observed")  # type: ignore[attr-defined]
        ax.plot(  # type: ignore[attr-defined]
            stroke[m & hollow],
            obs_reach[m & hollow],
            "o",
            ms=4,
            mfc="none",
            color="k",
            label="observed, held out",
        )
        ax.plot(grid, b, "--", color="tab:red", label="model before")  # type: ignore[attr-defined]
        ax.plot(grid, a, "-", color="tab:blue", label="model after")  # type: ignore[attr-defined]
        ax.set_title(  # type: ignore[attr-defined]
            f"{oid}: z {pose['z']:.2f} m, e {math.degrees(pose['elevation']):.0f}°", fontsize=8
        )
        ax.set_xlabel("stroke L_s [m]", fontsize=8)  # type: ignore[attr-defined]
        ax.set_ylabel("reach [m]", fontsize=8)  # type: ignore[attr-defined]
        ax.tick_params(labelsize=7)  # type: ignore[attr-defined]

    return [*_object_figures(plt, panel, objects, out), _overview(plt, panel, objects, out)]
