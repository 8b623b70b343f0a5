"""Random sort jobs: layouts and items the cell has never been tuned on.

`random_job(seed)` draws one job as a plain mapping that `cell.jobs.parse_job`
accepts once dumped to YAML (`cell job random --seed S -o job.yaml` writes it
so a user can look at it and edit it). The draw is the benchmark's
(`cell bench sort`):

- 4–7 open bins whose centres lie 0.4–3.2 m from the robot base, at any
  azimuth the arm can face (its first joint's range, less a margin), 0.25–0.40 m
  wide, rims 0.05–0.30 m high; bins keep clear of each other, of the robot base
  (`cell.jobs.ROBOT_BASE_CLEARANCE_M`) and of the pick station;
- 20–40 items: catalogue objects of every set and ad-hoc items (cube, cuboid,
  cylinder or sphere, 20–250 g, extents 25–90 mm, density 150–2500 kg/m³), with at
  least a third of all items from outside the calibration set (`thesis14`);
  each kind comes 1–4 times, so the cell meets the same object again.

Everything is drawn from one `numpy.random.Generator` seeded by `seed`, so a
seed names a job.
"""

from __future__ import annotations

import math
from typing import Any, cast

import numpy as np

from cell.catalogue import catalogue
from cell.jobbins import ROBOT_BASE_CLEARANCE_M
from cell.jobschema import PLACE_REACH_M

__all__ = ["LayoutRanges", "random_job", "CALIBRATION_SET", "facing_half_range_rad"]

CALIBRATION_SET = "thesis14"  # catalogue set thrown by `cell calibrate`


def facing_half_range_rad(robot: str) -> float:
    """Half-range of azimuths a bin may be drawn at for this arm [rad]: its mount file's
    `facing_half_range_deg` (the first joint's range less a margin for the wrist to face
    the bin: Panda 150° of its ±166°; the URs turn all around, π).

    Raises:
        InvalidInput: an unknown arm (naming the known ones).
    """
    from cell.robot.mount import load_mount

    return load_mount(robot).facing_half_range_rad


def _arm_field(robot: str) -> dict[str, str]:
    """The job's `cell` field naming the arm: `robot: <name>`, or for a mount file's path
    `mount: <its absolute path>` (a job's relative mount path is read from the job's own
    folder, wherever the job is written)."""
    from cell.robot.mount import is_mount_path, resolve_mount

    return {"mount": str(resolve_mount(robot))} if is_mount_path(robot) else {"robot": robot}


PICK_STATION_XY_M = (0.45, -0.40)  # [m, W] the default pick station (cell.jobs)
PICK_STATION_CLEAR_M = 0.35  # [m] no bin footprint within this of the station's centre
BIN_GAP_M = 0.10  # [m] clearance between bin footprints


class LayoutRanges:
    """The ranges of a random layout (SI units)."""

    bins = (4, 7)
    distance_m = (0.4, 3.2)
    width_m = (0.25, 0.40)
    rim_m = (0.05, 0.30)
    items = (20, 40)
    adhoc_mass_kg = (0.020, 0.250)
    adhoc_extent_m = (0.025, 0.090)
    adhoc_density_kgpm3 = (150.0, 2500.0)
    repeat = (1, 4)
    unseen_share = 1.0 / 3.0


def _box_volume(shape: str, size: tuple[float, float, float]) -> float:
    """Solid volume [m³] of a primitive with box extents `size`."""
    x, y, z = size
    if shape == "sphere":
        return math.pi / 6 * x**3
    if shape == "cylinder":
        return math.pi / 4 * x * y * z
    return x * y * z


def _adhoc_item(rng: np.random.Generator) -> dict[str, Any]:
    """An ad-hoc item: a primitive of plausible density in the issue's ranges."""
    r = LayoutRanges
    while True:
        shape = str(rng.choice(["cube", "cuboid", "cylinder", "sphere"]))
        if shape in ("cube", "sphere"):
            e = float(rng.uniform(*r.adhoc_extent_m))
            size = (e, e, e)
        elif shape == "cylinder":
            d, h = rng.uniform(*r.adhoc_extent_m, size=2)
            size = (float(d), float(d), float(h))
        else:
            a, b, c = rng.uniform(*r.adhoc_extent_m, size=3)
            size = (float(a), float(b), float(c))
        vol = _box_volume(shape, size)
        lo = max(r.adhoc_mass_kg[0], r.adhoc_density_kgpm3[0] * vol)
        hi = min(r.adhoc_mass_kg[1], r.adhoc_density_kgpm3[1] * vol)
        if lo < hi:
            mass = float(rng.uniform(lo, hi))
            return {
                "shape": shape,
                "mass_kg": round(mass, 4),
                "size_m": [round(s, 4) for s in size],
            }


def _bins(rng: np.random.Generator, robot: str) -> list[dict[str, Any]]:
    r = LayoutRanges
    n = int(rng.integers(r.bins[0], r.bins[1] + 1))
    half = facing_half_range_rad(robot)
    out: list[dict[str, Any]] = []
    tries = 0
    while len(out) < n:
        tries += 1
        if tries > 5000:  # a crowded draw: keep what fits (never fewer than the minimum)
            if len(out) >= r.bins[0]:
                break
            out, tries = [], 0
        w = rng.uniform(*r.width_m, size=2)
        half_diag = math.hypot(*w) / 2
        d_lo = max(r.distance_m[0], ROBOT_BASE_CLEARANCE_M + half_diag + 0.01)
        d = float(rng.uniform(d_lo, r.distance_m[1]))
        az = float(rng.uniform(-half, half))
        x, y = d * math.cos(az), d * math.sin(az)
        if (
            math.hypot(x - PICK_STATION_XY_M[0], y - PICK_STATION_XY_M[1])
            < PICK_STATION_CLEAR_M + half_diag
        ):
            continue
        if any(
            abs(x - b["position_m"][0]) < (w[0] + b["size_m"][0]) / 2 + BIN_GAP_M
            and abs(y - b["position_m"][1]) < (w[1] + b["size_m"][1]) / 2 + BIN_GAP_M
            for b in out
        ):
            continue
        out.append(
            {
                "id": f"bin_{len(out)}",
                "position_m": [round(x, 3), round(y, 3)],
                "size_m": [round(float(w[0]), 3), round(float(w[1]), 3)],
                "rim_height_m": round(float(rng.uniform(*r.rim_m)), 3),
            }
        )
    return out


def _object_of(entry: dict[str, Any]) -> Any:
    from cell.model.objects import ObjectParams

    if "object" in entry:
        return catalogue()[entry["object"]].params
    return ObjectParams(
        shape=entry["shape"], mass=entry["mass_kg"], size=tuple(entry["size_m"]), name=""
    )


def _spec(b: dict[str, Any]) -> Any:
    """A drawn bin as the job's `cell.jobs.BinSpec`."""
    from cell.jobs import BinSpec

    return BinSpec(b["id"], tuple(b["position_m"]), tuple(b["size_m"]), b["rim_height_m"])  # type: ignore[arg-type]


def sortable_bins(
    entry: dict[str, Any],
    bins: list[dict[str, Any]],
    params: Any,
    thrown: frozenset[str] = frozenset(),
) -> list[str]:
    """The ids of the bins the cell can sort this item into (`cell.arm.launch.check_sortable`;
    `thrown`: the bins within place reach the job would throw into, `Job.thrown_bins`)."""
    from cell.arm.grip_side import holding_sides
    from cell.arm.launch import check_sortable
    from cell.errors import CannotGrip, UnreachableTarget

    obj = _object_of(entry)
    try:  # the sides the pads hold it across: the item's, whatever the bin
        sides = holding_sides(params, obj)
    except CannotGrip:
        return []
    ok = []
    for b in bins:
        try:
            check_sortable(params, obj, _spec(b), sides=sides, thrown_bins=thrown)
        except (CannotGrip, UnreachableTarget):
            continue
        ok.append(b["id"])
    return ok


class NearBins:
    """A random layout's bins within the job's place reach, and which of them its load
    will find the arm cannot place into with the items sent there (`Job.thrown_bins`,
    `cell.jobcheck.job_problems`, by the same spot and IK: `place_spot`, `place_miss`): the
    job throws into those, so an item goes there only if it can be thrown there, and so
    can those sent before."""

    def __init__(self, robot: str, bins: list[dict[str, Any]]) -> None:
        self.robot, self._robot = robot, cast(Any, None)
        self._drawn = {b["id"]: b for b in bins if math.hypot(*b["position_m"]) <= PLACE_REACH_M}
        self.near = {i: _spec(b) for i, b in self._drawn.items()}
        self.sent: dict[str, list[tuple[dict[str, Any], Any]]] = {i: [] for i in self.near}
        self._missed: dict[tuple[str, float, tuple[float, float]], bool] = {}
        self._sorts: dict[tuple[Any, str, bool], bool] = {}

    def sortable(
        self, entry: dict[str, Any], bins: list[dict[str, Any]], params: Any, thrown: frozenset[str]
    ) -> list[str]:
        """`sortable_bins` with each bin's answer kept for the draw: by the item's
        ObjectParams (all `sortable_bins` reads of the entry), the bin, and whether the
        job throws into it though near (all `check_sortable` reads of `thrown`); the
        bins not answered before are asked together."""
        obj = _object_of(entry)
        asked = [b for b in bins if (obj, b["id"], b["id"] in thrown) not in self._sorts]
        if asked:
            ok = set(sortable_bins(entry, asked, params, thrown))
            for b in asked:
                self._sorts[(obj, b["id"], b["id"] in thrown)] = b["id"] in ok
        return [b["id"] for b in bins if self._sorts[(obj, b["id"], b["id"] in thrown)]]

    def _misses(self, bin_id: str, objs: list[Any]) -> bool:
        """Does the arm miss placing the items `objs` (ObjectParams) into the bin (cached)?"""
        from cell.jobcheck import CHECKED_CUBE_M, place_miss, place_spot

        tall_m = max((float(o.size[2]) for o in objs), default=CHECKED_CUBE_M)
        xy, _, _ = place_spot(self.near[bin_id], objs)
        key = (bin_id, tall_m, xy)
        if key not in self._missed:
            from cell.robot.model import load_robot

            self._robot = self._robot or load_robot(self.robot)
            self._missed[key] = place_miss(self._robot, self.near[bin_id], tall_m, xy)[0] != 0.0
        return self._missed[key]

    def _objs(self, bin_id: str, obj: Any = None) -> list[Any]:
        """The items sent to the bin (and `obj`), as `cell.jobcheck` reads them."""
        return [o for _, o in self.sent[bin_id]] + ([] if obj is None else [obj])

    def thrown_with(self, obj: Any) -> frozenset[str]:
        """The near bins the job would throw into were the item `obj` (ObjectParams) sent
        to each."""
        return frozenset(i for i in self.near if self._misses(i, self._objs(i, obj)))

    def keeps_sorted(self, bin_id: str, thrown: frozenset[str], params: Any) -> bool:
        """Can the items sent to `bin_id` before still be sorted there (thrown, where this
        item would have the job throw into a bin it placed into)?"""
        if bin_id not in thrown or self._misses(bin_id, self._objs(bin_id)):
            return True
        one = [self._drawn[bin_id]]
        return all(self.sortable(e, one, params, thrown) for e, _ in self.sent[bin_id])

    def send(self, entry: dict[str, Any], obj: Any) -> None:
        """The item `entry` (its ObjectParams `obj`) is sent to its bin."""
        if entry["bin"] in self.sent:
            self.sent[entry["bin"]].append((entry, obj))


def random_job(
    seed: int, robot: str = "panda", params: Any = None, refused: list[str] | None = None
) -> dict[str, Any]:
    """A random sort job as a mapping (dump it to YAML for `cell run`).

    Each item goes to a bin drawn among those the cell can sort it into by the
    planner's model of the scene (`params`, default: the scene's calibrated file):
    the cell refuses a job with an impossible item up front (cell.orchestrator), so
    a benchmark of impossible jobs would measure nothing. Items no bin can take are
    drawn again; the job's description says how many, and `refused` (a list, if
    given) receives each one's object name (ad hoc: "adhoc <shape>"), so a benchmark
    can say what its rate leaves out.

    Args:
        seed: names the job (0 ≤ seed < 2³²).
        robot: an arm's name under robots/ (`cell.robot.mount.robot_names`) or a mount
            file's path (the job names it by its absolute path, `cell.mount`).
        params: the model parameters the feasibility check uses.
        refused: appended to with the kinds drawn again.
    """
    from cell.params import load_params, scene_params_path

    if params is None:
        params = load_params(scene_params_path())
    facing_half_range_rad(robot)  # an unknown arm is refused before anything is drawn
    r = LayoutRanges
    rng = np.random.default_rng([seed, 0x10B])
    bins = _bins(rng, robot)
    near = NearBins(robot, bins)
    cat = catalogue()
    seen = [k for k, e in cat.items() if e.set == CALIBRATION_SET]
    unseen = [k for k, e in cat.items() if e.set != CALIBRATION_SET]
    n_items = int(rng.integers(r.items[0], r.items[1] + 1))
    items: list[dict[str, Any]] = []
    n_unseen = 0
    total = 0
    dropped: list[str] = []
    while total < n_items:
        need_unseen = n_unseen < math.ceil(r.unseen_share * n_items)
        kind = rng.uniform()
        count = min(int(rng.integers(r.repeat[0], r.repeat[1] + 1)), n_items - total)
        if need_unseen and kind < 0.5 or not need_unseen and kind < 0.25:
            entry: dict[str, Any] = _adhoc_item(rng)
            is_unseen = True
        elif need_unseen or kind < 0.5:
            entry, is_unseen = {"object": str(rng.choice(unseen))}, True
        else:
            entry, is_unseen = {"object": str(rng.choice(seen))}, False
        obj = _object_of(entry)
        thrown = near.thrown_with(obj)
        choices = [
            c
            for c in near.sortable(entry, bins, params, thrown)
            if near.keeps_sorted(c, thrown, params)
        ]
        if not choices:
            dropped.append(entry.get("object") or f"adhoc {entry['shape']}")
            continue
        entry["count"] = count
        entry["bin"] = choices[int(rng.integers(len(choices)))]
        near.send(entry, obj)
        items.append(entry)
        n_unseen += count if is_unseen else 0
        total += count
    if refused is not None:
        refused.extend(dropped)
    return {
        "name": f"random layout {seed}",
        "description": (
            f"drawn by cell job random --seed {seed} --robot {robot}: {len(bins)} bins, "
            f"{n_items} items, {n_unseen} of them outside the calibration set; "
            f"{len(dropped)} kinds drawn that no bin could take (the pads cannot hold them, "
            "or no bin is within their reach) were drawn again"
        ),
        "cell": {**_arm_field(robot), "ee": "pybullet"},
        "bins": bins,
        "items": items,
        "policy": "auto",
        "seed": int(seed),
        "limits": {"item_time_limit_s": 20},
    }
