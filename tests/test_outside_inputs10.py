"""Inputs written by hand as a new user would, a ninth round: names YAML 1.1 reads as
something else (`yes`, `off`, `~`, `010`, `0x10`, `1_000`, `.inf`, `2026-12-01`)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

import cell
from cell.errors import InvalidParameter, JobError
from cell.jobs import load_job, parse_job
from cell.robot.mount import load_mount
from cell.yamlsafe import safe_load

ROOT = Path(cell.__file__).resolve().parents[1]

STATION = "pick_station: {position_m: [0.45, -0.40, 0.20]}\n"


def _job(name: str) -> str:
    return (
        f"cell: {{robot: panda}}\n{STATION}bins:\n"
        f"  - {{id: {name}, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}}\n"
        f"items:\n  - {{object: cube50, bin: {name}}}\n"
    )


@pytest.mark.parametrize(
    ("name", "read_as"),
    [
        ("yes", "a boolean"),
        ("off", "a boolean"),
        ("null", "no value"),
        ("~", "no value"),
        ("0x10", r"a number to YAML \(16\)"),
        ("1_000", r"a number to YAML \(1000\)"),
        (".inf", r"a number to YAML \(inf\)"),
        ("2026-12-01", "a date"),
    ],
)
def test_a_name_yaml_reads_as_another_value_is_quoted_as_written(name: str, read_as: str) -> None:
    """A bin named `yes` was refused as "True must be a non-empty text", `~` as "None …",
    a date as "datetime.date(2026, 12, 1) …", none of them the text the user wrote; a bin
    named `010` was told "8 is a number; … write it in quotes, '8'", a quote that renames
    the bin (`010` is now the text it shows: below). The message now quotes the text as written, says what YAML reads it as and
    to quote it; and the advice is checked by following it: the job with the name in
    quotes loads, the bin's id and the item's bin that very text."""
    with pytest.raises(JobError) as err:
        parse_job(_job(name), "j.yaml", check_reach=False)
    said = str(err.value)
    for field, line in (("bins[0].id", 4), ("items[0].bin", 6)):
        assert re.search(
            rf"j\.yaml, line {line}, {re.escape(field)}: {re.escape(name)} is {read_as}"
            rf".*this is a name: write it in quotes, '{re.escape(name)}'",
            said,
        ), said
    quoted = f"'{name}'"
    job = parse_job(_job(quoted), "j.yaml", check_reach=False)
    assert [b.id for b in job.bins] == [name]
    assert [i.bin for i in job.items] == [name]


def test_a_choice_yaml_reads_as_a_boolean_or_no_value_names_the_choices() -> None:
    """`policy: off` and `shape: null` were "False must be a non-empty text" and "None …";
    they are said as written, with the valid choices; an `id:` left empty "has no value"."""
    text = (
        f"cell: {{robot: panda}}\n{STATION}bins:\n"
        "  - {id: a, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}\n"
        "  - {id: , position_m: [1.4, 0.6], size_m: [0.3, 0.3], rim_height_m: 0.15}\n"
        "items:\n  - {shape: null, mass_kg: 0.05, size_m: [0.05, 0.05, 0.05], bin: a}\n"
        "policy: off\n"
    )
    with pytest.raises(JobError) as err:
        parse_job(text, "j.yaml", check_reach=False)
    said = str(err.value)
    assert "line 5, bins[1].id: has no value: give a name" in said
    assert (
        "line 7, items[0].shape: null is no value to YAML (null; ~ and null are); "
        "choose one of cube, cuboid, cylinder, sphere" in said
    )
    assert "line 8, policy: off is a boolean to YAML" in said
    assert "choose one of auto, place, throw" in said


def _counted(count: str, seed: str = "0", max_items: str = "1000") -> str:
    return (
        f"cell: {{robot: panda}}\n{STATION}bins:\n"
        "  - {id: a, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}\n"
        f"items:\n  - {{object: cube50, bin: a, count: {count}}}\n"
        f"seed: {seed}\nlimits: {{max_items: {max_items}}}\n"
    )


def test_a_number_with_a_leading_zero_is_refused_not_read_as_octal() -> None:
    """`count: 010` was read as 8 items, `seed: 0010` as the seed 8 and `max_items: 0100`
    as 64 (YAML 1.1's octal), without a word; `09` (no octal) as text, "must be a whole
    number (it is in quotes …)" though it was not. Each is now refused saying what YAML
    reads and what to write; the same job written as the message says loads with the
    count, seed and limit the digits say in base ten (counted: the items listed)."""
    with pytest.raises(JobError) as err:
        parse_job(_counted("010", "0010", "0100"), "j.yaml", check_reach=False)
    said = str(err.value)
    assert (
        "line 6, items[0].count: 010 has a leading 0, which YAML reads as the octal number 8: write 10"
        in said
    )
    assert (
        "line 7, seed: 0010 has a leading 0, which YAML reads as the octal number 8: write 10"
        in said
    )
    assert (
        "limits.max_items: 0100 has a leading 0, which YAML reads as the octal number 64: write 100"
        in said
    )
    with pytest.raises(
        JobError, match=r"count: 09 has a leading 0, which YAML reads as text .*write 9"
    ):
        parse_job(_counted("09"), "j.yaml", check_reach=False)
    job = parse_job(_counted("10", "10", "100"), "j.yaml", check_reach=False)
    assert len(job.expanded_items("job")) == 10
    assert (job.seed, job.max_items) == (10, 100)


def test_a_number_yaml_reads_as_a_boolean_or_no_value_is_said_as_written() -> None:
    """`rim_height_m: ~`, `mass_kg: yes` and `seed: null` were "None must be a number",
    "True must be a number", "None must be a whole number …": the text written is said,
    with what YAML reads it as."""
    text = (
        f"cell: {{robot: panda}}\n{STATION}bins:\n"
        "  - {id: a, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: ~}\n"
        "items:\n  - {shape: cube, mass_kg: yes, size_m: [0.05, 0.05, 0.05], bin: a}\n"
        "seed: null\n"
    )
    with pytest.raises(JobError) as err:
        parse_job(text, "j.yaml", check_reach=False)
    said = str(err.value)
    assert (
        "line 4, bins[0].rim_height_m: ~ is no value to YAML (null; ~ and null are); give a number"
        in said
    )
    assert "line 6, items[0].mass_kg: yes is a boolean to YAML" in said
    assert (
        "line 7, seed: null is no value to YAML (null; ~ and null are); give a whole number from 0 to 4294967295"
        in said
    )


def test_a_leading_zero_is_text_in_every_yaml_file_the_cell_reads(tmp_path: Path) -> None:
    """YAML 1.1 reads `010` as the octal 8: a bin named `010` was refused as the number 8
    ("write it in quotes, '8'"), and a mount file's `facing_half_range_deg: 0120` was taken
    as 80° without a word (`cell.yamlsafe`, every job, mount and parameter file). Written
    so, it is now the text it shows: a name keeps it (the bins `010` and `10` are two), a
    number's field refuses it by name (the job's: the test above)."""
    job = parse_job(_job("010"), "j.yaml", check_reach=False)
    assert [b.id for b in job.bins] == ["010"]
    assert safe_load("a: 010\nb: 0x10\nc: 0\nd: 1_000\ne: 010.5\n", "x.yaml") == {
        "a": "010", "b": 16, "c": 0, "d": 1000, "e": 10.5,
    }  # fmt: skip
    text = (ROOT / "robots" / "ur5_throwing" / "mount.yaml").read_text()
    mount = tmp_path / "mount.yaml"
    mount.write_text(text.replace("arm: ur5", "arm: ur5_stand") + "facing_half_range_deg: 0120\n")
    with pytest.raises(InvalidParameter, match=r"facing_half_range_deg' must be a number .*'0120'"):
        load_mount(str(mount))
    mount.write_text(text.replace("arm: ur5", "arm: ur5_stand") + "facing_half_range_deg: 120\n")
    assert load_mount(str(mount)).facing_half_range_rad == pytest.approx(math.radians(120.0))


@pytest.mark.parametrize(
    ("encoding", "said"),
    [
        ("utf-16-le", "UTF-16 (little-endian, without a byte-order mark)"),
        ("utf-16-be", "UTF-16 (big-endian, without a byte-order mark)"),
        ("utf-32-le", "UTF-32 (little-endian, without a byte-order mark)"),
        ("utf-32-be", "UTF-32 (big-endian, without a byte-order mark)"),
    ],
)
def test_a_job_in_utf16_or_utf32_without_its_mark_is_named(
    tmp_path: Path, encoding: str, said: str
) -> None:
    """A job saved as UTF-16 without a byte-order mark decodes as UTF-8 (a NUL is UTF-8)
    and was refused as "not valid YAML (unacceptable character #x0000: special characters
    are not allowed in "<unicode string>", position 1)": the encoding is now named, as a
    log's is. The same text in UTF-8 loads (the judge: Python's own codec wrote the file)."""
    text = _job("a")
    f = tmp_path / "job.yaml"
    f.write_bytes(text.encode(encoding))
    with pytest.raises(JobError, match=re.escape(f"{f}: saved as {said}; a job file is YAML text")):
        load_job(f)
    f.write_bytes(text.encode("utf-8"))
    assert [b.id for b in load_job(f).bins] == ["a"]


def test_a_whole_number_with_an_exponent_or_a_thousands_comma_is_told_what_to_write() -> None:
    """`count: 1e3` (text to YAML 1.1: its exponent has no dot) was "'1e3' must be a whole
    number … (a number with a unit: …)", the `e3` taken for a unit, and `seed: 1.5e3`
    alike; `{count: 1,000}` was told "a decimal comma? … write N.000", which for a count
    is 1.0. Each now says what to write."""
    text = (
        f"cell: {{robot: panda}}\n{STATION}bins:\n"
        "  - {id: a, position_m: [1.4, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}\n"
        "items:\n  - {object: cube50, bin: a, count: 1e3}\n"
        "  - {object: cube50, bin: a, count: 1,000}\nseed: 1.5e3\n"
    )
    with pytest.raises(JobError) as err:
        parse_job(text, "j.yaml", check_reach=False)
    said = str(err.value)
    assert (
        "line 6, items[0].count: '1e3' must be a whole number from 1 to 100000 (written with an exponent: write 1000)"
        in said
    )
    assert (
        "seed: '1.5e3' must be a whole number from 0 to 4294967295 (written with an exponent: write 1500)"
        in said
    )
    assert "a unit" not in said
    assert "write N.000; a thousands separator: write N000)" in said


@pytest.mark.parametrize(
    ("field", "written", "read_as"),
    [
        ("arm", "yes", "a boolean"),
        ("arm", "off", "a boolean"),
        ("arm", "~", "no value"),
        ("arm", "2026-12-01", "a date"),
        ("flange", "on", "a boolean"),
        ("end_effector", "null", "no value"),
    ],
)
def test_a_mount_files_name_yaml_reads_as_another_value_is_said_as_written(
    tmp_path: Path, field: str, written: str, read_as: str
) -> None:
    """A mount file's `arm: yes` was "field 'arm' must be the arm's name (…), got True": the
    value YAML 1.1 made of it, not what was written. It is said as the job's names are
    (`cell.yamltree.not_text`), and written in quotes, the text loads as that name."""
    text = (ROOT / "robots" / "ur5_throwing" / "mount.yaml").read_text()
    old = re.search(rf"^{field}: \S+", text, re.M)
    assert old is not None
    mount = tmp_path / "mount.yaml"
    mount.write_text(text.replace(old.group(0), f"{field}: {written}"))
    with pytest.raises(InvalidParameter) as err:
        load_mount(str(mount))
    msg = str(err.value)
    assert msg.startswith(f"{mount}: field '{field}': {written} is {read_as} to YAML"), msg
    assert f"write it in quotes, '{written}'" in msg and "got " not in msg, msg
    if field == "arm":  # the name's rule said too; in quotes, a valid one loads as written
        assert "lower-case letters" in msg
        if written[0].isalpha():
            mount.write_text(text.replace(old.group(0), f"arm: '{written}'"))
            assert load_mount(str(mount)).name == written
