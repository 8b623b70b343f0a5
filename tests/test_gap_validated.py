"""Issue 57: the configured model's own validated accuracy in the noise floor.

A parameter file made by `cell calibrate --validate` carries the model's RMS landing miss
per object on held-out throws; the gap's floor from repeats takes it in quadrature
(`cell.gap.noise`). Checked against: the closed form F² = F_rep² + mean over the throws of
their object's misfit², the same floor without the section, the held-out throws thrown
again and predicted here (not the fitted ones), and the file's other sections byte for
byte."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from cell.cli import main
from cell.errors import InvalidInput
from cell.gap.noise import noise_floor
from cell.gap.problem import build_problem
from cell.gap.report import format_table
from cell.gap.run import diagnose_log
from cell.gap.world_other import draw_other_campaign
from cell.log import read_throws_csv
from cell.log.table import ThrowTable
from cell.model.params import DEFAULT_EE
from cell.model.throw import predict_landing
from cell.params import Validation, load_params, save_params, scene_params_path
from cell.workflows.campaign import campaign_plan, run_campaign


@pytest.fixture(scope="module")
def table() -> ThrowTable:
    camp = draw_other_campaign([], np.random.default_rng(5), n=120)
    return ThrowTable.from_records(camp.records)


def _floor(table: ThrowTable, validation: Validation | None):  # noqa: ANN202
    prob = build_problem(table, DEFAULT_EE, seed=0, validation=validation)
    idx = np.arange(len(prob))
    return noise_floor(prob, prob.observed - prob.landing(idx).xy, prob.landing(idx))


def test_floor_adds_the_validated_misfit_in_quadrature(table: ThrowTable) -> None:
    ids = table.text("object_id")
    objs = sorted(set(ids))
    assert len(objs) >= 3
    # two objects validated, the others not (they add nothing)
    v = {objs[0]: (0.030, 40), objs[1]: (0.012, 40)}
    without = _floor(table, None)
    assert without.method == "repeats" and np.isnan(without.validated_m)
    with_val = _floor(table, Validation(objects=v, throws=80, seed=0))
    per = np.array([v[o][0] if o in v else 0.0 for o in ids])
    mean_sq = float(np.mean(per**2))
    assert with_val.method == "repeats+validated"
    assert with_val.repeats_m == pytest.approx(without.repeats_m, rel=1e-12)
    assert with_val.floor_m**2 == pytest.approx(without.floor_m**2 + mean_sq, rel=1e-12)
    assert with_val.validated_m == pytest.approx(np.sqrt(mean_sq), rel=1e-12)
    assert with_val.validated_share == pytest.approx(np.mean([o in v for o in ids]))
    # a validation of objects the log does not hold changes nothing
    other = _floor(table, Validation(objects={"not_thrown": (0.05, 10)}, throws=10, seed=0))
    assert (other.floor_m, other.method) == (without.floor_m, without.method)


def test_diagnosis_reports_the_validated_floor(table: ThrowTable) -> None:
    v = Validation(objects={o: (0.02, 10) for o in set(table.text("object_id"))}, throws=90,
                   seed=0)  # fmt: skip
    d, _ = diagnose_log(table, DEFAULT_EE, seed=0, validation=v)
    nz = d.report["noise"]
    assert nz["method"] == "repeats+validated"
    assert d.report["noise_floor_m"] == pytest.approx(np.hypot(nz["repeats_m"], 0.02), rel=1e-12)
    text = format_table(d.report)
    assert "validated 0.0200 m" in text and "held-out misfit" in text


def _write(tmp_path: Path, section: object) -> str:
    doc = yaml.safe_load(Path(scene_params_path() or "").read_text())
    doc["validation"] = section
    p = tmp_path / "p.yaml"
    p.write_text(yaml.safe_dump(doc))
    return str(p)


GOOD = {"throws": 20, "seed": 1, "objects": {"cube30": {"heldout_rmse_m": 0.03, "n": 10}}}


@pytest.mark.parametrize(
    ("section", "field"),
    [
        ([1, 2], "validation must be"),
        ({**GOOD, "extra": 1}, "validation must be"),
        ({**GOOD, "throws": 2.5}, "validation.throws"),
        ({**GOOD, "throws": True}, "validation.throws"),
        ({**GOOD, "seed": "one"}, "validation.seed"),
        ({**GOOD, "objects": {}}, "validation.objects"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": float("nan"), "n": 3}}},
         "validation.objects.cube30.heldout_rmse_m"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": 5.0, "n": 3}}},
         "validation.objects.cube30.heldout_rmse_m"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": -0.01, "n": 3}}},
         "validation.objects.cube30.heldout_rmse_m"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": "x", "n": 3}}},
         "validation.objects.cube30.heldout_rmse_m"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": 0.01, "n": 0}}},
         "validation.objects.cube30.n"),
        ({**GOOD, "objects": {"cube30": {"rmse": 0.01, "n": 3}}}, "validation.objects.cube30"),
        ({**GOOD, "objects": {"cube30": {"heldout_rmse_m": 0.01, "n": 30}}}, "validation.throws"),
    ],
)  # fmt: skip
def test_bad_validation_section_is_refused_naming_the_field(tmp_path, section, field) -> None:
    with pytest.raises(InvalidInput, match=field.replace(".", r"\.")):
        load_params(_write(tmp_path, section))


def test_validation_section_round_trips(tmp_path: Path) -> None:
    mp = load_params(_write(tmp_path, GOOD))
    assert mp.validation == Validation(objects={"cube30": (0.03, 10)}, throws=20, seed=1)
    save_params(mp, tmp_path / "q.yaml")
    assert load_params(tmp_path / "q.yaml") == mp


def _rms_by_object(table: ThrowTable, params) -> dict[str, float]:  # noqa: ANN001
    batch = table.to_batch(objects=params.objects)
    land = predict_landing(batch, params.ee, strict=False, check_stroke=False)
    d2 = np.sum((land.xy - table.landed) ** 2, axis=1)
    ids = np.array(table.text("object_id"))
    return {o: float(np.sqrt(np.mean(d2[ids == o]))) for o in sorted(set(ids))}


def test_calibrate_validates_on_held_out_throws(tmp_path: Path) -> None:
    """The section is the model's miss on throws thrown after the fit from a stream of
    their own: thrown again here and predicted with the file's parameters, they give its
    numbers; the campaign's (fitted) throws give other, smaller ones."""
    out, log = tmp_path / "ee.yaml", tmp_path / "fitted.csv"
    argv = ["calibrate", "--n", "28", "--adhoc", "0", "--validate", "14", "--seed", "4",
            "-o", str(out), "--log", str(log)]  # fmt: skip
    assert main(argv) == 0
    mp = load_params(out)
    assert mp.validation is not None and mp.validation.throws == 14 and mp.validation.seed == 4
    held = run_campaign(campaign_plan(14, seed=4, held_out=True))
    fitted = read_throws_csv(log)  # the campaign's own throws, as `--log` wrote them
    assert len(fitted) == 28
    assert not set(held.text("throw_id")) & set(fitted.text("throw_id"))
    on_held, on_fitted = _rms_by_object(held, mp), _rms_by_object(fitted, mp)
    assert sorted(mp.validation.objects) == sorted(on_held)
    for o in on_held:
        x, n = mp.validation.objects[o]
        assert n == int(np.sum(np.array(held.text("object_id")) == o))
        assert x == pytest.approx(on_held[o], rel=1e-9)
    # the fit's own throws are not what the section reports
    assert max(abs(mp.validation.objects[o][0] - on_fitted[o]) for o in on_fitted) > 1e-3
    mean_held = np.mean([mp.validation.objects[o][0] for o in on_fitted])
    assert mean_held > np.mean(list(on_fitted.values()))


def test_validate_only_keeps_the_parameters_byte_identical(tmp_path: Path) -> None:
    """`--params FILE --validate N` writes FILE's own text, then the validation section."""
    shipped = Path(scene_params_path() or "")
    src = tmp_path / "src.yaml"
    mp = load_params(shipped)
    from dataclasses import replace

    save_params(replace(mp, validation=None), src)
    out = tmp_path / "out.yaml"
    argv = ["calibrate", "--params", str(src), "--validate", "14", "--seed", "2", "-o", str(out)]
    assert main(argv) == 0
    before, after = src.read_text(), out.read_text()
    assert after.startswith(before) and after[len(before) :].startswith("validation:\n")
    v = load_params(out).validation
    assert v is not None and v.throws == 14 and len(v.objects) == 14
    assert main(["calibrate", "--params", str(src), "-o", str(out)]) == 2
