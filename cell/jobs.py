"""Sort jobs: the YAML schema, loaded safely and validated with line numbers.

The format, every key with its units, default and bounds, an annotated example and what is
refused, is docs/jobs.md (a test checks that page against this parser and runs its
example); the keys themselves are `cell.jobschema`'s. Loading uses yaml's safe composer (no
tags are ever executed) and keeps the line of every node, so an error names the file, the
line and the field path and says what would be valid.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import yaml

from cell.catalogue import CatalogueEntry, catalogue
from cell.errors import InvalidInput, JobError
from cell.jobbins import (
    BIN_HINTS,
    ROBOT_BASE_CLEARANCE_M,
    capacity_warnings,
    light_item_warnings,
    look_alike_warnings,
    millimetre_problem,
    placement_problem,
    station_millimetres,
    wide_item_warnings,
)
from cell.jobcell import cell_section
from cell.jobcheck import extents_mismatch, items_fit, job_problems, unsorted_warning
from cell.joblimits import MAX_ITEMS, limits_section
from cell.jobresidual import residual_problems
from cell.jobrim import low_rim_warnings
from cell.jobschema import (
    BIN_KEYS,
    BIN_WALL_M,
    ITEM_KEYS,
    PICK_KEYS,
    TOP_KEYS,
    job_keys,
)
from cell.model.objects import SHAPES, ObjectParams, denser_than_any_solid, lighter_than_air
from cell.yamlsafe import check_yaml, compose, read_yaml_text
from cell.yamltree import Checker, Errors, Node, nearest, same_text, to_tree

__all__ = [
    "ROBOT_BASE_CLEARANCE_M",
    "BinSpec",
    "ItemSpec",
    "Job",
    "job_keys",
    "load_job",
    "parse_job",
]

POLICIES = ("auto", "place", "throw")
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
    warnings: tuple[str, ...] = ()
    thrown_bins: frozenset[str] = frozenset()  # `auto`'s near bins it cannot place into

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
        root = compose(text)
    except yaml.YAMLError as exc:
        raise JobError(f"{path}: not valid YAML: {exc}") from None
    if root is None:
        raise JobError(f"{path}: the job file is empty; it needs at least bins and items")
    return to_tree(root, path)


def _top_sections(c: Checker, tree: Node, errors: Errors) -> dict[str, Node]:
    """The top-level sections: each unknown key and each missing list (bins, items) one
    error; the known sections returned."""
    if not isinstance(tree.value, dict):
        raise c.fail(tree, "", f"must be a mapping with keys {', '.join(TOP_KEYS)}")
    top: dict[str, Node] = {}
    for k, v in tree.value.items():
        if k in TOP_KEYS:
            top[k] = v
        else:
            valid = ", ".join(sorted(TOP_KEYS))
            errors.add(c.fail(v, k, f"unknown key {k!r}{nearest(k, TOP_KEYS)}; valid keys here: {valid}"))  # fmt: skip
    for req in ("bins", "items"):
        if req not in top and req not in (k.casefold() for k in tree.value):  # `Bins:`: said
            errors.add(JobError(f"{c.path}, line {tree.line}: the job needs its '{req}' list"))
    return top


def _pick_position(c: Checker, top: dict[str, Node]) -> tuple[float, float, float]:
    """The top centre of the pick table [m, W] (the default station when not given)."""
    pick = (0.45, -0.40, 0.20)
    if "pick_station" in top:
        ps = c.mapping(top["pick_station"], "pick_station", dict.fromkeys(PICK_KEYS, ""))
        if "position_m" in ps:
            pick = c.vector(ps["position_m"], "pick_station.position_m", 3)  # type: ignore[assignment]
            if mm := station_millimetres(pick):
                raise c.fail(ps["position_m"], "pick_station.position_m", mm)
            if pick[2] < 0.0:
                raise c.fail(
                    ps["position_m"],
                    "pick_station.position_m",
                    f"the pick table's top at z = {pick[2]} m is under the floor (z = 0 in "
                    "the world frame W, z up): give a height of at least 0",
                )
    return pick


def _bin(c: Checker, bn: Node, fp: str, bins: list[BinSpec], ids: list[str]) -> BinSpec:
    """One bin, checked against the robot base and the bins before it.

    Args:
        c: the checker.
        bn: the bin's node.
        fp: its field path (bins[i]).
        bins: the valid bins already read.
        ids: the ids the bins before it give, valid or not (a bin whose other field is
            wrong still holds its id).

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
    if any(same_text(bid, other) for other in ids):
        raise c.fail(b["id"], f"{fp}.id", f"bin id {bid!r} is used twice")
    pos = c.vector(b["position_m"], f"{fp}.position_m", 2, hint=BIN_HINTS["position_m"])
    size = c.vector(b["size_m"], f"{fp}.size_m", 2, positive=True, hint=BIN_HINTS["size_m"])
    rim = c.number(b["rim_height_m"], f"{fp}.rim_height_m")
    if mm := millimetre_problem(pos, size, rim):  # [1600, 0], a rim of 150: millimetres?
        raise c.fail(bn, fp, mm)
    if rim <= BIN_WALL_M:  # 0 and below too: the valid range is the plate's thickness up
        raise c.fail(
            b["rim_height_m"],
            f"{fp}.rim_height_m",
            f"{rim} m is not above the bin's floor plate, {BIN_WALL_M} m thick: give a rim "
            f"higher than {BIN_WALL_M} m (and at most 1.0 m)",
        )
    clash = placement_problem(bid, pos, size, bins)
    if clash:
        raise c.fail(b["position_m"], f"{fp}.position_m", clash)
    return BinSpec(bid, pos, size, rim)  # type: ignore[arg-type]


def _bins(c: Checker, top: dict[str, Node], errors: Errors) -> tuple[list[BinSpec], list[str]]:
    """The `bins` list, in job order, each bad bin one error.

    Returns:
        (the bins that are valid, the ids every bin gives, valid or not: an item naming
        a bad bin is not told the bin does not exist).
    """
    bins_node = top["bins"]
    if not isinstance(bins_node.value, list) or not bins_node.value:
        raise c.fail(bins_node, "bins", "must be a non-empty list of bins")
    bins: list[BinSpec] = []
    ids: list[str] = []
    for i, bn in enumerate(bins_node.value):
        b = errors.run(_bin, c, bn, f"bins[{i}]", bins, ids)
        if b is not None:
            bins.append(b)
        given = bn.value.get("id") if isinstance(bn.value, dict) else None
        if isinstance(given, Node) and isinstance(given.value, str) and given.value:
            ids.append(given.value)
    return bins, list(dict.fromkeys(ids))


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
                f"unknown catalogue id {oid!r}{nearest(oid, cat) or _file_hint(oid)}; "
                f"valid: {', '.join(cat)}",
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
        mm = max(size) <= 250.0 and min(size) >= 1.0  # each a plausible extent in mm
        raise c.fail(
            it["size_m"],
            f"{fp}.size_m",
            f"extents above 0.25 m do not fit the grip (the largest here {max(size):g} m)"
            + (f": is it {[s_ / 1000.0 for s_ in size]} m written in millimetres?" if mm else ""),
        )
    bad_extents = extents_mismatch(shape, size)
    if bad_extents:
        raise c.fail(it["size_m"], f"{fp}.size_m", bad_extents)
    dense = denser_than_any_solid(mass, size) or lighter_than_air(mass, size)
    if dense:
        raise c.fail(it["mass_kg"], f"{fp}.mass_kg", dense)
    return ObjectParams(shape=shape, mass=mass, size=size, name=f"item{i}_{shape}")  # type: ignore[arg-type]


def _file_hint(oid: str) -> str:
    """What to say of an `object` that names a file (a mesh of the user's own)."""
    if "/" not in oid and "\\" not in oid and "." not in oid:
        return ""
    return (
        " (a file? a job takes no mesh of its own: an item is a catalogue object or an "
        "ad-hoc cube, cuboid, cylinder or sphere of its box, shape, mass_kg and size_m)"
    )


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
    c: Checker, top: dict[str, Node], routing: dict[str, str], bin_ids: list[str], errors: Errors
) -> list[ItemSpec]:
    """The `items` list, in job order, each bad item one error (the valid ones returned)."""
    items_node = top["items"]
    if not isinstance(items_node.value, list) or not items_node.value:
        raise c.fail(items_node, "items", "must be a non-empty list of items")
    cat = catalogue()
    out = [
        errors.run(_item, c, itn, i, cat, routing, bin_ids)
        for i, itn in enumerate(items_node.value)
    ]
    return [it for it in out if it is not None]


def _where(job: Job, tree: Node, top: dict[str, Node]) -> dict[str, str]:
    """ "file, line N" of the job's parts for `cell.jobcheck`'s messages: "cell",
    "pick_station" and "bins[i]" (i the index in `job.bins`)."""

    def bin_id(node: Node) -> str | None:
        v = node.value.get("id") if isinstance(node.value, dict) else None
        return v.value if isinstance(v, Node) and isinstance(v.value, str) else None

    where = {"cell": f"{job.path}, line {top['cell'].line if 'cell' in top else tree.line}"}
    where["pick_station"] = (
        f"{job.path}, line {top['pick_station'].line}" if "pick_station" in top else where["cell"]
    )
    lines = {bin_id(n): n.line for n in top["bins"].value}
    for i, b in enumerate(job.bins):
        where[f"bins[{i}]"] = f"{job.path}, line {lines.get(b.id, tree.line)}"
    return where


def parse_job(text: str, path: str = "<job>", *, check_reach: bool = True) -> Job:
    """Validate a job given as YAML text: every error in one report.

    Each section, bin and item is checked on its own, and the job as a whole against its
    arm (`cell.jobcheck`: a bin under the pick station; with `check_reach`, the arm's
    reach of the station and of the bins it places into); a job with errors is refused
    with all of them, one a line. `limits.max_items` below the items listed is not an
    error: `Job.warnings` says how many are left unsorted.

    Raises:
        JobError: naming, for each error, the file, the line and the field path, and what
            is valid.
    """
    tree = _job_tree(text, path)
    c = Checker(path)
    errors = Errors(path)
    top = errors.run(_top_sections, c, tree, errors) or {}
    cell = errors.run(cell_section, c, top, tree, path)
    pick = errors.run(_pick_position, c, top)
    both = errors.run(_bins, c, top, errors) if "bins" in top else None
    bins, bin_ids = both if both is not None else (None, [])
    routing = errors.run(_routing, c, top, bin_ids) or {}
    items = errors.run(_items, c, top, routing, bin_ids, errors) if "items" in top else None
    policy = (
        errors.run(lambda: c.text(top["policy"], "policy", POLICIES)) if "policy" in top else "auto"
    )
    seed = errors.run(lambda: c.integer(top["seed"], "seed", 0, 2**32 - 1)) if "seed" in top else 0
    limits = errors.run(limits_section, c, top)
    parts = (cell, pick, bins, items, policy, seed, limits)
    if errors.messages and any(p is None for p in parts):
        errors.raise_all()
    assert cell is not None and pick is not None and bins is not None and items is not None
    assert policy is not None and seed is not None and limits is not None
    job = Job(
        path=path,
        robot=cell.robot,
        ee=cell.ee,
        ee_config=cell.ee_config,
        params=cell.params,
        residual=cell.residual,
        pick_position=pick,
        bins=tuple(bins),
        items=tuple(items),
        policy=policy,
        seed=seed,
        place_reach_m=limits[0],
        max_items=limits[1],
        item_time_limit_s=limits[2],
        platform=cell.platform,
        hover_height_m=cell.hover_height_m,
        rotor_rpm=cell.rotor_rpm,
        base_speed_mps=cell.base_speed_mps,
    )
    errors.messages += items_fit(path, items, bins) + residual_problems(
        job, _where(job, tree, top)["cell"]
    )
    reach_warnings: list[str] = []
    if cell.platform == "arm":  # and which of auto's near bins the arm cannot place into
        problems, reach_warnings, thrown = job_problems(job, _where(job, tree, top), check_reach)
        errors.messages += problems
        job = replace(job, thrown_bins=thrown)
    errors.raise_all()
    warnings = unsorted_warning(job) + capacity_warnings(job) + light_item_warnings(job)
    warnings += wide_item_warnings(job) + low_rim_warnings(job)
    warnings += tuple(reach_warnings) + look_alike_warnings(job)
    return replace(job, warnings=warnings)


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
