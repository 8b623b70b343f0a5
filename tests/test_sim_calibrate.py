"""Calibration helpers: the effective-mass rule, the gap summary, a tiny campaign."""

import math

import numpy as np
import pytest

from cell.catalogue import catalogue
from cell.errors import InvalidInput, InvalidParameter
from cell.model.objects import ObjectParams
from cell.params import ModelParams
from cell.workflows.calibrate import extend_objects, gap_summary, mass_rule
from cell.workflows.campaign import campaign_plan, run_campaign


def test_mass_rule_recovers_kappa_and_band_mass():
    kappa, mb = 0.15, 0.012
    nominal = {
        f"o{i}": ObjectParams("cube", m, (0.04,) * 3) for i, m in enumerate([0.02, 0.05, 0.1, 0.2])
    }
    ident = {
        k: ObjectParams("cube", kappa * math.sqrt(o.mass + mb), (0.04,) * 3)
        for k, o in nominal.items()
    }
    rule = mass_rule(ident, nominal)
    assert rule.kappa == pytest.approx(kappa, rel=1e-4)
    assert rule.band_mass_kg == pytest.approx(mb, rel=1e-3)
    assert rule(0.07) == pytest.approx(kappa * math.sqrt(0.082), rel=1e-4)
    with pytest.raises(InvalidInput):
        mass_rule({"o0": ident["o0"]}, nominal)


def test_extend_objects_fills_every_catalogue_object():
    nominal = {k: e.params for k, e in catalogue().items()}
    ident = {"cube50": ObjectParams("cube", 0.04, (0.05,) * 3, name="cube50")}
    rule = mass_rule({**ident, "cube30": ObjectParams("cube", 0.027, (0.03,) * 3)}, nominal)
    out = extend_objects(ModelParams(objects=ident), rule)
    assert set(out.objects) == set(nominal)
    assert out.objects["cube50"].mass == 0.04  # identified values are kept
    assert out.objects["duck"].mass == pytest.approx(rule(nominal["duck"].mass))
    assert out.objects["duck"].size == nominal["duck"].size


def test_campaign_plan_raises_on_bad_size():
    with pytest.raises(InvalidParameter):
        campaign_plan(0)


def test_small_campaign_logs_valid_throws_and_the_nominal_gap():
    plan = campaign_plan(3, seed=7, objects=["cube30", "cube60", "sphere40"])
    table = run_campaign(plan)
    assert len(table) == 3
    assert np.all(np.isfinite(table.landed))
    assert np.all(table.num("t_flight_s") > 0.2)
    gap = gap_summary(table, ModelParams())
    # light objects fly shorter than the nominal impulse predicts, heavy ones farther
    assert gap.by_object["cube30"] > 0.1
    assert gap.by_object["cube60"] < -0.1


def test_calibrate_refuses_to_overwrite_the_shipped_parameters(tmp_path, capsys) -> None:
    """The shipped scene calibration is replaced only on request, and checked before any throw."""
    from cell.cli import main
    from cell.params import scene_params_path

    shipped = scene_params_path()
    assert shipped is not None
    before = open(shipped, "rb").read()
    assert main(["calibrate", "--n", "3", "-o", shipped]) == 2
    err = capsys.readouterr().err
    assert "--replace" in err and "Traceback" not in err
    assert open(shipped, "rb").read() == before
    for bad in (str(tmp_path), str(tmp_path / "missing" / "ee.yaml")):
        assert main(["calibrate", "--n", "3", "-o", bad]) == 2
        assert "-o " in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_scene_commands_keep_stdout_for_their_output(tmp_path, capfd) -> None:
    """PyBullet's banners ("argv[0]=", printed by C code on connect) are silenced at the
    file-descriptor level (issue 62): `cell calibrate --json` prints JSON alone on stdout,
    and stderr has no banner either."""
    import json

    from cell.cli import main

    argv = ["calibrate", "--n", "10", "--adhoc", "6", "--json", "-o", str(tmp_path / "e.yaml")]
    assert main(argv) == 0
    out, err = capfd.readouterr()
    assert json.loads(out)["throws"] == 10
    assert "argv[0]" not in out + err and "pybullet build time" not in out + err
