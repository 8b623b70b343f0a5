"""The README and the user's guide under docs/: the README stays a five-minute read, every
relative link resolves, the job-format page's example runs, and what the guide pages say of
the code (the job keys with their defaults and bounds, the throw-log columns and ranges, the
diagnosis's vocabulary and rules) is what the code does. The figures they quote are checked
in tests/test_readme_figures.py."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from cell.cli import main
from cell.errors import JobError
from cell.jobs import ROBOT_BASE_CLEARANCE_M, parse_job
from cell.jobschema import job_keys

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
README_MAX_LINES = 250


def _read(rel: str) -> str:
    return (ROOT / rel).read_text()


def test_the_readme_is_at_most_250_lines() -> None:
    n = len(_read("README.md").splitlines())
    assert n <= README_MAX_LINES, f"README.md has {n} lines; the front door keeps to 250"


# -- links -----------------------------------------------------------------------------------
def _anchors(text: str) -> set[str]:
    """GitHub's anchors for a page's headings: lower case, punctuation dropped, spaces to -."""
    out: set[str] = set()
    fence = False
    for line in text.splitlines():
        if line.startswith("```"):
            fence = not fence
        elif not fence and (m := re.match(r"#{1,6} +(.*)", line)):
            slug = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
            base, k = slug, 1
            while slug in out:
                slug, k = f"{base}-{k}", k + 1
            out.add(slug)
    return out


def _links(text: str) -> list[str]:
    """The targets of a page's markdown links and images, outside code."""
    prose = re.sub(r"```.*?```", "", text, flags=re.S)
    prose = re.sub(r"`[^`\n]*`", "", prose)
    return re.findall(r"\]\(([^)\s]+)\)", prose)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_resolves(page: Path) -> None:
    bad = []
    for target in _links(page.read_text()):
        if re.match(r"[a-z]+:", target):
            continue  # a web address
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            bad.append(f"{target}: no such file")
        elif anchor and anchor not in _anchors(dest.read_text()):
            bad.append(f"{target}: no heading #{anchor} in {dest.name}")
    assert not bad, f"{page.name}: " + "; ".join(bad)


def test_the_link_check_can_fail() -> None:
    assert "the-sort-job-format" in _anchors(_read("docs/jobs.md"))
    assert "no-such-heading" not in _anchors(_read("docs/jobs.md"))
    assert _links("see [a](b.md#c) and `[d](e.md)`") == ["b.md#c"]


# -- the sort-job format ---------------------------------------------------------------------
def _yaml_blocks(rel: str) -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", _read(rel), flags=re.S)


def _run(job_text: str, tmp_path: Path) -> dict[str, Any]:
    job = tmp_path / "job.yaml"
    job.write_text(job_text)
    out = tmp_path / "out.json"
    assert main(["run", str(job), "--no-log", "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_the_annotated_example_job_runs_as_the_page_describes_it(tmp_path: Path) -> None:
    (text,) = _yaml_blocks("docs/jobs.md")
    job = parse_job(text, "docs/jobs.md")
    assert [(i.obj.name, i.count, i.bin) for i in job.items] == [
        ("cube50", 1, "far"),
        ("item1_cylinder", 2, "near"),  # routed by its shape
    ]
    summary = _run(text, tmp_path)
    assert summary["items"] == 3 and summary["in_bin"] == 3
    actions = {r["object_id"]: r["action"] for r in summary["results"]}
    assert actions == {"cube50": "throw", "item1_cylinder": "place"}  # far thrown, near placed


def test_the_readme_describes_the_demo_job_as_it_is() -> None:
    from cell.catalogue import catalogue
    from cell.jobs import load_job

    job = load_job(ROOT / "tasks" / "bins.yaml")
    words = ("zero one two three four five six seven eight nine ten").split()
    objects = {i.obj.name for i in job.items}
    meshes = sorted(i.obj.name for i in job.items if i.obj.shape == "mesh")
    near = [b for b in job.bins if math.hypot(*b.position) <= job.place_reach_m]
    text = " ".join(_read("README.md").split())
    assert (
        f"items of {words[len(objects)]} catalogue objects (two of them meshes the cell was "
        f"never calibrated on, a {meshes[0]} and a {meshes[1]}) into {words[len(job.bins)]} "
        f"open bins, {words[len(near)]} within the arm's reach (placed) and "
        f"{words[len(job.bins) - len(near)]} beyond it (thrown)"
    ) in text
    assert len(meshes) == 2 and {catalogue()[m].set for m in meshes} == {"unseen"}


def test_the_readme_first_job_runs(tmp_path: Path) -> None:
    (text,) = _yaml_blocks("README.md")
    assert len(text.splitlines()) <= 10, "the README's first job is ten lines at most"
    summary = _run(text, tmp_path)
    assert summary["items"] == 3 and summary["in_bin"] == 3


def _documented_keys() -> list[str]:
    """The keys in the first column of the job page's key table (`routing.a`, `routing.b`
    in one cell count as each)."""
    section = _read("docs/jobs.md").split("## Every key", 1)[1].split("\n## ", 1)[0]
    keys: list[str] = []
    for line in section.splitlines():
        if line.startswith("| `"):
            keys.extend(re.findall(r"`([^`]+)`", line.split("|")[1]))
    return keys


def test_every_key_the_parser_accepts_is_documented_and_no_other() -> None:
    documented = _documented_keys()
    assert sorted(documented) == sorted(job_keys())


def _row(key: str) -> list[str]:
    section = _read("docs/jobs.md").split("## Every key", 1)[1]
    for line in section.splitlines():
        if line.startswith(f"| `{key}` |"):
            return [c.strip() for c in line.strip("|").split("|")]
    raise AssertionError(f"docs/jobs.md has no row for {key}")


MINIMAL = {
    "bins": [{"id": "far", "position_m": [1.5, 0.0], "size_m": [0.3, 0.3], "rim_height_m": 0.15}],
    "items": [{"object": "cube50", "bin": "far"}],
}
# key -> (where the value goes in a job, the Job attribute or item field it sets, the
# platform the key needs)
NUMERIC: dict[str, tuple[tuple[Any, ...], str, str]] = {
    "cell.drone.hover_height_m": (("cell", "drone", "hover_height_m"), "hover_height_m", "drone"),
    "cell.drone.rotor_rpm": (("cell", "drone", "rotor_rpm"), "rotor_rpm", "drone"),
    "cell.mobile.speed_mps": (("cell", "mobile", "speed_mps"), "base_speed_mps", "mobile"),
    "bins[].rim_height_m": (("bins", 0, "rim_height_m"), "", "arm"),
    "items[].mass_kg": (("items", 0, "mass_kg"), "", "arm"),
    "items[].count": (("items", 0, "count"), "", "arm"),
    "seed": (("seed",), "seed", "arm"),
    "limits.place_reach_m": (("limits", "place_reach_m"), "place_reach_m", "arm"),
    "limits.max_items": (("limits", "max_items"), "max_items", "arm"),
    "limits.item_time_limit_s": (("limits", "item_time_limit_s"), "item_time_limit_s", "arm"),
}


def _job_with(path: tuple[Any, ...], value: Any, platform: str) -> str:
    job: dict[str, Any] = json.loads(json.dumps(MINIMAL))
    if platform != "arm":
        job["cell"] = {"platform": platform}
    if path[0] == "items" and path[2] == "mass_kg":
        job["items"][0] = {"shape": "cube", "size_m": [0.05, 0.05, 0.05], "bin": "far"}
    node = job
    for k in path[:-1]:
        if isinstance(k, str):
            node = node.setdefault(k, {})
        else:
            node = node[k]
    node[path[-1]] = value
    return yaml.safe_dump(job)


def _accepts(path: tuple[Any, ...], value: Any, platform: str) -> bool:
    try:
        parse_job(_job_with(path, value, platform))
    except JobError:
        return False
    return True


@pytest.mark.parametrize("key", sorted(NUMERIC))
def test_the_documented_bounds_and_defaults_are_the_parsers(key: str) -> None:
    path, attr, platform = NUMERIC[key]
    _, _, default, bounds = _row(key)[:4]
    m = re.fullmatch(r"`([\[(])([-\d.]+), ([-\d.]+)\]`", bounds) or re.fullmatch(
        r"at least `([-\d.]+)`", bounds
    )
    assert m, f"{key}: bounds {bounds!r} not in a form this test reads"
    integer = key in ("items[].count", "seed", "limits.max_items")
    if len(m.groups()) == 1:
        lo, hi, closed_lo = float(m.group(1)), math.inf, True
    else:
        lo, hi, closed_lo = float(m.group(2)), float(m.group(3)), m.group(1) == "["
    step = 1 if integer else 1e-6 * max(1.0, abs(hi) if math.isfinite(hi) else abs(lo))

    def v(x: float) -> Any:
        return int(x) if integer else x

    assert _accepts(path, v(lo), platform) == closed_lo, f"{key}: {lo}"
    assert not _accepts(path, v(lo - step), platform), f"{key}: below {lo}"
    if math.isfinite(hi):
        assert _accepts(path, v(hi), platform), f"{key}: {hi}"
        assert not _accepts(path, v(hi + step), platform), f"{key}: above {hi}"
    if attr:
        job = parse_job(_job_with(("seed",), 0, platform))
        assert default == f"`{getattr(job, attr)}`", f"{key}: the parser's default"
    elif key == "items[].count":
        job = parse_job(_job_with(("seed",), 0, platform))
        assert default == f"`{job.items[0].count}`"


def test_the_other_documented_defaults_are_the_parsers() -> None:
    job = parse_job(yaml.safe_dump(MINIMAL))
    for key, value in (
        ("cell.robot", job.robot),
        ("cell.ee", job.ee),
        ("cell.platform", job.platform),
        ("policy", job.policy),
        ("pick_station.position_m", json.dumps(list(job.pick_position))),
    ):
        assert _row(key)[2] == f"`{value}`", key


def test_the_documented_limits_are_the_codes() -> None:
    from cell import yamlsafe
    from cell.loop import FAILURES

    page = _read("docs/jobs.md")
    assert f"`ROBOT_BASE_CLEARANCE_M` is `{ROBOT_BASE_CLEARANCE_M}`" in page
    for name in ("MAX_BYTES", "MAX_DEPTH", "MAX_NODES"):
        assert f"`{name}` (`{getattr(yamlsafe, name)}`" in page, name
    size = json.loads(json.dumps(MINIMAL))
    size["items"] = [{"shape": "cube", "mass_kg": 0.05, "size_m": [0.05, 0.05, 0.25], "bin": "far"}]
    parse_job(yaml.safe_dump(size))
    size["items"][0]["size_m"][2] = 0.251
    with pytest.raises(JobError, match="0.25 m"):
        parse_job(yaml.safe_dump(size))
    assert "extents over `0.25` m" in page
    reasons = page.split("gets one reason in the results table", 1)[1]
    for reason in FAILURES:
        assert f"`{reason}`" in reasons, reason


# -- the throw-log format --------------------------------------------------------------------
def _table_rows(rel: str, after: str) -> list[list[str]]:
    section = _read(rel).split(after, 1)[1]
    rows = []
    for line in section.splitlines():
        if not line.startswith("|"):
            if rows:
                break
            continue
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows[2:]


def _value(cell: str) -> float:
    """A table cell's number: `20`, `-1000`, `pi/2`, `-2 pi`."""
    m = re.fullmatch(r"`(-?)([\d.]*) ?(pi)?(?:/(\d+))?`", cell)
    assert m, cell
    sign, k, pi, div = m.groups()
    x = (float(k) if k else 1.0) * (math.pi if pi else 1.0) / (float(div) if div else 1.0)
    return -x if sign else x


def test_the_throw_log_page_is_the_readers_contract() -> None:
    from cell.log import csvio, store
    from cell.log.table import RANGES, REQUIRED_COLUMNS

    rows = _table_rows("docs/throw_log.md", "## throws.csv")
    columns = [c for r in rows for c in re.findall(r"`([a-z_]+)`", r[0])]
    assert columns == list(REQUIRED_COLUMNS)
    page = _read("docs/throw_log.md")
    optional = page.split("Optional columns", 1)[1].split("\n\n", 1)[0]
    assert set(re.findall(r"`([a-z_]+)`", optional)) == set(
        store.OPTIONAL_TEXT + store.OPTIONAL_NUM
    )
    documented: dict[str, tuple[float, float]] = {}
    for cols, lo, hi in _table_rows("docs/throw_log.md", "a value outside"):
        bounds = (_value(lo), _value(hi))
        for c in re.findall(r"`([a-z_]+)`", cols):
            documented[c] = bounds  # type: ignore[assignment]
    assert set(documented) == set(RANGES)
    for c, (lo, hi) in RANGES.items():
        assert documented[c] == pytest.approx((lo, hi)), c
    assert f"`MAX_CSV_BYTES` (`{csvio.MAX_CSV_BYTES}` bytes)" in page
    from cell.gap.run import MIN_THROWS

    assert f"`MIN_THROWS` (`{MIN_THROWS}`)" in page
    assert f"`0x{store.APPLICATION_ID:08X}`" in page


# -- the diagnosis ---------------------------------------------------------------------------
def test_the_diagnosis_page_names_the_codes_effects_and_rules() -> None:
    from cell.gap import diagnose
    from cell.model.effects import EFFECTS, FAMILIES

    rows = _table_rows("docs/diagnosis.md", "## The effects")
    documented = {r[0].strip("`"): r[1] for r in rows}
    assert documented == {
        **{name: cls.phase for name, cls in EFFECTS.items()},
        "none": "—",
        "unknown": "—",
    }
    assert set(FAMILIES) == set(EFFECTS)
    page = _read("docs/diagnosis.md")
    for name in ("NONE_RATIO", "VERDICT_RATIO", "MIN_CUT", "PERM_SHARE"):
        assert hasattr(diagnose, name) and f"`{name}`" in page, name


def test_the_report_keys_are_the_reports() -> None:
    documented = [
        r[0].strip("`") for r in _table_rows("docs/diagnosis.md", "## Reading the report")
    ]
    page = _read("docs/diagnosis.md")
    where = page[page.index("keys appear only where they apply") :].split("\n\n")[0]
    sometimes = set(re.findall(r"`([a-z_]+)` where", where))
    assert sometimes == {
        "proposal",
        "wind_throw_to_throw",
        "parameter_throw_to_throw",
        "one_configuration",
        "wind_not_steady",
        "flight_bends",
        "parameter_drifts",
        "landing_step",
        "proposal_vs_verdict",
    }
    for name in ("nominal", "identified"):
        report = json.loads((ROOT / "docs" / "scene_gap" / f"{name}.json").read_text())
        # the table's keys are in every report; any other key is one of those that appear
        # only where they apply
        assert set(documented) <= set(report), name
        assert set(report) - set(documented) <= sometimes, name


def test_the_hardware_page_gives_the_codes_exit_code() -> None:
    from cell.cli.cmd_run import EXIT_HARDWARE_FAULT

    assert f"exit code `{EXIT_HARDWARE_FAULT}`" in _read("docs/hardware.md")


def test_the_help_texts_point_to_the_repositorys_throw_log_page() -> None:
    for path in (ROOT / "cell").rglob("*.py"):
        assert "THROW_LOG.md" not in path.read_text(), f"{path} points to THROW_LOG.md"
    assert (ROOT / "docs" / "throw_log.md").is_file()
