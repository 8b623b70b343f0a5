"""A sort run's recording from plain data: scene, items, releases, flights, landings, figures.

Entities (world frame W, z up, metres):

- `world/floor`, `world/pick_station`, `world/bins/<id>` (boxes labelled with the bin id);
- `world/items/<nnn>_<object>`: each item's frame over time (its shape under it);
- `world/release/<nnn>`: the planned release point and throw axis;
- `world/flight/<nnn>/predicted`, `.../observed`: the model's and the scene's flights;
- `world/landing/<nnn>`: where the item crossed the target's rim plane (a place: where it
  rests), beside `world/landing/<nnn>/target` (the point it was for: a throw's aim, the bin
  centre at rim height for a place);
- `items/landing_error_m`, `items/stroke_m`, `items/cycle_time_s`: one sample per item;
- `log`: one text entry per item (its failure reason, if any).

Everything is on the `sim_time` timeline (simulated seconds); what belongs to
an item is also on the `item` timeline (its index in the job).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.record.stream import Recording

__all__ = ["RunRecording", "item_entity", "FLOOR_HALF_M"]

FLOOR_HALF_M = 3.0  # [m] half width of the floor drawn
GREEN, RED, GREY = (60, 180, 75), (230, 25, 75), (150, 150, 150)
PREDICTED, OBSERVED = (255, 160, 0), (0, 130, 200)


def _layout() -> Any:
    """The viewer's default layout: the cell in 3-D beside the per-item figures and the log."""
    import rerun.blueprint as rrb

    eye = rrb.EyeControls3D(position=(0.7, -2.8, 1.5), look_target=(1.3, 0.05, 0.2))
    whole = rrb.TimeAxis(  # every item, not a window that follows the cursor
        view_range=rrb.TimeRange(
            start=rrb.TimeRangeBoundary.infinite(), end=rrb.TimeRangeBoundary.infinite()
        )
    )
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(origin="world", name="cell", eye_controls=eye),
            rrb.Vertical(
                rrb.TimeSeriesView(
                    origin="items/landing_error_m", name="landing error [m]", axis_x=whole
                ),
                rrb.TimeSeriesView(origin="items/stroke_m", name="stroke [m]", axis_x=whole),
                rrb.TimeSeriesView(
                    origin="items/cycle_time_s", name="cycle time [s]", axis_x=whole
                ),
                rrb.TimeSeriesView(origin="arm", name="joint angles [rad]", axis_x=whole),
                rrb.TextLogView(origin="log", name="log"),
            ),
            column_shares=[2, 1],
        ),
        rrb.TimePanel(timeline="sim_time", play_state="following"),
        collapse_panels=True,
    )


def item_entity(index: int, object_id: str) -> str:
    """The entity path of an item."""
    return f"world/items/{index:03d}_{object_id}"


class RunRecording:
    """Writes a sort run to a `.rrd` file from plain values.

    Args:
        path: the `.rrd` file.
        application_id: Rerun's application id.
    """

    def __init__(self, path: str | Path, application_id: str = "cell_run") -> None:
        self.rec = Recording(path, application_id)
        self.path = self.rec.path
        self.bins: dict[str, dict[str, Any]] = {}
        self.rec.stream.send_blueprint(_layout())

    # -- the scene -------------------------------------------------------------
    def scene(
        self,
        bins: Sequence[Mapping[str, Any]],
        pick_station: Mapping[str, Any] | None = None,
    ) -> None:
        """The floor, the pick station and the bins (static).

        Args:
            bins: each {"id", "center_xy" [m], "size_xy" [m], "rim_height" [m]}.
            pick_station: {"center_xy" [m], "height" [m], "half_xy" [m]} or None.
        """
        r = self.rec
        r.boxes(
            "world/floor",
            [0, 0, -0.005],
            [FLOOR_HALF_M, FLOOR_HALF_M, 0.005],
            colors=[(200, 200, 200)],
            static=True,
        )
        if pick_station is not None:
            cx, cy = pick_station["center_xy"]
            h = float(pick_station["height"])
            hx, hy = pick_station.get("half_xy", (0.12, 0.12))
            r.boxes(
                "world/pick_station",
                [cx, cy, h / 2],
                [hx, hy, h / 2],
                labels=["pick station"],
                colors=[(128, 102, 77)],
                static=True,
            )
        for b in bins:
            cx, cy = b["center_xy"]
            sx, sy = b["size_xy"]
            h = float(b["rim_height"])
            self.bins[str(b["id"])] = dict(b)
            r.boxes(
                f"world/bins/{b['id']}",
                [cx, cy, h / 2],
                [sx / 2, sy / 2, h / 2],
                labels=[str(b["id"])],
                colors=[(77, 115, 178)],
                wireframe=True,
                static=True,
            )

    # -- an item ---------------------------------------------------------------
    def item_start(self, index: int, object_id: str, target_bin: str, sim_time_s: float) -> None:
        """An item appears on the pick station."""
        self.rec.at(sim_time_s, index)
        self.rec.text("log", f"item {index}: {object_id} -> bin {target_bin}", "DEBUG")

    def item_pose(
        self,
        index: int,
        object_id: str,
        sim_time_s: float,
        position: Sequence[float],
        quat_xyzw: Sequence[float],
    ) -> None:
        """Where an item is [m, W] at a simulated time."""
        self.rec.at(sim_time_s, index)
        self.rec.pose(item_entity(index, object_id), position, quat_xyzw)

    def release(
        self,
        index: int,
        sim_time_s: float,
        point: Sequence[float],
        axis: Sequence[float],
        *,
        stroke_m: float,
        predicted: np.ndarray | None = None,
    ) -> None:
        """The planned release: grip centre p0 [m, W], throw axis u, and the predicted flight.

        Args:
            predicted: the model's flight, (k, 4) t [s since release], x, y, z [m].
        """
        r = self.rec
        r.at(sim_time_s, index)
        p = np.asarray(point, float)
        u = np.asarray(axis, float)
        r.arrows(
            f"world/release/{index:03d}",
            p,
            0.2 * u / np.linalg.norm(u),
            colors=[PREDICTED],
        )
        if predicted is not None and len(predicted) > 1:
            r.strips(
                f"world/flight/{index:03d}/predicted",
                [predicted[:, 1:4]],
                colors=[PREDICTED],
                radius=0.004,
            )

    def flight(self, index: int, sim_time_s: float, observed: np.ndarray) -> None:
        """The observed flight: (k, 4) t [s since release], x, y, z [m, W]."""
        self.rec.at(sim_time_s, index)
        self.rec.strips(
            f"world/flight/{index:03d}/observed",
            [np.asarray(observed)[:, 1:4]],
            colors=[OBSERVED],
            radius=0.004,
        )

    def item_done(
        self,
        result: Mapping[str, Any],
        sim_time_s: float,
        landing_xyz: Sequence[float] | None = None,
        *,
        aim_xyz: Sequence[float] | None = None,
    ) -> None:
        """An item's outcome (as `ItemResult.as_dict` / `cell run --json` results).

        Args:
            result: index, object_id, target_bin, action, reason, bin_id, in_bin,
                landing_error_m, stroke_m, cycle_time_s.
            sim_time_s: simulated time when it is scored [s].
            landing_xyz: the landing point [m, W] (throw: the rim-plane crossing;
                place: the rest point), None when there is none.
            aim_xyz: a throw's aim [m, W]: the point of the target's rim plane it was
                for, from which its landing error is measured (the bin's centre, or a
                point clear of what the bin holds); None: the bin's centre at rim
                height, as a place's error is measured.
        """
        r = self.rec
        i = int(result["index"])
        r.at(sim_time_s, i)
        ok = bool(result.get("in_bin"))
        err = float(result.get("landing_error_m", math.nan))
        label = f"{i} {result['object_id']} {err:.2f} m"
        if landing_xyz is not None:
            r.points(
                f"world/landing/{i:03d}",
                [landing_xyz],
                labels=[label],
                colors=[GREEN if ok else RED],
                radii=0.015,
            )
        b = self.bins.get(str(result["target_bin"]))
        if aim_xyz is None and b is not None:
            aim_xyz = (*b["center_xy"], b["rim_height"])
        if aim_xyz is not None:
            r.points(
                f"world/landing/{i:03d}/target",
                [tuple(float(v) for v in aim_xyz)],
                colors=[GREY],
                radii=0.01,
            )
        r.scalar("items/landing_error_m", err)
        r.scalar("items/stroke_m", float(result.get("stroke_m", math.nan)))
        r.scalar("items/cycle_time_s", float(result.get("cycle_time_s", math.nan)))
        if result["action"] == "failed":
            r.text("log", f"item {i} ({result['object_id']}) failed: {result['reason']}", "ERROR")
        elif not ok:
            r.text(
                "log",
                f"item {i} ({result['object_id']}) missed bin {result['target_bin']}: "
                f"in {result.get('bin_id') or 'no bin'}, {err:.3f} m from its aim",
                "WARN",
            )
        else:
            r.text(
                "log",
                f"item {i} ({result['object_id']}) in bin {result['bin_id']}, "
                f"{err:.3f} m from its centre",
                "INFO",
            )

    def summary(self, summary: Mapping[str, Any]) -> None:
        """The closing figures as a static Markdown document."""
        rows = [f"| {k} | {v} |" for k, v in summary.items() if k != "results"]
        self.rec.document("summary", "| figure | value |\n|---|---|\n" + "\n".join(rows))

    def close(self) -> None:
        """Flush and close the file."""
        self.rec.close()
