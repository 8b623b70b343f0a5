"""Inputs a new user's cell gives, a twelfth round: a residual learned against another
model than the job plans with, the parameter files `cell` writes read back, what
`cell learn` says it saved, and `cell identify`'s iteration count."""

from __future__ import annotations

import json
import re
from dataclasses import fields, replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import sklearn
import yaml
from sklearn.dummy import DummyRegressor
from sklearn.pipeline import Pipeline

from cell.arm.grip_side import GripSideChoice, holding_sides, throw_sides
from cell.errors import JobError, UnreachableTarget
from cell.jobs import parse_job
from cell.model.objects import ObjectParams
from cell.model.params import EndEffectorParams
from cell.params import ModelParams, load_params, save_params, scene_params_path
from cell.residual.features import FEATURE_NAMES
from cell.residual.model import ResidualModel
from tests.cli_exit import cell_exit

FAR = "{id: far, position_m: [1.60, 0.00], size_m: [0.40, 0.40], rim_height_m: 0.15}"


def _residual(path: Path, ee: EndEffectorParams, constant_mm: float = 3.0) -> Path:
    """A residual file as `cell learn` writes one whose inner CV chose a constant ΔL_s."""
    x = np.zeros((3, len(FEATURE_NAMES)))
    reg = DummyRegressor(strategy="constant", constant=constant_mm)
    pipe = Pipeline([("reg", reg)]).fit(x, np.full(3, constant_mm))
    ResidualModel(
        learner="svr",
        pipeline=pipe,
        feature_names=FEATURE_NAMES,
        training_objects=("cube50",),
        ee=ee,
        sklearn_version=sklearn.__version__,
        best_params={"null": "mean", "learner_cv_mse_mm2": 9.0, "reg__C": 10.0},
        n_train=3,
    ).save(path)
    return path


def _job(tmp_path: Path, cell: str) -> Path:
    job = tmp_path / "job.yaml"
    job.write_text(f"cell: {cell}\nbins:\n  - {FAR}\nitems:\n  - {{object: cube50, bin: far}}\n")
    return job


def test_a_residual_learned_against_other_parameters_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell learn THROWS.csv -o r.skops` learns ΔL_s against the reference parameters (its
    default), `cell run` plans with the scene's calibrated file (its default): a job naming
    that residual added to the scene's strokes corrections of another model's, silently (a
    constant one threw a cube50 0.84 m past a bin 1.6 m out that it lands in without).
    Refused now, naming the keys that differ; the residual of the job's own parameters, or
    with `cell.params` the file it was learned with, is taken."""
    scene = load_params(scene_params_path())
    ref = ModelParams()
    _residual(tmp_path / "ref.skops", ref.ee)
    assert cell_exit(["run", str(_job(tmp_path, "{residual: ref.skops}")), "--no-log"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert f"job.yaml, line 1, cell.residual: {tmp_path / 'ref.skops'} learned" in err, err
    differ = [
        f.name
        for f in fields(EndEffectorParams)
        if getattr(ref.ee, f.name) != getattr(scene.ee, f.name)
    ]
    assert len(differ) > 4  # the two models differ in most of η_ee: four named, the count
    for k in differ[:4]:
        assert f"{k} {getattr(ref.ee, k):.6g} against {getattr(scene.ee, k):.6g}" in err, k
    assert f"and {len(differ) - 4} more" in err
    assert f"--params {scene_params_path()}" in err  # how to learn it again
    # one parameter off by a part in a thousand is another model too
    bent = replace(scene.ee, Ke1=scene.ee.Ke1 * 1.001)
    _residual(tmp_path / "bent.skops", bent)
    with pytest.raises(JobError, match=r"Ke1 [\d.]+ against [\d.]+ \(learned against planned\)"):
        parse_job(_job(tmp_path, "{residual: bent.skops}").read_text(), str(tmp_path / "job.yaml"))
    # taken: learned against the scene's file; the reference one with it as cell.params
    _residual(tmp_path / "scene.skops", scene.ee)
    save_params(ref, tmp_path / "ref.yaml")
    for cell in ("{residual: scene.skops}", "{residual: ref.skops, params: ref.yaml}"):
        job = parse_job(_job(tmp_path, cell).read_text(), str(tmp_path / "job.yaml"))
        assert job.residual.endswith(".skops"), cell


def test_parameter_files_cell_writes_read_back_without_a_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell identify -o id.yaml` and `cell synth --save-world w.yaml` wrote files without
    `L_e` (the ride's end, left out at 0), and every command reading them warned "gives 13
    of its 14 parameters; 1 reference value taken": docs/cli_inputs.md says a file they
    write gives them all. Now it does, and reads back as written. `cell identify`'s "10
    iterations, stopped at --max-iter" under `--max-iter 5` (two passes of 5) says so."""
    log, world, ident = tmp_path / "t.csv", tmp_path / "w.yaml", tmp_path / "id.yaml"
    out = tmp_path / "id.json"
    argv = ["synth", "-o", str(log), "--n", "30", "--seed", "2", "--save-world", str(world)]
    assert cell_exit(argv) == 0
    argv = ["identify", str(log), "-o", str(ident), "--max-iter", "1", "--holdout", "0"]
    assert cell_exit([*argv, "--json", str(out)]) == 0
    text = capsys.readouterr().out
    names = [f.name for f in fields(EndEffectorParams)]
    for f in (world, ident):
        written = yaml.safe_load(f.read_text())["end_effector"]
        assert sorted(written) == sorted(names), f  # every key, L_e (0: off) among them
        assert cell_exit(["throw", "--params", str(f), "--object", "cube50"]) == 0
        err = capsys.readouterr().err
        assert "reference value" not in err, err
        ee = load_params(f).ee
        assert all(getattr(ee, k) == written[k] for k in names), f  # read as written
    iterations = json.loads(out.read_text())["iterations"]
    line = next(ln for ln in text.splitlines() if re.match(r"\d+ iterations?\b", ln))
    assert line.startswith(f"{iterations} iteration"), line
    assert iterations <= 1 or "two passes" in line and "each of at most --max-iter 1" in line


def test_learn_names_a_saved_constant_correction_not_the_learners_parameters(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Where the inner cross-validation chose a constant ΔL_s over the learner, `cell learn`
    ended "saved svr residual (…; reg__C=10, …)": the hyper-parameters of a learner not
    saved. It names the constant, which the file predicts."""
    from argparse import Namespace

    from cell.cli.cmd_learn import _print
    from cell.residual.model import GripPose

    path = _residual(tmp_path / "c.skops", ModelParams().ee, constant_mm=2.5)
    model = ResidualModel.load(path)
    saved = {"learner": "svr", "residual": "constant", "heldout": None, "reason": "."}
    _print(Namespace(output=str(path)), {}, (), model, saved, None)
    out = capsys.readouterr().out
    cube = ObjectParams("cube", 0.06, (0.05, 0.05, 0.05))
    delta_mm = 1000 * model.delta_strokes([cube], [GripPose(0.07, 0.4, 0.0)])[0]
    assert f"saved a constant correction (ΔL_s = {delta_mm:+.2f} mm for every throw" in out
    assert "reg__C" not in out and "saved svr residual" not in out, out


class _Sides(GripSideChoice):
    """`GripSideChoice._throw_side` with the planner stubbed: each side's width [mm] is
    recorded as planned; a width in `fail` finds no throw, the others cost their width."""

    def __init__(self, fail: tuple[int, ...] = ()) -> None:  # no arm: nothing else is read
        self.fail, self.planned = fail, []

    def _plan(self, obj, target, index, stroke_max_m, beat):  # type: ignore[no-untyped-def]
        w = round(obj.width * 1000)
        self.planned.append(w)
        if w in self.fail:
            raise UnreachableTarget(f"{w} mm: no throw")
        return SimpleNamespace(cost=(False, float(w)))

    def _budget_spent(self) -> bool:
        return False


def test_a_throw_grips_a_side_the_model_is_calibrated_on_where_one_gives_a_throw() -> None:
    """A 30 g box 30 x 120 mm was thrown gripped across 120 mm where that side's cycle
    estimate was the shorter: the pads squeeze so wide an item as it leaves them, and it
    landed short. The narrower side (within `calibrated_width_m`, 90 mm) is planned first,
    the wider only where it finds no throw; sides all within 90 mm are chosen as before,
    by their estimates (cuboid_a's 30 and 50 mm)."""
    params = load_params(scene_params_path())
    box = ObjectParams("cuboid", 0.03, (0.03, 0.12, 0.1))
    sides = throw_sides(holding_sides(params, box), box)
    assert sorted(round(s.width_m * 1000) for s in sides) == [30, 120]
    wide_first = sorted(sides, key=lambda s: -s.width_m)  # the wide side cheaper, first
    arm = _Sides()
    side, _ = arm._throw_side(wide_first, (1.4, 0.0, 0.15), 0)
    assert round(side.width_m * 1000) == 30 and arm.planned == [30]
    arm = _Sides(fail=(30,))  # the narrow side finds no throw: the wide one is planned
    side, _ = arm._throw_side(wide_first, (3.5, 0.0, 0.15), 0)
    assert round(side.width_m * 1000) == 120 and arm.planned == [30, 120]
    cub = ObjectParams("cuboid", 0.03, (0.05, 0.03, 0.1))  # 50 and 30 mm: both planned
    both = throw_sides(holding_sides(params, cub), cub)
    arm = _Sides()
    side, _ = arm._throw_side(both, (1.4, 0.0, 0.15), 0)
    assert sorted(arm.planned) == [30, 50] and round(side.width_m * 1000) == 30


def test_a_light_box_with_a_narrow_side_is_thrown_into_its_bin(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """In the scene (the plant, not the planner's model): a 30 g box [0.03, 0.12, 0.1]
    thrown to a bin 2.19 m out (tune layout 1's bin_4) came to rest outside it, 0.35 m
    from its aim, gripped across 120 mm; across its 30 mm side it rests in the bin."""
    job = tmp_path / "wide.yaml"
    job.write_text(
        "bins:\n  - {id: b, position_m: [1.692, -1.395], size_m: [0.379, 0.388], "
        "rim_height_m: 0.278}\npolicy: throw\n"
        "items:\n  - {shape: cuboid, mass_kg: 0.03, size_m: [0.03, 0.12, 0.1], bin: b}\n"
    )
    out = tmp_path / "out.json"
    assert cell_exit(["run", str(job), "--no-log", "-q", "--json", str(out)]) == 0
    (r,) = json.loads(out.read_text())["results"]
    assert r["in_bin"] and r["bin_id"] == "b", r
    assert r["landing_error_m"] < 0.05, r


def test_synth_objects_a_repeat_refused_and_a_misspelling_told_the_id(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell synth --objects cube50 cube50` drew a campaign of cube50 alone and said "of 2
    objects" (a repeat takes a second equal share: `cube50 cube50 cyl50` throws cube50
    twice as often, without a word); `--objects Cube50` listed the catalogue with no
    nearest id, where a job's `object: Cube50` is told 'cube50'."""
    out = tmp_path / "s.csv"
    assert cell_exit(["synth", "-o", str(out), "--n", "6", "--objects", "cube50", "cube50"]) == 2
    err = capsys.readouterr().err
    assert "--objects lists 'cube50' more than once" in err and "Traceback" not in err, err
    assert not out.exists()
    argv = ["synth", "-o", str(out), "--n", "6", "--objects", "Cube50", "cyl-50", "zzz"]
    assert cell_exit(argv) == 2
    err = capsys.readouterr().err
    assert "did you mean 'cube50' for 'Cube50', 'cyl50' for 'cyl-50'?" in err, err
    argv = ["synth", "-o", str(out), "--n", "6", "--objects", "cube50", "cyl50"]
    assert cell_exit(argv) == 0  # each once: an equal share, said as 2 objects
    assert "drew 6 throws of 2 objects" in capsys.readouterr().out
    rows = out.read_text().splitlines()[1:]
    assert sorted(r.split(",")[1] for r in rows) == ["cube50"] * 3 + ["cyl50"] * 3


def test_throw_and_plan_with_a_parameter_file_model_the_object_as_the_run_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell throw --params robots/cell_scene/ee_params.yaml --object cube50` predicted with
    the catalogue's 60 g, where `cell run` plans with the file's identified η_o (39.5 g):
    0.77 m out where the scene's throw lands 1.33 m; `cell plan` gave a stroke the cell
    would not command. Against the plant (a bare scene's throw, no arm): the landing within
    0.05 m, the stroke that lands there within 2 mm of the one thrown.
    Without --params (the reference values, no objects, no mass rule) as before."""
    from cell.endeffector.factory import make_end_effector
    from cell.sim import CellScene
    from cell.workflows.campaign import throw_once

    scene_file = str(scene_params_path())
    pose = ["--at", "0", "0", "0.7", "--elevation", "0.4363", "--land-z", "0.1"]
    sc = CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0))
    try:
        ee = make_end_effector("pybullet", plant=sc)
        for name, stroke in (("cube50", 0.07), ("cyl70", 0.08)):
            rec = throw_once(
                sc, ee, name, stroke=stroke, position=(0, 0, 0.7), elevation=0.4363, land_z=0.1
            )
            out = tmp_path / f"{name}.json"
            argv = ["throw", "--params", scene_file, "--object", name, "--stroke", str(stroke)]
            assert cell_exit([*argv, *pose, "--json", str(out)]) == 0
            said = capsys.readouterr().out
            assert "modelled as" in said and "identified η_o, as `cell run` plans it" in said
            predicted = json.loads(out.read_text())["landed_x_m"]
            assert abs(predicted - rec["landed_x_m"]) < 0.05, (name, predicted, rec)
            # cell plan, held to that release and elevation: the stroke the scene threw
            at = ["--current", "0", "0", "0.7", "--elevation-range", "0.4362", "0.4364"]
            at += ["--box", "-0.001", "-0.001", "0.699", "0.001", "0.001", "0.701"]
            target = ["--target", f"{rec['landed_x_m']:.4f}", "0", "0.1"]
            argv = ["plan", "--params", scene_file, "--object", name, *target, *at]
            assert cell_exit([*argv, "--json", "-"]) == 0
            plan = json.loads(capsys.readouterr().out)
            assert abs(plan["stroke_m"] - stroke) < 0.002, (name, plan["stroke_m"])
    finally:
        sc.close()
    assert cell_exit(["throw", "--object", "cube50", *pose]) == 0  # the reference: unchanged
    assert "modelled as" not in capsys.readouterr().out


def test_predict_with_a_parameter_file_models_each_row_as_the_run_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell predict LOG --params robots/cell_scene/ee_params.yaml` predicted an ad-hoc row
    with its logged mass, where `cell run` plans it with the file's mass rule: the cell's
    own throws of four wide boxes (tune layout 2) came out 0.06-0.75 m from their landings.
    Against the plant: a 100 g 50 mm cube thrown in the bare scene, and cube50, predicted
    within 0.05 m of where they landed (the cube 0.48 m off before)."""
    import csv

    from cell.endeffector.factory import make_end_effector
    from cell.sim import CellScene
    from cell.workflows.campaign import throw_once

    sc = CellScene(robot=None, bins=(), pick_station_xy=(-1.0, -1.0))
    try:
        ee = make_end_effector("pybullet", plant=sc)
        cube = ObjectParams("cube", 0.1, (0.05, 0.05, 0.05))
        kw = {"position": (0, 0, 0.7), "elevation": 0.4363, "land_z": 0.1}
        rows = [
            {**throw_once(sc, ee, cube, stroke=0.08, **kw), "object_id": "item0_cube"},
            {**throw_once(sc, ee, "cube50", stroke=0.07, **kw), "throw_id": "sim2"},
        ]
    finally:
        sc.close()
    log, out = tmp_path / "log.csv", tmp_path / "pred.csv"
    with log.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    argv = ["predict", str(log), "-o", str(out), "--params", str(scene_params_path())]
    assert cell_exit(argv) == 0, capsys.readouterr().err
    for r in csv.DictReader(out.open()):
        miss = np.hypot(
            float(r["pred_x_m"]) - float(r["landed_x_m"]),
            float(r["pred_y_m"]) - float(r["landed_y_m"]),
        )
        assert miss < 0.05, (r["object_id"], miss)
