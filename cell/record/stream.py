"""A Rerun recording written to a `.rrd` file, fed plain data.

One `Recording` owns a dedicated `rerun.RecordingStream` (never the global
one) whose sink is the file. Every entity lives in the world frame W (z up,
metres) under `world/`; time series (scalars) live outside it. Times are set
on two timelines: `sim_time` (simulated seconds, a duration) and `item` (a
sequence number); `at` sets either or both for what is logged next.
"""

from __future__ import annotations

import logging
import uuid
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from cell.errors import InvalidInput, MissingDependency
from cell.record import RECORD_EXTRA

__all__ = ["Recording", "import_rerun", "SIM_TIME", "ITEM"]

log = logging.getLogger(__name__)

SIM_TIME = "sim_time"  # timeline: simulated time [s]
ITEM = "item"  # timeline: item (or throw) number

Color = Sequence[int]


def import_rerun() -> Any:
    """The `rerun` module.

    Raises:
        MissingDependency: rerun-sdk is not installed; names the extra to install.
    """
    try:
        import rerun
    except ImportError:
        raise MissingDependency(f"--record needs rerun-sdk: {RECORD_EXTRA}") from None
    return rerun


class Recording:
    """A `.rrd` recording.

    Args:
        path: the file to write (its folder is created).
        application_id: Rerun's application id (the viewer groups recordings by it).

    Raises:
        MissingDependency: rerun-sdk is not installed.
        InvalidInput: the path is a folder or cannot be written.
    """

    def __init__(self, path: str | Path, application_id: str = "cell") -> None:
        rr = import_rerun()
        self.rr = rr
        self.path = Path(path)
        if self.path.is_dir():
            raise InvalidInput(f"--record {path}: is a folder; give a file name such as run.rrd")
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_bytes(b"")  # fail here, named, rather than in Rerun's sink thread
        except OSError as exc:
            raise InvalidInput(f"--record {path}: cannot write there ({exc.strerror})") from None
        self.stream = rr.RecordingStream(application_id, recording_id=str(uuid.uuid4()))
        self.stream.save(str(self.path))
        self.stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self._closed = False
        # sampled series, sent as columns (one call per entity, not one per sample)
        self._poses: dict[
            tuple[str, int | None], list[tuple[float, Sequence[float], Sequence[float]]]
        ] = {}
        self._series: dict[str, list[tuple[float, Sequence[float]]]] = {}
        self._segment_item: int | None = None

    # -- time ------------------------------------------------------------------
    def at(self, sim_time_s: float | None = None, item: int | None = None) -> None:
        """Set the time of what is logged next: simulated time [s] and/or item number."""
        if sim_time_s is not None:
            self.stream.set_time(SIM_TIME, duration=float(sim_time_s))
        if item is not None:
            self.stream.set_time(ITEM, sequence=int(item))

    # -- archetypes from plain data --------------------------------------------
    def boxes(
        self,
        entity: str,
        centers: Any,
        half_sizes: Any,
        *,
        labels: Sequence[str] | None = None,
        colors: Sequence[Color] | None = None,
        quaternions: Any = None,
        wireframe: bool = False,
        static: bool = False,
    ) -> None:
        """Boxes by centre and half extents [m] (quaternions x y z w, optional)."""
        rr = self.rr
        self.stream.log(
            entity,
            rr.Boxes3D(
                centers=np.atleast_2d(np.asarray(centers, float)),
                half_sizes=np.atleast_2d(np.asarray(half_sizes, float)),
                labels=labels,
                colors=colors,
                quaternions=None
                if quaternions is None
                else [rr.Quaternion(xyzw=q) for q in np.atleast_2d(quaternions)],
                fill_mode="majorwireframe" if wireframe else "solid",
            ),
            static=static,
        )

    def points(
        self,
        entity: str,
        positions: Any,
        *,
        labels: Sequence[str] | None = None,
        colors: Sequence[Color] | None = None,
        radii: float | Sequence[float] | None = None,
        static: bool = False,
    ) -> None:
        """Points [m, W]."""
        self.stream.log(
            entity,
            self.rr.Points3D(
                np.atleast_2d(np.asarray(positions, float)),
                labels=labels,
                colors=colors,
                radii=radii,
            ),
            static=static,
        )

    def strips(
        self,
        entity: str,
        strips: Sequence[Any],
        *,
        labels: Sequence[str] | None = None,
        colors: Sequence[Color] | None = None,
        radius: float | None = None,
        static: bool = False,
    ) -> None:
        """Polylines, each (k, 3) [m, W]."""
        self.stream.log(
            entity,
            self.rr.LineStrips3D(
                [np.asarray(s, float) for s in strips],
                labels=labels,
                colors=colors,
                radii=radius,
            ),
            static=static,
        )

    def arrows(
        self,
        entity: str,
        origins: Any,
        vectors: Any,
        *,
        labels: Sequence[str] | None = None,
        colors: Sequence[Color] | None = None,
    ) -> None:
        """Arrows from origins along vectors [m, W]."""
        self.stream.log(
            entity,
            self.rr.Arrows3D(
                origins=np.atleast_2d(np.asarray(origins, float)),
                vectors=np.atleast_2d(np.asarray(vectors, float)),
                labels=labels,
                colors=colors,
            ),
        )

    def pose(
        self,
        entity: str,
        translation: Sequence[float],
        quat_xyzw: Sequence[float] = (0.0, 0.0, 0.0, 1.0),
        *,
        scale: Sequence[float] | None = None,
        static: bool = False,
    ) -> None:
        """The entity's frame in its parent's frame: translation [m] and quaternion (x, y, z, w)."""
        rr = self.rr
        self.stream.log(
            entity,
            rr.Transform3D(
                translation=[float(v) for v in translation],
                quaternion=rr.Quaternion(xyzw=[float(v) for v in quat_xyzw]),
                scale=None if scale is None else [float(v) for v in scale],
            ),
            static=static,
        )

    def mesh_file(self, entity: str, path: str | Path, rgba: Color | None = None) -> None:
        """A mesh file (STL, OBJ, glTF/GLB) as a static asset."""
        self.stream.log(entity, self.rr.Asset3D(path=str(path), albedo_factor=rgba), static=True)

    def scalar(self, entity: str, value: float) -> None:
        """One sample of a time series (NaN is logged as a gap: nothing)."""
        if np.isfinite(value):
            self.stream.log(entity, self.rr.Scalars(float(value)))

    def scalars(self, entity: str, values: Sequence[float]) -> None:
        """One sample of several series at once (e.g. the arm's joint angles)."""
        self.stream.log(entity, self.rr.Scalars(np.asarray(values, float)))

    def text(self, entity: str, text: str, level: str = "INFO") -> None:
        """A text entry (levels: TRACE, DEBUG, INFO, WARN, ERROR, CRITICAL)."""
        self.stream.log(entity, self.rr.TextLog(text, level=level))

    def document(self, entity: str, markdown: str) -> None:
        """A static text document (Markdown)."""
        self.stream.log(
            entity, self.rr.TextDocument(markdown, media_type="text/markdown"), static=True
        )

    def clear(self, entity: str) -> None:
        """Remove an entity and its children from the view from now on."""
        self.stream.log(entity, self.rr.Clear(recursive=True))

    # -- sampled series, sent in columns ----------------------------------------
    def sample_pose(
        self,
        entity: str,
        sim_time_s: float,
        translation: Sequence[float],
        quat_xyzw: Sequence[float],
        item: int | None = None,
    ) -> None:
        """Buffer one pose sample (as `pose`) of the current segment; see `flush_samples`.

        `item`: the item the sample belongs to, when it is not the segment's (a thrown
        item still flying while the next one is picked)."""
        self._poses.setdefault((entity, item), []).append((sim_time_s, translation, quat_xyzw))

    def sample_scalars(self, entity: str, sim_time_s: float, values: Sequence[float]) -> None:
        """Buffer one sample of several series at once (as `scalars`); see `flush_samples`."""
        self._series.setdefault(entity, []).append((sim_time_s, values))

    def flush_samples(self, item: int | None = None) -> None:
        """Send the buffered samples (on `sim_time`, and on `item` when the segment had one),
        then start a new segment whose samples belong to `item`."""
        rr = self.rr
        seg = self._segment_item

        def indexes(ts: list[float], own: int | None = None) -> list[Any]:
            out = [rr.TimeColumn(SIM_TIME, duration=np.asarray(ts, float))]
            tag = seg if own is None else own
            if tag is not None:
                out.append(rr.TimeColumn(ITEM, sequence=np.full(len(ts), tag, dtype=np.int64)))
            return out

        for (entity, own), rows in self._poses.items():
            ts, tr, qs = zip(*rows, strict=True)
            cols = rr.Transform3D.columns(
                translation=np.asarray(tr, float), quaternion=np.asarray(qs, float)
            )
            self.stream.send_columns(entity, indexes(list(ts), own), cols)
        for entity, vals in self._series.items():
            ts, vs = zip(*vals, strict=True)
            arr = np.asarray(vs, float)
            cols = rr.Scalars.columns(scalars=arr.ravel()).partition([arr.shape[1]] * len(ts))
            self.stream.send_columns(entity, indexes(list(ts)), cols)
        self._poses, self._series = {}, {}
        self._segment_item = item

    # -- end -------------------------------------------------------------------
    def close(self) -> None:
        """Send what is buffered, flush everything to the file and close it."""
        if self._closed:
            return
        self.flush_samples()
        self._closed = True
        self.stream.flush()
        self.stream.disconnect()
        log.info("recording written to %s", self.path)

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
