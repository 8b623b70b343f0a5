"""The sim-to-real diagnosis on campaigns with a withheld, known effect."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest

from cell.cli import main
from cell.errors import InvalidInput
from cell.gap.fit import score_set
from cell.gap.problem import build_problem
from cell.gap.report import write_json
from cell.gap.run import diagnose_log
from cell.gap.world import draw_campaign
from cell.gap.world_tracks import draw_tracked_campaign
from cell.log.csvio import write_throws_csv
from cell.model.effects import BandMass, Bounce, TrackingScale
from cell.model.params import DEFAULT_EE

# GAP.md: the JSON report's keys
TOP_KEYS = {"throws", "noise_floor_m", "baseline", "where", "candidates", "verdict"}


def _no_nan(text: str) -> dict:
    def bad(c: str) -> None:
        raise AssertionError(f"non-JSON constant {c}")

    return json.loads(text, parse_constant=bad)


@pytest.fixture(scope="module")
def band_mass_run(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    # 160 throws: A 0.96-0.99 F, the band mass 0.4-2.3 % off, the floor 1-4 % over the
    # scatter, the shuffled mass losing 0.39-0.45 of the gain (seeds 11, 0, 1)
    camp = draw_campaign("band_mass", np.random.default_rng(11), n=160)
    d, prob = diagnose_log(camp.table, DEFAULT_EE)
    return camp, d, prob, tmp_path_factory.mktemp("gap")


def test_band_mass_found_and_report_schema(band_mass_run: tuple) -> None:
    camp, d, _, tmp = band_mass_run
    path = tmp / "report.json"
    write_json(d.report, path)
    rep = _no_nan(path.read_text())
    assert TOP_KEYS <= set(rep)
    assert set(rep["baseline"]) >= {"fit_rmse_m", "heldout_rmse_m"}
    assert set(rep["where"]) >= {"phase", "evidence", "worst"}
    for w in rep["where"]["worst"]:
        assert set(w) >= {"factor", "level", "heldout_rmse_m"}
    for c in rep["candidates"]:
        assert set(c) >= {"effect", "heldout_rmse_m", "shrink_pct", "params"}
    rm = [c["heldout_rmse_m"] for c in rep["candidates"]]
    assert rm == sorted(rm)  # best first
    v = rep["verdict"]
    assert v["effects"] == ["band_mass"]
    assert rep["where"]["phase"] == "launch"
    B = rep["baseline"]["heldout_rmse_m"]
    assert v["shrink_pct"] == pytest.approx(100 * (1 - v["heldout_rmse_m"] / B))
    # within 1.3 F, and the fitted band mass near the injected one
    assert v["heldout_rmse_m"] <= 1.3 * rep["noise_floor_m"]
    assert rep["candidates"][0]["params"]["mass_kg"] == pytest.approx(
        camp.params["mass_kg"], rel=0.25
    )
    # the noise floor recovers the injected scatter (repeats)
    assert rep["noise_floor_m"] == pytest.approx(camp.noise_m, rel=0.15)
    # light objects are where the gap concentrates
    assert any(w["factor"] in ("object_id", "mass_kg") for w in rep["where"]["worst"])


def test_permutation_control(band_mass_run: tuple) -> None:
    """Shuffling mass between throws takes band_mass's gain away on a band-mass world, and
    gives nothing on a world whose launch loss does not depend on mass."""
    _, d, prob, _ = band_mass_run
    real = d.scores["band_mass"]
    shuffled = score_set(prob, [BandMass], permute=True)
    B = math.sqrt(d.baseline_sq.mean())
    assert shuffled.heldout_rmse_m - real.heldout_rmse_m > 0.25 * (B - real.heldout_rmse_m)
    # a world whose band is uniformly weaker (not in the vocabulary): band_mass fits a
    # mean loss, and it fits it just as well with the masses shuffled
    from dataclasses import replace

    weak = replace(DEFAULT_EE, Ke1=DEFAULT_EE.Ke1 * 0.9, Ke2=DEFAULT_EE.Ke2 * 0.9,
                   Ke3=DEFAULT_EE.Ke3 * 0.9)  # fmt: skip
    camp = draw_campaign("none", np.random.default_rng(5), n=200, ee=weak)
    p2 = build_problem(camp.table, DEFAULT_EE)
    r = score_set(p2, [BandMass])
    s = score_set(p2, [BandMass], permute=True)
    B2 = math.sqrt(np.mean(np.sum(p2.residual(np.arange(len(p2))) ** 2, axis=1)))
    assert B2 - r.heldout_rmse_m > 0.1 * B2  # the spurious effect does cut the miss
    assert s.heldout_rmse_m - r.heldout_rmse_m < 0.25 * (B2 - r.heldout_rmse_m)


def test_none_within_noise() -> None:
    camp = draw_campaign("none", np.random.default_rng(2), n=200)
    d, _ = diagnose_log(camp.table, DEFAULT_EE)
    assert d.report["verdict"]["effects"] == ["none"]
    assert d.report["where"]["phase"] == "none"


def test_other_launcher_from_tracks() -> None:
    """No stroke logged: launch from the tracks, the landing effect still found. Five
    landings logged 0.6 m off are outliers, and every throw is still counted as from
    another launcher, the outliers among them said apart (the count was taken after the
    outliers were left out: 155 of 160 then). 80 throws (160 before: 7.35 -> 5.71 CPU-s),
    the same verdict, phase and five rows flagged."""
    from cell.gap.report import format_table

    camp = draw_tracked_campaign((Bounce(0.3),), np.random.default_rng(4), n=80)
    assert np.all(np.isnan(camp.table.num("stroke_m")))
    with pytest.raises(InvalidInput, match="stroke or a track"):
        diagnose_log(camp.table, DEFAULT_EE)  # without tracks nothing can be said
    x = camp.table.num("landed_x_m").copy()
    moved = [7, 30, 45, 61, 75]
    x[moved] += 0.6
    d, _ = diagnose_log(camp.table.with_columns({"landed_x_m": x}), DEFAULT_EE, tracks=camp.tracks)
    rep = d.report
    assert rep["outliers"]["rows"] == [i + 1 for i in moved]
    assert rep["other_launcher_throws"] == rep["throws"] == len(camp.table) == 80
    assert rep["outliers"]["other_launcher"] == len(moved)
    n = rep["throws"]
    assert f"throws           {n} ({n} from another launcher, from tracks, 5 of them outliers)" in (
        format_table(rep)
    )
    assert rep["verdict"]["effects"] == ["bounce"]
    assert rep["where"]["phase"] == "landing"
    assert all(c["phase"] != "launch" for c in rep["candidates"])


def test_the_verdict_is_judged_on_the_rows_it_flags() -> None:
    """Another implementation's world (a rolling slide, τ 0.02 s), 40 throws, two landings
    moved 0.3-1 m (world seed 4, of the tune range): their misses widen the repeats' floor
    (207.7 mm against a baseline of 204.4 mm), the first pass says `none`, and its flags on
    the baseline's misses take two real throws (rows 4 and 36) out with them. The passes go
    on until the last fit is made without the very rows its verdict flags: the two moved
    (the world's truth), the slide named, its robust held-out RMSE within the verdict's
    ratio of the floor it was judged on. (Before, the second pass's verdict, fitted without
    four rows, reported two, and rows 4 and 36 were out of its fit but in its robust RMSE.)"""
    from cell.gap.select import VERDICT_RATIO
    from cell.gap.world_other import draw_other_campaign
    from cell.log.table import ThrowTable

    slide = {"kind": "slide", "form": "const", "tau_s": 0.02}
    camp = draw_other_campaign([slide], np.random.default_rng(4), n=40, outliers=0.05)
    table = ThrowTable.from_records(camp.records)
    d, prob = diagnose_log(table, DEFAULT_EE, seed=4)
    rep = d.report
    fitted = set(prob.table.text("throw_id"))
    left_out = [i + 1 for i, t in enumerate(table.text("throw_id")) if t not in fitted]
    assert rep["outliers"]["rows"] == left_out == [i + 1 for i in camp.outliers] == [3, 16]
    assert rep["outliers"]["left_out_of_fit"] == 2
    assert rep["verdict"]["effects"] == ["bounce"]
    assert rep["verdict"]["heldout_rmse_robust_m"] <= VERDICT_RATIO * rep["noise_floor_m"]


@pytest.fixture(scope="module")
def scale_run() -> tuple:
    """A tracker 5 % off in scale, the cell's own launcher: the campaign and its diagnosis
    (drawn and diagnosed once for the two tests that read it)."""
    camp = draw_tracked_campaign(
        (TrackingScale(1.05),), np.random.default_rng(8), n=120, other_launcher=False
    )
    d, prob = diagnose_log(camp.table, DEFAULT_EE, tracks=camp.tracks)
    return camp, d, prob


def test_measurement_phase_from_tracks(scale_run: tuple) -> None:
    _, d, _ = scale_run
    assert d.report["where"]["phase"] == "measurement"
    assert d.report["tracks"]["g_ratio"] == pytest.approx(1.05, abs=0.01)
    assert d.report["verdict"]["effects"] == ["tracking_scale"]


@pytest.fixture(scope="module")
def stroke_offset_cli(tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """`cell gap` run once on a stroke-offset campaign with every output asked for (the
    JSON report, the HTML report, the Rerun recording): its log, its outputs and what it
    printed, for the two tests that read them."""
    tmp = tmp_path_factory.mktemp("gap_cli")
    camp = draw_campaign("stroke_offset", np.random.default_rng(21), n=160)
    log = tmp / "throws.csv"
    write_throws_csv(camp.table, log)
    params = tmp / "ee.yaml"
    params.write_text("effects: {bounce: {inv_mu: 0.0}}\n")
    files = {k: tmp / f"r.{k}" for k in ("json", "html", "rrd")}
    argv = ["gap", str(log), "--params", str(params), "--json", str(files["json"])]
    argv += ["--report", str(files["html"]), "--record", str(files["rrd"])]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue(), log, files


def test_cli_gap_writes_json_and_html(stroke_offset_cli: tuple, tmp_path) -> None:
    code, out, log, files = stroke_offset_cli
    assert code == 0
    assert "verdict" in out and "stroke_offset" in out
    rep = _no_nan(files["json"].read_text())
    assert rep["verdict"]["effects"] == ["stroke_offset"]
    text = files["html"].read_text()
    assert text.count("data:image/png;base64,") == 3
    bad = tmp_path / "bad.yaml"
    bad.write_text("effects: {gremlins: {}}\n")
    assert main(["gap", str(log), "--params", str(bad)]) == 2


def test_cli_gap_record_holds_every_throw_before_and_after_the_verdict(
    stroke_offset_cli: tuple,
) -> None:
    """`cell gap --record` (read back with Rerun's reader): every throw before and after
    the verdict; here, not in test_record_gap.py, to share `stroke_offset_cli`'s run."""
    from cell.log import read_throws_csv
    from cell.record.read import read_rows

    F32 = 1e-6  # [m] Rerun stores positions as float32
    code, out, log, files = stroke_offset_cli
    assert code == 0
    rrd = files["rrd"]
    assert f"recording -> {rrd}" in out
    rep = json.loads(files["json"].read_text())
    rows = read_rows(rrd)
    # the observed landings are the log's, in its order (read independently from the CSV)
    table = read_throws_csv(log)
    obs = np.asarray(rows["/world/landings/observed"][0]["Points3D:positions"])
    assert obs.shape == (len(table), 3)
    assert np.allclose(obs[:, :2], table.landed, atol=F32)
    assert np.allclose(obs[:, 2], table.num("land_z_m"), atol=F32)
    # one step per throw on the `throw` timeline; residuals = observed - model, per throw
    steps = rows["/world/throw/observed"]
    assert [r["throw"] for r in steps] == list(range(len(table)))
    before = np.asarray([r["Points3D:positions"] for r in rows["/world/throw/model_before"]])[:, 0]
    res_b = np.array([r["Scalars:scalars"] for r in rows["/gap/before_m"]])[:, 0]
    res_a = np.array([r["Scalars:scalars"] for r in rows["/gap/after_m"]])[:, 0]
    assert np.allclose(res_b, np.hypot(*(obs[:, :2] - before[:, :2]).T), atol=1e-5)
    # the verdict's effect shrinks the residuals, as the report says
    rms_b, rms_a = np.sqrt(np.mean(res_b**2)), np.sqrt(np.mean(res_a**2))
    assert rep["verdict"]["effects"] == ["stroke_offset"] and rms_a < 0.5 * rms_b
    assert rms_b == pytest.approx(rep["baseline"]["fit_rmse_m"], rel=1e-6)
    assert "stroke_offset" in rows["/verdict"][0]["TextDocument:text"][0]


def test_gap_record_draws_each_track_beside_the_model_flight(scale_run: tuple, tmp_path) -> None:
    """`cell.record.gap` (read back with Rerun's reader): each track beside the model's
    flight; here, not in test_record_gap.py, to share `scale_run`'s diagnosis."""
    from cell.model.throw import predict_landing
    from cell.record.gap import record_gap
    from cell.record.read import read_rows

    F32 = 1e-6  # [m] Rerun stores positions as float32
    camp, d, prob = scale_run
    rows = read_rows(record_gap(tmp_path / "gap.rrd", d, prob, camp.tracks))
    ids = prob.table.text("throw_id")
    tracks = rows["/world/throw/track"]
    flights = rows["/world/throw/model_flight"]
    assert len(tracks) == len(flights) == len(ids)
    k = 7
    got = np.asarray(tracks[k]["LineStrips3D:strips"][0])
    assert tracks[k]["throw"] == k
    assert np.allclose(got, camp.tracks[ids[k]][:, 1:4], atol=F32)
    # the model's flight leaves the logged release point and ends on the fast path's landing
    fl = np.asarray(flights[k]["LineStrips3D:strips"][0])
    release = [prob.table.num(c)[k] for c in ("x_m", "y_m", "z_m")]
    assert np.allclose(fl[0], release, atol=F32)
    land = predict_landing(prob.batch.take(np.array([k])), prob.ee)
    assert np.hypot(fl[-1, 0] - land.x[0], fl[-1, 1] - land.y[0]) < 2e-3
