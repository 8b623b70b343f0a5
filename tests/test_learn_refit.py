"""`cell run --learn` refits the job's objects from the store's earlier throws.

The refit (`cell.identify.refit.refit_objects`) on throws the model itself made with
known η_o, and the whole loop in the PyBullet scene: a run planned with a wrong
effective mass records its throws, the next `cell run --learn` refits from them and
lands closer.
"""

from __future__ import annotations

import json
import math
import sqlite3
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cell.cli import main
from cell.identify.refit import refit_objects, sort_throws
from cell.log.records import throw_record
from cell.log.store import ThrowStore
from cell.log.table import ThrowTable
from cell.model.objects import ObjectParams
from cell.model.throw import ThrowBatch, predict_landing
from cell.params import load_params, save_params, scene_params_path

ADHOC = ObjectParams(shape="cube", mass=0.05, size=(0.045, 0.045, 0.045), name="item0_cube")


def _throws(rng, logged: ObjectParams, true: ObjectParams, n: int, ee, tag: str) -> list[dict]:
    """n throws of `logged` whose landings the model gives for the `true` η_o."""
    out = []
    for i in range(n):
        stroke, el, az = rng.uniform(0.05, 0.10), rng.uniform(0.5, 0.9), rng.uniform(-0.5, 0.5)
        pos = np.array([0.3, 0.0, 0.8]) + rng.normal(0.0, 0.05, 3)
        b = ThrowBatch.build(
            stroke=stroke,
            position=pos,
            elevation=el,
            azimuth=az,
            shape=true.code,
            mass=true.mass,
            size=true.size,
            land_z=0.12,
        )
        xy = predict_landing(b, ee).xy[0]
        out.append(
            throw_record(
                f"{tag}-{i}",
                logged,
                stroke_m=stroke,
                position_m=pos,
                elevation_rad=el,
                azimuth_rad=az,
                land_z_m=0.12,
                landed_xy_m=xy,
                target_bin="far",
            )
        )
    return out


def test_the_refit_recovers_the_effective_mass_that_made_the_landings() -> None:
    params = load_params(scene_params_path())
    assert params.mass_rule is not None and "item0_cube" not in params.objects
    rng = np.random.default_rng(1)
    # an ad-hoc item starts from the mass rule: the truth is 20 % heavier
    rule = params.model_object(ADHOC)
    true_adhoc = replace(rule, mass=rule.mass * 1.2)
    # an identified object starts from the file's η_o: the truth is 20 % lighter
    cube50 = ObjectParams(shape="cube", mass=0.06, size=(0.05, 0.05, 0.05), name="cube50")
    true50 = replace(params.objects["cube50"], mass=params.objects["cube50"].mass * 0.8)
    lone = ObjectParams(shape="sphere", mass=0.04, size=(0.05, 0.05, 0.05), name="lone")
    records = (
        _throws(rng, ADHOC, true_adhoc, 6, params.ee, "a")
        + _throws(rng, cube50, true50, 4, params.ee, "b")
        + _throws(rng, lone, replace(params.model_object(lone), mass=0.02), 1, params.ee, "c")
    )
    table = ThrowTable.from_records(records, path="model-made")

    new, report = refit_objects(table, params, min_throws=2)

    assert math.isclose(new.objects["item0_cube"].mass, true_adhoc.mass, rel_tol=0.02)
    assert math.isclose(new.objects["cube50"].mass, true50.mass, rel_tol=0.02)
    for oid, true in (("item0_cube", true_adhoc), ("cube50", true50)):
        assert np.allclose(new.objects[oid].size, true.size, rtol=0.03)
    # one throw is too few: the object keeps the mass rule, and is not added
    assert "lone" not in new.objects
    assert new.model_object(lone) == params.model_object(lone)
    # everything else is the file's
    assert new.ee == params.ee and new.mass_rule == params.mass_rule
    assert new.effects == params.effects
    for oid, o in params.objects.items():
        if oid != "cube50":
            assert new.objects[oid] == o
    by_id = {r.object_id: r for r in report.objects}
    assert [r.object_id for r in report.refitted] == ["cube50", "item0_cube"]
    assert (by_id["item0_cube"].throws, by_id["cube50"].throws, by_id["lone"].throws) == (6, 4, 1)
    for oid in ("item0_cube", "cube50"):
        r = by_id[oid]
        assert r.rmse_before_m > 0.1 and r.rmse_after_m < 0.01, r
    assert not by_id["lone"].refitted
    assert by_id["lone"].rmse_after_m == by_id["lone"].rmse_before_m
    assert math.isclose(by_id["item0_cube"].mass_before_kg, rule.mass)


def test_the_store_gives_the_sort_throws_of_the_jobs_objects_only(tmp_path: Path) -> None:
    params = load_params(scene_params_path())
    rng = np.random.default_rng(2)
    other_job = replace(ADHOC, mass=0.08)  # another job's item0_cube
    recs = _throws(rng, ADHOC, params.model_object(ADHOC), 4, params.ee, "sort")
    recs += _throws(rng, other_job, params.model_object(other_job), 2, params.ee, "other")
    campaign = _throws(rng, ADHOC, params.model_object(ADHOC), 2, params.ee, "campaign")
    for r in campaign:
        del r["target_bin"]  # a calibration campaign's or `cell synth`'s row
    drone = _throws(rng, ADHOC, params.model_object(ADHOC), 1, params.ee, "drone")
    drone[0]["platform"] = "drone"
    with ThrowStore(tmp_path / "s.sqlite") as store:
        for r in recs + campaign + drone:
            store.append(r)
    # rows spoilt behind the store's back: an infinite release, a landing lost
    con = sqlite3.connect(tmp_path / "s.sqlite")
    con.execute("UPDATE throws SET x_m = 9e999 WHERE throw_id = 'sort-2'")
    con.execute("UPDATE throws SET landed_x_m = NULL WHERE throw_id = 'sort-3'")
    con.commit()
    con.close()
    with ThrowStore(tmp_path / "s.sqlite", read_only=True) as store:
        found = sort_throws(store, {"item0_cube": ADHOC, "cube50": params.objects["cube50"]})
    assert found.table is not None
    assert found.table.text("throw_id") == ["sort-0", "sort-1"]
    assert sum(found.left_out.values()) == 7
    assert found.left_out["another platform"] == 1
    assert found.left_out["not a sort throw (no target_bin)"] == 2
    assert found.left_out["a model column empty or not finite"] == 2
    assert found.left_out["another object of the same id (shape, mass or size)"] == 2


JOB = """
cell: {params: %s}
bins:
  - {id: far, position_m: [1.7, 0.3], size_m: [0.3, 0.3], rim_height_m: 0.12}
items:
  - {shape: cube, mass_kg: 0.05, size_m: [0.045, 0.045, 0.045], count: %d, bin: far}
policy: throw
"""


def _job(tmp: Path, count: int) -> tuple[Path, Path]:
    """A job planned without the mass rule (the item's own mass: its throws land ~0.6 m
    long), and that parameter file."""
    bad = tmp / "no_rule.yaml"
    if not bad.exists():
        save_params(replace(load_params(scene_params_path()), mass_rule=None), bad)
    job = tmp / f"job{count}.yaml"
    job.write_text(JOB % (bad.name, count))
    return job, bad


def _errors(path: Path) -> list[float]:
    return [r["landing_error_m"] for r in json.loads(path.read_text())["results"]]


def test_a_second_learn_run_refits_from_the_first_and_lands_closer(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    job, bad = _job(tmp_path, 2)
    db, out1, out2 = tmp_path / "s.sqlite", tmp_path / "r1.json", tmp_path / "r2.json"
    saved = tmp_path / "refitted.yaml"
    before = bad.read_bytes()

    # the release search and the turn are not what is checked here: off, for speed
    fast = ["--no-cycle-search", "--no-turn-release"]
    assert main(["run", str(job), "--db", str(db), "--learn", "--json", str(out1)] + fast) in (0, 4)
    err1 = capsys.readouterr().err
    assert "no throw store" in err1
    code = main(
        ["run", str(job), "--db", str(db), "--learn", "--json", str(out2)]
        + ["--learn-save", str(saved)]
        + fast
    )
    assert code == 0
    err2 = capsys.readouterr().err

    e1, e2 = _errors(out1), _errors(out2)
    assert len(e1) == len(e2) == 2
    assert e1[0] > 0.3  # the wrong mass throws the first item far off
    # the refit, not only the flywheel: the second run's first throw (no landing of its
    # own run to learn from yet) already lands close, and the run's mean is far lower
    assert e2[0] < 0.5 * e1[0]
    assert np.mean(e2) < 0.5 * np.mean(e1)
    line = next(s for s in err2.splitlines() if "item0_cube: 2 throws" in s)
    assert "landing RMSE" in line
    # the input parameter file is never written; --learn-save has the refit
    assert bad.read_bytes() == before
    refitted = load_params(saved)
    assert "item0_cube" in refitted.objects and refitted.mass_rule is None
    assert refitted.objects["item0_cube"].mass < 0.05 * 0.9  # lighter than its own mass
    with ThrowStore(db, read_only=True) as store:
        assert len(store) == 4


def test_learn_save_refuses_the_input_file_and_odd_stores_do_not_stop_a_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    job, bad = _job(tmp_path, 1)
    before = bad.read_bytes()
    assert main(["run", str(job), "--no-log", "--learn", "--learn-save", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "--learn-save" in err and "parameter file this run reads" in err
    assert bad.read_bytes() == before
    assert main(["run", str(job), "--no-log", "--learn-save", str(tmp_path / "x.yaml")]) == 2
    assert "add --learn" in capsys.readouterr().err
    # not a store at all: the refit says so and the run (not recording) goes on
    junk = tmp_path / "junk.sqlite"
    junk.write_bytes(b"not an sqlite file, just bytes" * 10)
    out = tmp_path / "r.json"
    fast = ["--no-cycle-search", "--no-turn-release"]  # the run is not what is checked
    code = main(
        ["run", str(job), "--db", str(junk), "--no-log", "--learn", "--json", str(out)] + fast
    )
    err = capsys.readouterr().err
    assert code in (0, 4) and "cannot refit from" in err and str(junk) in err
    assert len(_errors(out)) == 1
