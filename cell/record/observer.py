"""The sort loop's recorder: a run observer that writes a Rerun recording of the scene.

The loop calls it at scene set-up, item start, release, flight and item done
(`RunObserver`). At scene set-up it logs the static scene and starts sampling
the scene at `sample_hz` of simulated time: the arm's links (meshes) and joint
angles, the end-effector's bodies, and every item it was told about, each as
a pose over `sim_time`. The sampling wraps the scene's `step` on that one
scene object (stepping one physics step at a time is what `step(n)` does), so
the loop itself does not change and a run without a recorder runs as before.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from cell.record.bodies import Visual, body_visuals, link_poses
from cell.record.run import RunRecording, item_entity

__all__ = ["RunObserver", "SceneRecorder"]

log = logging.getLogger(__name__)


class RunObserver(Protocol):
    """What the sort loop tells an observer (every argument is the loop's own object)."""

    def on_scene(self, scene: Any, job: Any) -> None: ...
    def on_item_start(self, index: int, obj: Any, target: Any, item: Any) -> None: ...
    def on_release(
        self,
        index: int,
        plan: Any,
        model_obj: Any,
        ee: Any,
        stroke_m: float,
        point: Any,
        aim_xyz: Any,
    ) -> None: ...
    def on_flight(self, index: int, outcome: Any, landing_xyz: Any) -> None: ...
    def on_item_done(self, result: Any) -> None: ...


class SceneRecorder:
    """A `RunObserver` writing a `.rrd` recording of a run in the PyBullet cell.

    Args:
        path: the `.rrd` file.
        sample_hz: poses sampled per simulated second.

    Raises:
        MissingDependency: rerun-sdk is not installed.
    """

    def __init__(self, path: str | Path, *, sample_hz: float = 30.0) -> None:
        self.run = RunRecording(path)
        self.path = self.run.path
        self.period_s = 1.0 / sample_hz
        self.scene: Any = None
        self._next_t = 0.0
        self._bodies: list[tuple[int, str, list[int]]] = []  # (body, entity, links)
        self._items: dict[int, tuple[int, str]] = {}  # body -> (index, object id)
        self._index: int | None = None
        self._landing: Any = None
        self._aims: dict[int, Any] = {}  # item → the point its throw was for [m, W]
        self._step: Any = None

    # -- RunObserver -----------------------------------------------------------
    def on_scene(self, scene: Any, job: Any = None) -> None:
        """Log the static scene and start sampling it."""
        self.scene = scene
        bins = [
            dict(id=b.id, center_xy=b.center_xy, size_xy=b.size_xy, rim_height=b.rim_height)
            for b in scene.bins
        ]
        station = dict(center_xy=scene.pick_station_xy, height=scene.pick_station_height)
        self.run.scene(bins, station)
        if scene.arm is not None:
            scene.show_arm()  # its meshes, drawn in the recording
            self._add_body(scene.arm, "world/arm")
        self._add_body(scene.ee_body, "world/end_effector")
        step = scene.step

        def sampled_step(n: int = 1) -> None:
            for _ in range(n):
                step(1)
                if scene.t + 1e-12 >= self._next_t:
                    self._sample()
                    self._next_t = scene.t + self.period_s

        self._step = step
        scene.step = sampled_step
        self._sample()
        self._next_t = scene.t + self.period_s

    def on_item_start(self, index: int, obj: Any, target: Any, item: Any) -> None:
        """A new item on the pick station (its body is sampled from now on)."""
        oid = obj.name or obj.shape
        self._index = index
        self.run.rec.flush_samples(item=index)
        self.run.item_start(index, oid, target.id, self.scene.t)
        ent = item_entity(index, oid)
        self._items[item.body] = (index, oid)
        self._log_visuals(item.body, ent, body_visuals(self.scene.client, item.body))
        self._sample()

    def on_release(
        self,
        index: int,
        plan: Any,
        model_obj: Any,
        ee: Any,
        stroke_m: float,
        point: Any,
        aim_xyz: Any,
    ) -> None:
        """The planned release (and the model's flight) just before the latch opens;
        aim_xyz is the point of the target's rim plane the throw is for [m, W]."""
        self._aims[index] = aim_xyz
        from cell.errors import CellError
        from cell.model.throw import throw_axis
        from cell.record.flight import predicted_flight

        u = throw_axis(np.array([plan.elevation_rad]), np.array([plan.azimuth_rad]))[0]
        try:
            pred = predicted_flight(plan.to_batch(model_obj), ee)
        except CellError as exc:  # the plan's own model never lands: draw no flight
            log.info("item %d: no predicted flight (%s)", index, exc)
            pred = None
        p0 = (plan.x_m, plan.y_m, plan.z_m)
        self.run.release(index, self.scene.t, p0, u, stroke_m=stroke_m, predicted=pred)

    def on_flight(self, index: int, outcome: Any, landing_xyz: Any) -> None:
        """The observed flight (track since release) and its landing point [m, W]."""
        self.run.flight(index, self.scene.t, outcome.track)
        self._landing = landing_xyz

    def on_item_done(self, result: Any) -> None:
        """Score the item; the recording stops following it (a bin keeps its body)."""
        d = result if isinstance(result, dict) else result.__dict__
        self.run.rec.flush_samples(item=d["index"])
        aim = self._aims.pop(d["index"], None)
        self.run.item_done(d, self.scene.t, self._landing, aim_xyz=aim)
        self._landing = None
        for body, (i, oid) in list(self._items.items()):
            if i == d["index"]:
                self.run.rec.clear(item_entity(i, oid))
                del self._items[body]

    # -- the end -----------------------------------------------------------------
    def finish(self, summary: Any = None) -> None:
        """Log the closing figures (a RunSummary or dict), stop sampling and close the file."""
        if summary is not None:
            d = summary.as_dict() if hasattr(summary, "as_dict") else dict(summary)
            self.run.summary({k: _fmt(v) for k, v in d.items()})
        self.close()

    def close(self) -> None:
        """Stop sampling and close the file (safe to call twice)."""
        if self.scene is not None and self._step is not None:
            self.scene.step = self._step
            self._step = None
        self.run.close()

    # -- sampling ----------------------------------------------------------------
    def _add_body(self, body: int, entity: str) -> None:
        vis = body_visuals(self.scene.client, body)
        links = sorted({v.link for v in vis})
        self._bodies.append((body, entity, links))
        self._log_visuals(body, entity, vis, per_link=True)

    def _log_visuals(
        self, body: int, entity: str, vis: list[Visual], *, per_link: bool = False
    ) -> None:
        r = self.run.rec
        for k, v in enumerate(vis):
            parent = f"{entity}/link{v.link}" if per_link else entity
            ent = f"{parent}/visual{k}"
            scale = v.size if v.kind == "mesh" else None
            r.pose(ent, v.position, v.quat_xyzw, scale=scale, static=True)
            rgba = v.rgba
            if v.kind == "mesh":
                r.mesh_file(f"{ent}/mesh", v.mesh, rgba=rgba)
            else:  # boxes; spheres, cylinders and capsules as their bounding boxes
                r.boxes(f"{ent}/box", [0, 0, 0], v.size, colors=[rgba], static=True)

    def _sample(self) -> None:
        sc = self.scene
        r = self.run.rec
        t = sc.t
        cl = sc.client
        for body, entity, links in self._bodies:
            for link, (p, q) in link_poses(cl, body, links).items():
                r.sample_pose(f"{entity}/link{link}", t, p, q)
        if sc.arm is not None:
            angles = [cl.getJointState(sc.arm, j)[0] for j in sc.arm_joints]
            r.sample_scalars("arm/joint_angles_rad", t, angles)
        for body, (i, oid) in self._items.items():
            if any(it.body == body for it in sc.items):
                p, o = cl.getBasePositionAndOrientation(body)
                info = cl.getDynamicsInfo(body, -1)
                ip, io = cl.invertTransform(info[3], info[4])
                lp, lo = cl.multiplyTransforms(p, o, ip, io)
                r.sample_pose(item_entity(i, oid), t, lp, lo, item=i)


def _fmt(v: Any) -> Any:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.4g}"
    return v
