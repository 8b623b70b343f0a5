"""Sort jobs: the YAML schema, loaded safely and validated with line numbers.

The format, every key with its units, default and bounds, an annotated example and what is
refused, is docs/jobs.md (a test checks that page against this parser and runs its
example); the keys themselves are `cell.jobschema`'s. Loading uses yaml's safe composer (no
tags are ever executed) and keeps the line of every node, so an error names the file, the
line and the field path and says what would be valid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import yaml

from cell.catalogue import CatalogueEntry, catalogue
from cell.errors import InvalidInput, JobError
from cell.jobschema import (
    BIN_KEYS,
    CELL_KEYS,
    DRONE_KEYS,
    ITEM_KEYS,
    LIMIT_KEYS,
    MOBILE_KEYS,
    PICK_KEYS,
    TOP_KEYS,
    job_keys,
)
from cell.kinds import EE_BACKENDS, PLATFORMS, ROBOTS
from cell.model.objects import SHAPES, ObjectParams
from cell.yamlsafe import check_yaml, read_yaml_text
from cell.yamltree import Checker, Node, to_tree

__all__ = ["BinSpec", "ItemSpec", "Job", "job_keys", "load_job", "parse_job"]

POLICIES = ("auto", "place", "throw")
ROBOT_BASE_CLEARANCE_M = 0.25  # [m] no bin may come closer to the robot base than this
MAX_ITEMS = 100_000  # items in one job (a count, or limits.max_items); more is refused unbuilt
# The orders a job's items may be taken in (`Job.expanded_items`, `cell run --order`): as
# listed, or bin by bin (the items all at hand, as in a tote).
ORDERS = ("job", "bins")


def check_order(order: str) -> None:
    """InvalidInput unless `order` is one of ORDERS (naming them)."""
    if order not in ORDERS:
        raise InvalidInput(f"item order {order!r}: valid are {list(ORDERS)}")


@dataclass(frozen=True)
class BinSpec:
    """An open bin on the floor.

    Attributes:
        id: its name.
        position: centre of its floor [m, W], (x, y).
        size: inner extents (x, y) [m].
        rim_height: height of its rim above the floor [m]: the landing plane.
    """

    id: str
    position: tuple[float, float]
    size: tuple[float, float]
    rim_height: float


@dataclass(frozen=True)
class ItemSpec:
    """Items of one kind to sort.

    Attributes:
        obj: the object's parameters.
        count: how many.
        bin: destination bin id.
        line: the line of the job file that asked for it.
    """

    obj: ObjectParams
    count: int
    bin: str
    line: int


@dataclass(frozen=True)
class Job:
    """A validated sort job."""

    path: str
    robot: str
    ee: str
    ee_config: str
    params: str
    residual: str
    pick_position: tuple[float, float, float]
    bins: tuple[BinSpec, ...]
    items: tuple[ItemSpec, ...]
    policy: str
    seed: int
    place_reach_m: float
    max_items: int
    item_time_limit_s: float
    platform: str = "arm"
    hover_height_m: float = 2.0
    rotor_rpm: float = 0.0
    base_speed_mps: float = 0.0
    extras: dict[str, Any] = field(default_factory=dict)

    def bin(self, bin_id: str) -> BinSpec:
        """The bin with this id."""
        for b in self.bins:
            if b.id == bin_id:
                return b
        raise JobError(f"{self.path}: no bin {bin_id!r}; bins: {[b.id for b in self.bins]}")

    def expanded_items(self, order: str = "job") -> list[ItemSpec]:
        """One entry per item, capped at max_items (the job's first ones), in the `order`
        they are taken (ORDERS): "job", as listed; "bins", each bin's items one after
        another, the bins in the order the job first names them, each bin's items in job
        order (the items are all at hand, as in a tote). InvalidInput for another order."""
        check_order(order)
        out: list[ItemSpec] = []
        for it in self.items:
            out.extend([it] * min(it.count, self.max_items - len(out)))
            if len(out) >= self.max_items:
                break
        if order == "bins":
            rank = {b: i for i, b in enumerate(dict.fromkeys(it.bin for it in out))}
            out.sort(key=lambda it: rank[it.bin])  # stable: job order within a bin
        return out


def _footprints_overlap(pos_a: Any, size_a: Any, pos_b: Any, size_b: Any) -> bool:
    """Whether two axis-aligned bin footprints (centre [x, y] m, size [x, y] m) share area."""
    return all(abs(pos_a[k] - pos_b[k]) < (size_a[k] + size_b[k]) / 2 for k in (0, 1))


@dataclass(frozen=True)
class _CellSpec:
    """The `cell` section, validated: robot, end-effector, files and platform."""

    robot: str
    ee: str
    ee_config: str
    params: str
    residual: str
    platform: str
    hover_height_m: float
    rotor_rpm: float
    base_speed_mps: float


def _job_tree(text: str, path: str) -> Node:
    """The job's YAML as a tree of nodes with their lines.

    Raises:
        JobError: unsafe or invalid YAML, or an empty file.
    """
    try:
        check_yaml(text, path)
    except InvalidInput as exc:
        raise JobError(str(exc)) from None
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        raise JobError(f"{path}: not valid YAML: {exc}") from None
    if root is None:
        raise JobError(f"{path}: the job file is empty; it needs at least bins and items")
    return to_tree(root, path)


def _top_sections(c: Checker, tree: Node, path: str) -> dict[str, Node]:
    """The top-level sections, known keys only, with bins and items required."""
    top = c.mapping(tree, "", dict.fromkeys(TOP_KEYS, ""))
    for req in ("bins", "items"):
        if req not in top:
            raise JobError(f"{path}, line {tree.line}: the job needs a '{req}' list")
    return top


def _platform(c: Checker, cell: dict[str, Node]) -> tuple[str, float, float, float]:
    """The platform and its settings.

    Returns:
        (platform, hover height [m], rotor speed [rpm], base speed [m/s]); the drone's
        and the mobile base's settings keep their defaults on other platforms.
    """
    platform = c.text(cell["platform"], "cell.platform", PLATFORMS) if "platform" in cell else "arm"
    drone = _platform_section(c, cell, platform, "drone", DRONE_KEYS)
    hover = _setting(c, drone, "cell.drone.hover_height_m", 2.0, 0.5, 10.0)
    rpm = _setting(c, drone, "cell.drone.rotor_rpm", 0.0, 0.0, 30000.0)
    mobile = _platform_section(c, cell, platform, "mobile", MOBILE_KEYS)
    speed = _setting(c, mobile, "cell.mobile.speed_mps", 0.0, 0.0, 2.0)
    return platform, hover, rpm, speed


def _platform_section(
    c: Checker, cell: dict[str, Node], platform: str, name: str, keys: Any
) -> dict[str, Node]:
    """The section `cell.<name>` of a platform's settings, known keys only ({} when absent);
    JobError when it is given for another platform."""
    if name not in cell:
        return {}
    if platform != name:
        raise c.fail(cell[name], f"cell.{name}", f"only for platform: {name}")
    return c.mapping(cell[name], f"cell.{name}", dict.fromkeys(keys, ""))


def _setting(
    c: Checker, sec: dict[str, Node], path: str, default: float, lo: float, hi: float
) -> float:
    """The number at `path` (cell.<section>.<key>) within [lo, hi]; `default` when absent."""
    key = path.rsplit(".", 1)[1]
    return c.number(sec[key], path, lo=lo, hi=hi) if key in sec else default


def _cell_file(c: Checker, cell: dict[str, Node], key: str, base: Path) -> str:
    """The file a `cell` key names, as given if it exists, else relative to the job's folder
    ("" when the key is absent).

    Raises:
        JobError: the file exists in neither place.
    """
    if key not in cell:
        return ""
    p = Path(c.text(cell[key], f"cell.{key}"))
    full = p if p.is_absolute() or p.exists() else base / p
    if not full.exists():
        raise c.fail(
            cell[key],
            f"cell.{key}",
            f"file {p} does not exist (relative to the current folder or to {base})",
        )
    return str(full)


def _cell_section(c: Checker, top: dict[str, Node], tree: Node, path: str) -> _CellSpec:
    """The `cell` section: platform, robot, end-effector back-end and the files they read."""
    cell = c.mapping(top["cell"], "cell", dict.fromkeys(CELL_KEYS, "")) if "cell" in top else {}
    platform, hover, rpm, speed = _platform(c, cell)
    robot = c.text(cell["robot"], "cell.robot", ROBOTS) if "robot" in cell else "panda"
    ee = c.text(cell["ee"], "cell.ee", EE_BACKENDS) if "ee" in cell else "pybullet"
    base = Path(path).parent if path != "<job>" else Path(".")
    ee_config = _cell_file(c, cell, "ee_config", base)
    params = _cell_file(c, cell, "params", base)
    residual = _cell_file(c, cell, "residual", base)
    if ee == "dynamixel" and not ee_config:
        raise c.fail(
            cell.get("ee", tree),
            "cell.ee_config",
            "the dynamixel back-end needs ee_config (e.g. robots/throwing_ee/dynamixel.yaml)",
        )
    return _CellSpec(robot, ee, ee_config, params, residual, platform, hover, rpm, speed)


def _pick_position(c: Checker, top: dict[str, Node]) -> tuple[float, float, float]:
    """The top centre of the pick table [m, W] (the default station when not given)."""
    pick = (0.45, -0.40, 0.20)
    if "pick_station" in top:
        ps = c.mapping(top["pick_station"], "pick_station", dict.fromkeys(PICK_KEYS, ""))
        if "position_m" in ps:
            pick = c.vector(ps["position_m"], "pick_station.position_m", 3)  # type: ignore[assignment]
    return pick


def _bin(c: Checker, bn: Node, fp: str, bins: list[BinSpec]) -> BinSpec:
    """One bin, checked against the robot base and the bins before it.

    Args:
        c: the checker.
        bn: the bin's node.
        fp: its field path (bins[i]).
        bins: the bins already read.

    Raises:
        JobError: a missing or invalid field, a repeated id, a bin too close to the robot
            base or overlapping another.
    """
    b = c.mapping(bn, fp, dict.fromkeys(BIN_KEYS, ""))
    for req in BIN_KEYS:
        if req not in b:
            raise c.fail(
                bn,
                fp,
                f"missing '{req}' (a bin needs id, position_m [x, y], size_m [x, y], rim_height_m)",
            )
    bid = c.text(b["id"], f"{fp}.id")
    if any(x.id == bid for x in bins):
        raise c.fail(b["id"], f"{fp}.id", f"bin id {bid!r} is used twice")
    pos = c.vector(b["position_m"], f"{fp}.position_m", 2)
    size = c.vector(b["size_m"], f"{fp}.size_m", 2, positive=True)
    rim = c.number(b["rim_height_m"], f"{fp}.rim_height_m", lo=0.0, hi=1.0, strict_lo=True)
    near = math.hypot(*pos) - math.hypot(size[0] / 2, size[1] / 2)
    if near < ROBOT_BASE_CLEARANCE_M:
        raise c.fail(
            b["position_m"],
            f"{fp}.position_m",
            f"the bin reaches within {max(near, 0):.2f} m of the robot base at the "
            f"origin; keep every bin at least {ROBOT_BASE_CLEARANCE_M} m away",
        )
    for other in bins:
        if _footprints_overlap(pos, size, other.position, other.size):
            raise c.fail(
                b["position_m"],
                f"{fp}.position_m",
                f"bin {bid!r} overlaps bin {other.id!r} (footprints {tuple(size)} m at "
                f"{tuple(pos)} and {tuple(other.size)} m at {tuple(other.position)}); "
                "an item landing in one would be scored in the other: move them apart",
            )
    return BinSpec(bid, pos, size, rim)  # type: ignore[arg-type]


def _bins(c: Checker, top: dict[str, Node]) -> list[BinSpec]:
    """The `bins` list, in job order."""
    bins_node = top["bins"]
    if not isinstance(bins_node.value, list) or not bins_node.value:
        raise c.fail(bins_node, "bins", "must be a non-empty list of bins")
    bins: list[BinSpec] = []
    for i, bn in enumerate(bins_node.value):
        bins.append(_bin(c, bn, f"bins[{i}]", bins))
    return bins


def _routing(c: Checker, top: dict[str, Node], bin_ids: list[str]) -> dict[str, str]:
    """The routing rules {shape class: bin id} (empty when not given)."""
    routing: dict[str, str] = {}
    if "routing" in top:
        rt = c.mapping(top["routing"], "routing", dict.fromkeys(SHAPES, ""))
        for shape, node in rt.items():
            routing[shape] = c.text(node, f"routing.{shape}", tuple(bin_ids))
    return routing


def _item_object(
    c: Checker, it: dict[str, Node], itn: Node, fp: str, i: int, cat: dict[str, CatalogueEntry]
) -> ObjectParams:
    """An item's object: a catalogue entry, or an ad hoc shape, mass and size.

    Args:
        c: the checker.
        it: the item's fields.
        itn: the item's node.
        fp: its field path (items[i]).
        i: its index in the list (names an ad hoc object).
        cat: the catalogue.
    """
    if "object" in it:
        if any(k in it for k in ("shape", "mass_kg", "size_m")):
            raise c.fail(
                itn,
                fp,
                "give either object (a catalogue id) or shape, mass_kg and size_m, not both",
            )
        oid = c.text(it["object"], f"{fp}.object")
        if oid not in cat:
            raise c.fail(
                it["object"],
                f"{fp}.object",
                f"unknown catalogue id {oid!r}; valid: {', '.join(cat)}",
            )
        return cat[oid].params
    for req in ("shape", "mass_kg", "size_m"):
        if req not in it:
            raise c.fail(
                itn,
                fp,
                f"missing '{req}': an item needs object (a catalogue id) "
                "or shape, mass_kg and size_m",
            )
    shape = c.text(it["shape"], f"{fp}.shape", SHAPES[:4])
    mass = c.number(it["mass_kg"], f"{fp}.mass_kg", lo=0.0, hi=2.0, strict_lo=True)
    size = c.vector(it["size_m"], f"{fp}.size_m", 3, positive=True)
    if max(size) > 0.25:
        raise c.fail(it["size_m"], f"{fp}.size_m", "extents above 0.25 m do not fit the grip")
    return ObjectParams(shape=shape, mass=mass, size=size, name=f"item{i}_{shape}")  # type: ignore[arg-type]


def _item(
    c: Checker,
    itn: Node,
    i: int,
    cat: dict[str, CatalogueEntry],
    routing: dict[str, str],
    bin_ids: list[str],
) -> ItemSpec:
    """One entry of `items`: its object, count and destination bin (its own, else the
    routing rule for its shape)."""
    fp = f"items[{i}]"
    it = c.mapping(itn, fp, dict.fromkeys(ITEM_KEYS, ""))
    obj = _item_object(c, it, itn, fp, i, cat)
    count = c.integer(it["count"], f"{fp}.count", 1, MAX_ITEMS) if "count" in it else 1
    if "bin" in it:
        dest = c.text(it["bin"], f"{fp}.bin", tuple(bin_ids))
    elif obj.shape in routing:
        dest = routing[obj.shape]
    else:
        raise c.fail(
            itn,
            fp,
            f"no destination: give 'bin' (one of {', '.join(bin_ids)}) or a "
            f"routing rule for shape {obj.shape!r}",
        )
    return ItemSpec(obj, count, dest, itn.line)


def _items(
    c: Checker, top: dict[str, Node], routing: dict[str, str], bin_ids: list[str]
) -> list[ItemSpec]:
    """The `items` list, in job order."""
    items_node = top["items"]
    if not isinstance(items_node.value, list) or not items_node.value:
        raise c.fail(items_node, "items", "must be a non-empty list of items")
    cat = catalogue()
    return [_item(c, itn, i, cat, routing, bin_ids) for i, itn in enumerate(items_node.value)]


def _limits(c: Checker, top: dict[str, Node]) -> tuple[float, int, float]:
    """The `limits` section.

    Returns:
        (place reach [m], max items, time limit per item [s]), defaults where not given.
    """
    lim = (
        c.mapping(top["limits"], "limits", dict.fromkeys(LIMIT_KEYS, "")) if "limits" in top else {}
    )
    reach = (
        c.number(lim["place_reach_m"], "limits.place_reach_m", lo=0.2, hi=1.2)
        if "place_reach_m" in lim
        else 0.75
    )
    max_items = (
        c.integer(lim["max_items"], "limits.max_items", 1, MAX_ITEMS)
        if "max_items" in lim
        else 1000
    )
    tlim = (
        c.number(lim["item_time_limit_s"], "limits.item_time_limit_s", lo=1.0)
        if "item_time_limit_s" in lim
        else 20.0
    )
    return reach, max_items, tlim


def parse_job(text: str, path: str = "<job>") -> Job:
    """Validate a job given as YAML text.

    Raises:
        JobError: naming the file, the line and the field path, and what is valid.
    """
    tree = _job_tree(text, path)
    c = Checker(path)
    top = _top_sections(c, tree, path)
    cell = _cell_section(c, top, tree, path)
    pick = _pick_position(c, top)
    bins = _bins(c, top)
    bin_ids = [b.id for b in bins]
    routing = _routing(c, top, bin_ids)
    items = _items(c, top, routing, bin_ids)
    policy = c.text(top["policy"], "policy", POLICIES) if "policy" in top else "auto"
    seed = c.integer(top["seed"], "seed", 0, 2**32 - 1) if "seed" in top else 0
    reach, max_items, tlim = _limits(c, top)
    return Job(
        path=path,
        pick_position=pick,
        bins=tuple(bins),
        items=tuple(items),
        policy=policy,
        seed=seed,
        place_reach_m=reach,
        max_items=max_items,
        item_time_limit_s=tlim,
        **{f.name: getattr(cell, f.name) for f in fields(cell)},  # the `cell` section's
    )


def load_job(path: str | Path) -> Job:
    """Read and validate a job file.

    Raises:
        JobError: missing or unreadable file, or any invalid field (file, line, field path).
    """
    p = str(path)
    try:
        text = read_yaml_text(p, "job file")
    except InvalidInput as exc:
        raise JobError(str(exc)) from None
    return parse_job(text, p)
