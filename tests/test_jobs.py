"""Sort-job files: the demo loads; every kind of bad field is named with file, line and path."""

from pathlib import Path

import pytest

from cell.errors import JobError
from cell.jobs import load_job, parse_job

TASKS = Path(__file__).resolve().parents[1] / "tasks"

GOOD = """\
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.3, 0.3], rim_height_m: 0.12}
  - {id: far, position_m: [2.0, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cube50, count: 2, bin: far}
  - {shape: sphere, mass_kg: 0.03, size_m: [0.04, 0.04, 0.04]}
routing: {sphere: near}
"""


def test_demo_job_meets_its_brief():
    job = load_job(TASKS / "bins.yaml")
    items = job.expanded_items()
    assert len(items) >= 24
    assert len({i.obj.name for i in items}) >= 8
    assert sum(i.obj.shape == "mesh" for i in job.items) >= 2
    dist = sorted((b.position[0] ** 2 + b.position[1] ** 2) ** 0.5 for b in job.bins)
    assert len(dist) >= 4 and dist[0] >= 0.5 and dist[-1] <= 3.0
    assert sum(d > job.place_reach_m for d in dist) >= 2


def test_every_task_file_loads():
    for path in TASKS.glob("*.yaml"):
        load_job(path)


def test_good_job_with_routing():
    job = parse_job(GOOD, "j.yaml")
    assert [i.bin for i in job.expanded_items()] == ["far", "far", "near"]
    assert job.policy == "auto" and job.robot == "panda"


@pytest.mark.parametrize(
    "old, new, where",
    [
        ("count: 2", "count: two", "line 5, items[0].count"),
        ("count: 2", "count: 2, colour: red", "line 5, items[0].colour"),
        ("mass_kg: 0.03", "mass_kg: 0", "line 6, items[1].mass_kg"),
        ("object: cube50", "object: cube99", "line 5, items[0].object"),
        ("position_m: [2.0, 0.0]", "position_m: [0.1, 0.0]", "line 3, bins[1].position_m"),
        ("position_m: [2.0, 0.0]", "position_m: [0.7, 0.35]", "line 3, bins[1].position_m"),
        ("rim_height_m: 0.15", "rim_height_m: -1", "line 3, bins[1].rim_height_m"),
        ("bin: far", "bin: nowhere", "line 5, items[0].bin"),
        ("routing: {sphere: near}", "routing: {sphere: near}\npolicy: yeet", "line 8, policy"),
        ("routing: {sphere: near}", "", "line 6, items[1]"),
    ],
)
def test_bad_fields_are_named(old, new, where):
    with pytest.raises(JobError) as exc:
        parse_job(GOOD.replace(old, new), "j.yaml")
    assert str(exc.value).startswith(f"j.yaml, {where}")


def test_yaml_tags_are_never_executed(tmp_path):
    marker = tmp_path / "pwned"
    text = f'bins: !!python/object/apply:os.system ["touch {marker}"]\nitems: []\n'
    with pytest.raises(JobError, match="tag"):
        parse_job(text, "evil.yaml")
    assert not marker.exists()


def test_missing_file_and_empty_file(tmp_path):
    with pytest.raises(JobError, match="no such job file"):
        load_job(tmp_path / "nope.yaml")
    (tmp_path / "empty.yaml").write_text("")
    with pytest.raises(JobError, match="empty"):
        load_job(tmp_path / "empty.yaml")


def test_a_list_where_a_number_belongs_is_quoted_by_its_values():
    """The message shows what the file says ([1, 2]), not the reader's internal nodes."""
    import re

    from cell.errors import JobError
    from cell.jobs import parse_job

    text = """
bins:
  - {id: a, position_m: [1.5, 0.0], size_m: [0.3, 0.3], rim_height_m: [1, 2]}
items:
  - {object: cube50, bin: a}
"""
    with pytest.raises(JobError) as err:
        parse_job(text, "job.yaml")
    msg = str(err.value)
    assert "[1, 2] must be a number" in msg and "rim_height_m" in msg, msg
    assert not re.search(r"object at 0x", msg)


def test_a_bin_id_used_twice_is_named_even_when_its_first_bin_is_wrong():
    """A bin with a bad field still holds its id: a second bin with that id is the second error."""
    text = GOOD.replace("rim_height_m: 0.12", "rim_height_m: -1").replace("id: far", "id: near")
    with pytest.raises(JobError) as exc:
        parse_job(text, "j.yaml")
    lines = str(exc.value).splitlines()
    assert lines[0] == "j.yaml: 3 errors:", lines
    assert any("line 2, bins[0].rim_height_m" in ln for ln in lines)
    assert any("line 3, bins[1].id: bin id 'near' is used twice" in ln for ln in lines)
    # the item sent to the bin renamed away is told the bins there are
    assert any("line 5, items[0].bin: 'far' is not valid; choose one of near" in ln for ln in lines)
