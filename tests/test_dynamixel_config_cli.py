"""The YAML configuration, the factory and `cell ee` against the emulated bus."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from cell.cli import main
from cell.endeffector.dynamixel import EmulatedBus, load_config
from cell.endeffector.factory import make_end_effector
from cell.errors import InvalidInput, InvalidParameter
from tests.dynamixel_fixtures import FAST, TIME_SCALE

REPO_CONFIG = Path(__file__).resolve().parents[1] / "robots" / "throwing_ee" / "dynamixel.yaml"


def _write(tmp_path: Path, doc: dict) -> Path:
    p = tmp_path / "ee.yaml"
    p.write_text(yaml.safe_dump(doc))
    return p


def test_repo_config_loads_with_the_model_stroke_range() -> None:
    cfg = load_config(REPO_CONFIG)
    assert (cfg.stroke.min_m, cfg.stroke.max_m) == (0.03, 0.11)  # MODEL.md stroke range
    assert cfg.latch.id != cfg.spool.id
    assert cfg.source == str(REPO_CONFIG)


@pytest.mark.parametrize(
    ("doc", "where"),
    [
        ({"bogus": 1}, "bogus"),
        ({"latch": {"idd": 1}}, "latch: unknown key"),
        ({"latch": {"id": "one"}}, "latch.id: must be an integer"),
        ({"latch": {"id": 300}}, "latch.id: must be a servo ID"),
        ({"spool": {"model": "mx-28"}}, "spool.model: unknown model 'mx-28'"),
        ({"spool": {"radius_m": 0}}, "spool.radius_m"),
        ({"spool": {"wind_direction": 2}}, "spool.wind_direction"),
        ({"stroke": {"min_m": 0.12}}, "stroke.min_m"),
        ({"stroke": {"rest_m": 0.2}}, "stroke.rest_m"),
        ({"baud_rate": 12345}, "baud_rate: must be one of"),
        ({"spool": {"id": 1}}, "share ID 1"),
        ({"timing": {"poll_period_s": -1}}, "timing.poll_period_s"),
        ([1, 2], "must be a mapping"),
    ],
)
def test_bad_config_names_file_and_field(tmp_path: Path, doc: object, where: str) -> None:
    p = _write(tmp_path, doc)  # type: ignore[arg-type]
    with pytest.raises(InvalidInput) as exc:
        load_config(p)
    assert str(p) in str(exc.value) and where in str(exc.value)


def test_missing_config_file(tmp_path: Path) -> None:
    with pytest.raises(InvalidInput, match="no such"):
        load_config(tmp_path / "nope.yaml")


def test_config_in_code_validates() -> None:
    with pytest.raises(InvalidParameter, match="latch.tolerance"):
        type(FAST.latch)(tolerance=500)


def test_factory_emulated_end_effector_stops_its_bus() -> None:
    ee = make_end_effector("dynamixel", REPO_CONFIG, emulate=True, time_scale=TIME_SCALE)
    with ee:
        ee.grasp(0.06)
        assert ee.stroke() == pytest.approx(0.06, abs=2e-5)
        ee.throw()
    with pytest.raises(InvalidInput, match="valid: \\['pybullet', 'dynamixel'"):
        make_end_effector("gripper3000")


def test_cli_against_a_served_bus(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cfg_path = _write(
        tmp_path,
        {
            "retries": 2,
            "latency_timer_ms": 60,
            "timing": {"stall_timeout_s": 0.1, "poll_period_s": 0.002},
        },
    )
    cfg = load_config(cfg_path)
    with EmulatedBus.from_config(cfg, time_scale=TIME_SCALE) as emu:
        base = ["ee", "--config", str(cfg_path), "--port", emu.port]
        assert main([*base, "grasp", "--stroke", "0.06"]) == 0
        assert "stroke 0.0600 m, latch engaged" in capsys.readouterr().out
        assert emu.servo(2).value("torque_enable") == 0  # off after each command
        assert main([*base, "stroke", "0.045"]) == 0
        capsys.readouterr()
        assert main([*base, "stroke"]) == 0
        assert capsys.readouterr().out.strip() == "0.0450"
        assert emu.true_stroke_m() == pytest.approx(0.045, abs=2e-5)
        assert main([*base, "--json", "throw"]) == 0
        st = json.loads(capsys.readouterr().out)
        assert st["latch_engaged"] is False and st["stroke_m"] == 0.11
        assert emu.true_stroke_m() == pytest.approx(0.11)
        assert main([*base, "throw"]) == 2
        assert "throw refused" in capsys.readouterr().err
        assert main([*base, "stroke", "0.5"]) == 2
        assert "[0.03, 0.11]" in capsys.readouterr().err


def test_cli_emulate_and_bad_port(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ee", "--config", str(REPO_CONFIG), "--emulate", "status"]) == 0
    out = capsys.readouterr().out
    assert "latch open" in out and "M2 spool ID 2" in out
    assert main(["ee", "--config", str(REPO_CONFIG), "--port", "/dev/ttyNOPE9", "status"]) == 2
    err = capsys.readouterr().err
    assert "/dev/ttyNOPE9" in err and "cannot open serial port" in err
