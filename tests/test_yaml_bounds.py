"""User YAML (jobs, parameter files, Dynamixel configurations) is bounded before anything is
built: alias bombs, deep nesting, huge files and huge counts are refused with a named error,
in little memory."""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest

from cell.cli import main
from cell.errors import InvalidInput, JobError
from cell.jobs import load_job, parse_job
from cell.params import load_params

BOMB = "\n".join(
    ["a: &a [x, x, x, x, x, x, x, x, x, x]"]
    + [f"{chr(98 + k)}: &{chr(98 + k)} [{', '.join(['*' + chr(97 + k)] * 10)}]" for k in range(8)]
)  # 10^9 leaves if expanded

JOB = """\
bins:
  - {id: far, position_m: [2.0, 0.0], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cube50, bin: far, count: COUNT}
"""


def _peak_mb(fn) -> float:  # type: ignore[no-untyped-def]
    tracemalloc.start()
    try:
        fn()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak / 1e6


@pytest.mark.parametrize("kind", ["job", "params", "dynamixel"])
def test_an_alias_bomb_is_refused_unexpanded(kind: str, tmp_path: Path) -> None:
    f = tmp_path / f"{kind}.yaml"
    f.write_text(BOMB + "\n")

    def load() -> None:
        if kind == "job":
            load_job(f)
        elif kind == "params":
            load_params(f)
        else:
            from cell.endeffector.dynamixel import load_config

            load_config(f)

    def refused() -> None:
        with pytest.raises(InvalidInput, match=r"line 2: YAML aliases \(\*a\) are not accepted"):
            load()

    assert _peak_mb(refused) < 100.0


def test_deep_nesting_and_huge_files_are_refused(tmp_path: Path) -> None:
    with pytest.raises(JobError, match="nested deeper than 32"):
        parse_job("items: " + "[" * 200 + "]" * 200, "deep.yaml")
    big = tmp_path / "big.yaml"
    big.write_text("note: '" + "x" * 2_000_000 + "'\n")
    with pytest.raises(InvalidInput, match="at most 1000000"):
        load_params(big)
    with pytest.raises(JobError, match="is a folder"):
        load_job(tmp_path)
    binary = tmp_path / "bin.yaml"
    binary.write_bytes(bytes(range(128, 256)) * 4)
    with pytest.raises(InvalidInput, match="not a text file"):
        load_params(binary)


def test_a_huge_count_is_refused_and_max_items_caps_without_building(tmp_path: Path) -> None:
    with pytest.raises(JobError, match=r"items\[0\].count: 10000000000 must be a whole number"):
        parse_job(JOB.replace("COUNT", "10000000000"), "j.yaml")
    job = parse_job(JOB.replace("COUNT", "100000") + "limits: {max_items: 7}\n", "j.yaml")
    assert len(job.expanded_items()) == 7
    assert _peak_mb(job.expanded_items) < 1.0


def test_scientific_notation_is_a_number_in_jobs_as_in_parameter_files(tmp_path: Path) -> None:
    job = parse_job(
        JOB.replace("COUNT", "1").replace("rim_height_m: 0.15", "rim_height_m: 15e-2"), "j.yaml"
    )
    assert job.bins[0].rim_height == pytest.approx(0.15)
    p = tmp_path / "p.yaml"
    p.write_text("end_effector: {dt: 12e-3}\n")
    assert load_params(p).ee.dt == pytest.approx(0.012)


def test_the_cli_names_the_bomb_without_a_traceback(tmp_path: Path, capsys) -> None:
    f = tmp_path / "job.yaml"
    f.write_text(BOMB + "\n")
    assert main(["run", str(f), "--no-log"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"cell: error: {f}, line 2: YAML aliases") and "Traceback" not in err


def test_a_text_read_again_gives_a_fresh_equal_value_and_a_bad_one_names_each_file() -> None:
    # safe_load keeps the values of texts it read (the mount files every scene reads):
    # a caller changing what it got changes nothing the next caller gets
    import yaml

    from cell.yamlsafe import safe_load

    text = "arm: panda\nhome: [0.0, -0.5, 0.0]\nnested: {a: [1, 2], b: 2026-11-29}\n"
    for name in ("a.yaml", "b.yaml", "c.yaml"):
        got = safe_load(text, name)
        assert got == yaml.safe_load(text)
        got["home"].append(9.0)
        got["nested"]["a"].clear()
    for name in ("d.yaml", "e.yaml"):  # a refused text is checked, and named, each time
        with pytest.raises(InvalidInput, match=f"^{name}, line 2: YAML aliases"):
            safe_load("a: &x [1]\nb: *x\n", name)
