"""`cell run --record`: a Rerun recording of a sort run, read back with Rerun's own reader and
checked against the run's JSON; without --record nothing from rerun is imported and the run
is the same."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cell.cli import main
from cell.record.read import read_rows

# "edge": within the job's place reach, its centre, where a place goes first, beyond the arm's
# reach pointing down (27 mm), the place's own spot nearest the base within it (the job
# check's pose: the bin is placed into, not thrown into): the first cube50 is set down there,
# the second, with that spot taken, finds none it reaches and fails IK when it is planned,
# an item failed in the run that the job check cannot know of (it checks an empty bin).
# "near" is sent nothing (a cyl70 placed there, a second place beside the first cube50's,
# cost 1.2 CPU-s a run): a bin the run leaves empty is drawn all the same
JOB = """\
cell: {robot: panda}
limits: {place_reach_m: 1.0}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
  - {id: edge, position_m: [0.00, 0.85], size_m: [0.30, 0.30], rim_height_m: 0.12}
items:
  - {object: cube50, count: 1, bin: far}
  - {object: cube50, count: 2, bin: edge}
  - {object: duck, count: 1, bin: far}
"""
BINS = {
    "near": (0.55, 0.30, 0.12),
    "far": (1.40, 0.00, 0.15),
    "edge": (0.0, 0.85, 0.12),
}  # centre x, y, rim height [m]
F32 = 2e-6  # [m] Rerun stores positions as float32

# the run without --record, what it imported, then the same job recorded in the same fresh
# process (a run is the same bytes after another job in a process: tests/test_same_result.py);
# without the turn, the cube thrown first into "far" rests where the duck thrown after it is
# aimed clear of it, off the bin's centre: the recording must draw that aim
NO_RECORD_THEN_RECORD = """\
import json, sys
from cell.cli import main
code = main(["run", sys.argv[1], "--no-log", "--no-turn-release", "--json", sys.argv[2]])
rerun = sorted(m for m in sys.modules if m.startswith("rerun"))
again = main(["run", sys.argv[1], "--no-log", "--no-turn-release", "--json", sys.argv[3],
              "--record", sys.argv[4]])
print(json.dumps({"code": code, "rerun": rerun, "recorded": again}))
"""


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict, dict, dict, Path]:
    d = tmp_path_factory.mktemp("record_run")
    job = d / "job.yaml"
    job.write_text(JOB)
    plain, recorded, rrd = d / "plain.json", d / "recorded.json", d / "run.rrd"
    p = subprocess.run(
        [
            sys.executable,
            "-c",
            NO_RECORD_THEN_RECORD,
            str(job),
            str(plain),
            str(recorded),
            str(rrd),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stderr
    flags = json.loads(p.stdout.strip().splitlines()[-1])
    assert flags.pop("recorded") == 0, p.stderr
    return flags, json.loads(plain.read_text()), json.loads(recorded.read_text()), rrd


def _at_item(rows: list[dict], i: int) -> list[dict]:
    return [r for r in rows if r.get("item") == i]


def test_without_record_nothing_from_rerun_is_imported_and_the_run_is_the_same(runs) -> None:
    flags, plain, recorded, _ = runs
    assert flags == {"code": 0, "rerun": []}
    strip = ("throw_id", "wall_time_s", "plan_s")  # the run's name, wall-clock figures
    for a, b in zip(plain["results"], recorded["results"], strict=True):
        assert {k: v for k, v in a.items() if k not in strip} == {
            k: v for k, v in b.items() if k not in strip
        }
    assert plain["sim_time_s"] == recorded["sim_time_s"]


def test_the_scene_arm_and_items_are_entities_on_both_timelines(runs) -> None:
    _, _, summary, rrd = runs
    rows = read_rows(rrd)
    for bin_id, (x, y, rim) in BINS.items():
        box = rows[f"/world/bins/{bin_id}"][0]
        assert box["Boxes3D:labels"] == [bin_id]
        assert np.allclose(box["Boxes3D:centers"][0], (x, y, rim / 2), atol=F32)
    assert rows["/world/pick_station"][0]["Boxes3D:labels"] == ["pick station"]
    assert "/world/floor" in rows
    meshes = [e for e in rows if e.startswith("/world/arm/") and e.endswith("/mesh")]
    assert len(meshes) >= 8  # the Panda's links (base and 7)
    assert any(e.startswith("/world/end_effector/link") for e in rows)
    joints = rows["/arm/joint_angles_rad"]
    assert all(len(r["Scalars:scalars"]) == 7 for r in joints)
    t = [r["sim_time"] for r in joints]
    # the scene's clock runs on through flights and settling; the summary counts arm time
    # the poses cover the whole run, to within one 30 Hz frame of its end
    assert t == sorted(t) and t[-1] > summary["sim_time_s"] - 1 / 30
    assert np.all(np.diff(t) < 0.04)  # sampled at 30 Hz of simulated time
    for r in summary["results"]:
        ent = f"/world/items/{r['index']:03d}_{r['object_id']}"
        poses = rows[ent]
        assert len(poses) > (1 if r["action"] == "failed" else 20)
        assert {p["item"] for p in poses} == {r["index"]}
    assert "Clear:is_recursive" in str(rows["/world/items/000_cube50"][-1])
    assert "| items | 4 |" in rows["/summary"][0]["TextDocument:text"][0]


def test_every_item_lands_in_the_recording_as_in_the_json(runs) -> None:
    _, _, summary, rrd = runs
    rows = read_rows(rrd)
    assert [r["action"] for r in summary["results"]] == ["throw", "place", "failed", "throw"]
    assert [r["target_bin"] for r in summary["results"][1:3]] == ["edge", "edge"]
    (duck,) = rows["/world/landing/003/target"]
    assert np.hypot(*(np.subtract(duck["Points3D:positions"][0][:2], BINS["far"][:2]))) > 0.02
    for r in summary["results"]:
        i = r["index"]
        texts = [t["TextLog:text"][0] for t in _at_item(rows["/log"], i)]
        if r["action"] == "failed":  # the reason as a text entry; no landing, no figures
            (err,) = [t for t in _at_item(rows["/log"], i) if t["TextLog:level"] == ["ERROR"]]
            assert r["reason"].startswith("IK") and r["reason"] in err["TextLog:text"][0]
            assert f"/world/landing/{i:03d}" not in rows
            assert _at_item(rows["/items/landing_error_m"], i) == []
            (cyc,) = _at_item(rows["/items/cycle_time_s"], i)
            assert cyc["Scalars:scalars"] == [r["cycle_time_s"]]
            continue
        for name in ("landing_error_m", "stroke_m", "cycle_time_s"):
            (row,) = _at_item(rows[f"/items/{name}"], i)
            assert row["Scalars:scalars"] == [r[name]]  # the very value, not a rounding
        (land,) = rows[f"/world/landing/{i:03d}"]
        x, y, z = land["Points3D:positions"][0]
        cx, cy, rim = BINS[r["target_bin"]]
        (target,) = rows[f"/world/landing/{i:03d}/target"]
        bx, by, bz = target["Points3D:positions"][0]
        # the point it was for: a place's is the bin's centre, as is a throw's into an
        # empty bin (the first into each); a later throw's lies on the rim plane, inside
        # the rim (cell.arm.spots.throw_spot moves it clear of what the bin holds)
        first = r["target_bin"] not in [q["target_bin"] for q in summary["results"][:i]]
        if r["action"] == "place" or first:
            assert np.allclose((bx, by, bz), (cx, cy, rim), atol=F32)
        assert bz == pytest.approx(rim, abs=F32)
        assert abs(bx - cx) < 0.15 and abs(by - cy) < 0.15  # the bins are 0.30 m wide
        # the landing point lies at the JSON's landing error from that point
        assert np.hypot(x - bx, y - by) == pytest.approx(r["landing_error_m"], abs=F32)
        assert any(f"in bin {r['bin_id']}" in s for s in texts)
        if r["action"] == "throw":
            assert z == pytest.approx(rim, abs=F32)  # the rim-plane crossing
            (obs,) = rows[f"/world/flight/{i:03d}/observed"]
            (pred,) = rows[f"/world/flight/{i:03d}/predicted"]
            track = np.asarray(obs["LineStrips3D:strips"][0])
            # the observed flight passes through the landing point (1 ms samples)
            assert np.min(np.linalg.norm(track - (x, y, z), axis=1)) < 0.01
            # the model's flight was planned onto that point
            end = np.asarray(pred["LineStrips3D:strips"][0])[-1]
            assert np.allclose(end, (bx, by, rim), atol=0.01)
            (rel,) = rows[f"/world/release/{i:03d}"]
            # the planned release point against where the item's centre of mass was at
            # release: the duck, held at its neck, turns in the pads while carried (its
            # centre of mass moved 20 mm); the boxes stay within 1 cm
            tol = 0.03 if r["object_id"] == "duck" else 0.01
            assert np.allclose(rel["Arrows3D:origins"][0], track[0], atol=tol)
        else:
            assert f"/world/flight/{i:03d}/predicted" not in rows


def test_a_recording_needs_the_arm_platform_and_a_file_name(tmp_path, capsys) -> None:
    job = tmp_path / "job.yaml"
    job.write_text(JOB)
    assert main(["run", str(job), "--no-log", "--record", str(tmp_path)]) == 2
    assert "is a folder" in capsys.readouterr().err
