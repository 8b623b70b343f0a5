"""The checks of the figures the guide pages docs/arms.md, docs/jobs.md and docs/gap_scene.md
quote (run by tests/test_readme_figures.py): measured figures against the JSON `make figures`
writes, rules and limits against the code's constants, the mount parser and the shipped
files."""

from __future__ import annotations

import inspect
import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.figure_quotes import COVERED, ROOT, close, load_json, note, page_text, quoted


def _as_written(q: str, value: float) -> None:
    """`q` is `value` to the decimals `q` is written with."""
    close(q.replace("−", "-"), value, len(q.split(".")[1]) if "." in q else 0)


# -- docs/arms.md ----------------------------------------------------------------------------
def check_the_arms_page() -> None:
    from cell.robot import mount
    from cell.sim.items import resolve_object

    page = "docs/arms.md"
    (longest,) = quoted(page, r"lower-case letters, digits and `_`, at most (\d+);")
    assert mount._NAME.fullmatch("a" * int(longest))
    assert not mount._NAME.fullmatch("a" * (int(longest) + 1))
    (acc,) = quoted(page, r"\| `acceleration_limits` \| per joint \[rad/s²\] \| one per joint, "
                    r"positive, at most (\d+) \|")  # fmt: skip
    assert float(acc) == mount.MAX_ACCELERATION
    (ten,) = quoted(page, r"\| one per joint, positive, at most (10)⁶ \|")
    assert float(ten) ** 6 == mount.MAX_JERK
    slow_acc, slow_jerk = quoted(
        page,
        r"An acceleration limit under `MIN_ACCELERATION` \(([\d.]+) rad/s²\) or a jerk limit "
        r"under `MIN_JERK` \(([\d.]+) rad/s³\) is refused",
    )
    assert (float(slow_acc), float(slow_jerk)) == (mount.MIN_ACCELERATION, mount.MIN_JERK)
    lo, hi, default = quoted(page, r"\| from (\d+) to (\d+) \(default (\d+), all around\) \|")
    facing = mount._facing
    where = Path("mount.yaml")
    assert facing({}, where) == math.pi and float(default) == 180.0
    assert facing({"facing_half_range_deg": float(hi)}, where) == math.pi
    assert facing({"facing_half_range_deg": float(lo)}, where) == pytest.approx(
        math.radians(float(lo))
    )
    for bad in (float(lo) - 0.01, float(hi) + 0.01):
        with pytest.raises(Exception, match="facing_half_range_deg"):
            facing({"facing_half_range_deg": bad}, where)
    # the demo job: 24 items, 18 thrown into the chutes, 6 placed into the totes
    job = yaml.safe_load((ROOT / "tasks/bins.yaml").read_text())
    run = load_json("docs/figures/run.json")
    items, thrown, near, far, placed = quoted(
        page,
        r"The demo's (\d+) items \((\d+) thrown into three chutes ([\d.]+)–([\d.]+) m out, "
        r"(\d+) placed into two totes\)",
    )
    assert (int(items), int(thrown), int(placed)) == (run["items"], run["thrown"], run["placed"])
    assert int(items) == sum(i["count"] for i in job["items"])
    chutes = [math.hypot(*b["position_m"]) for b in job["bins"] if b["id"].startswith("chute")]
    assert len(chutes) == 3
    close(near, min(chutes), 1)
    close(far, max(chutes), 1)
    mass_g, size_mm = quoted(page, r"the second `cyl70` \((\d+) g, (\d+) mm\)")
    cyl70, _ = resolve_object("cyl70")
    assert (float(mass_g), float(size_mm)) == (1000 * cyl70.mass, 1000 * cyl70.size[0])


# -- docs/arms.md and docs/jobs.md: the demo on the UR3 --------------------------------------
def _ur3_refusal() -> str:
    from cell.errors import CellError
    from cell.jobs import parse_job

    text = (ROOT / "tasks/bins.yaml").read_text().replace("robot: panda", "robot: ur3")
    with pytest.raises(CellError) as err:
        parse_job(text, "bins.yaml")
    return str(err.value)


def check_the_ur3_reach() -> None:
    from cell.jobcheck import STATION_HALF_M

    msg = _ur3_refusal()
    m = re.search(r"pick_station\.position_m: the ur3 arm does not reach", msg)
    assert m, msg
    (said,) = re.findall(r"reaches about ([\d.]+) m out at that height", msg)
    job = yaml.safe_load((ROOT / "tasks/bins.yaml").read_text())
    station = math.hypot(*job["pick_station"]["position_m"][:2])
    out, reach = quoted("docs/arms.md", r"its station is ([\d.]+) m out; the UR3's grip "
                        r"pointing down reaches about ([\d.]+) m at that height")  # fmt: skip
    close(out, station, 2)
    assert reach == said
    page = "docs/jobs.md"
    from cell.jobschema import BIN_WALL_M
    from cell.sim.bins import BinSpec

    (plate,) = quoted(page, r"above the bin's ([\d.]+) m floor plate")
    assert float(plate) == BIN_WALL_M == BinSpec.__dataclass_fields__["wall"].default
    (block,) = quoted(page, r"under the pick station's ([\d.]+) m block")
    close(block, 2 * STATION_HALF_M, 2)
    out, reach = quoted(page, r"its station, ([\d.]+) m out, is beyond the ([\d.]+) m the UR3's")
    close(out, station, 2)
    assert reach == said


# -- docs/gap_scene.md: the table ------------------------------------------------------------
_ROW = (
    r"\n\| (s:[\w+.-]+) \| ([\w+]+) \| ([\w+]+) \| ([^|]+) \| ((?:[^|\\]|\\\|)+) \| ([\d.]+) "
    r"\(F (\d+) mm(?:, F0 (\d+))?(?:; (\d+) with the flagged rows)?\) \| (yes|no) \|(?=\n)"
)


def _check_parameters(page: str, m: re.Match, row: dict[str, Any]) -> None:
    from cell.gap.scene_table import case_truths, flat_params

    cell, at = m.group(5), m.start(5)
    found_params = {e: flat_params(p) for e, p in row["params"].items()}
    truths, seen = case_truths(row), 0
    for p in re.finditer(
        r"(\w+)\.(\w+) (-?[\d.]+)(?: \((-?[\d.]+)\))?", cell.split(" proposal")[0]
    ):
        eff, key, found, truth = p.groups()
        _as_written(found, found_params[eff][key])
        if truth is not None:
            _as_written(truth, truths[f"{eff}.{key}"])
        COVERED[page].extend((at + a, at + b) for a, b in (p.span(3), p.span(4)) if a >= 0)
        seen += 1
    assert seen == sum(len(v) for v in found_params.values()), row["case"]
    prop = re.search(r" proposal \((\d+) terms?\): (.*?)(?: \+ …)?$", cell)
    if row["proposal"] is None:
        assert prop is None, row["case"]
        return
    assert prop, row["case"]
    terms = row["proposal"].split(" + ")
    assert int(prop.group(1)) == len(terms)
    assert prop.group(2).replace("\\|", "|") == " + ".join(terms[:2])
    COVERED[page].append((at + prop.start(1), at + prop.end(2)))


def check_the_gap_scene_table() -> None:
    from cell.gap.scene_table import scene_table

    page, doc = "docs/gap_scene.md", load_json("docs/figures/gap_check_scene.json")
    rows = {r["case"]: r for r in doc["campaigns"]}
    ms = list(re.finditer(_ROW, page_text(page)))
    assert [m.group(1) for m in ms] == list(rows), "every case once, in the JSON's order"
    for m in ms:
        note(page, m)
        row = rows[m.group(1)]
        assert (m.group(2), m.group(3), m.group(10)) == (
            row["truth"],
            row["verdict"],
            "yes" if row["passes"] else "no",
        )
        phases = "; ".join(f"{k}: {v}" for k, v in row["phases"].items()) or "—"
        assert m.group(4) == phases
        _check_parameters(page, m, row)
        close(m.group(6), row["after_over_floor"], 2)
        # the floor A was judged against: on the rows A was counted on (flagged rows out)
        close(m.group(7), 1000 * row["world_floor_kept_m"], 0)
        if m.group(8) is not None:  # F0 beside F where the effect's scatter raises it
            close(m.group(8), 1000 * row["world_floor0_kept_m"], 0)
        if m.group(9) is not None:  # F on every row where the flagged rows move it
            close(m.group(9), 1000 * row["world_floor_m"], 0)
    passes, total, diag, phase, params, ratio, floor = quoted(
        page,
        r"\n(\d+)/(\d+) pass; diagonal (\d+), phase (\d+), parameters (\d+), A ≤ ([\d.]+) F (\d+)\n",
    )
    assert [int(x) for x in (passes, total, diag, phase, params, floor)] == [
        doc[k] for k in ("passes", "total", "diagonal", "phase_ok", "params_ok", "floor_ok")
    ]
    assert float(ratio) == doc["criteria"]["floor_ratio"]
    # examples/11_gap_scene_table.py prints the table as the page shows it
    assert scene_table(doc) in page_text(page)


# -- docs/gap_scene.md: the worlds and what the table shows ----------------------------------
def _case(name: str) -> tuple[dict[str, Any], ...]:
    from cell.gap.check_scene import SCENE_CASES

    effects, *_ = SCENE_CASES[name]
    return tuple(effects)


def _drag_ratios() -> dict[str, float]:
    """Per thesis14 object, the configured model's drag constant over the scene's (as
    `cell.gap.world_scene.matched_objects` computes it)."""
    from cell.catalogue import catalogue
    from cell.params import load_params, scene_params_path
    from cell.sim.items import resolve_object

    path = scene_params_path()
    assert path is not None
    mp, out = load_params(path), {}
    for k, e in catalogue().items():
        if e.set == "thesis14" and k in mp.objects:
            true, _ = resolve_object(k)
            c = mp.objects[k]
            out[k] = (c.cd * c.area / c.mass) / (true.cd * true.area / true.mass)
    return out


def check_the_gap_scene_worlds() -> None:
    """The worlds as the page describes them are `cell.gap.world_scene` and the cases."""
    from cell.gap import world_scene as ws
    from cell.gap.check_scene import _JET
    from cell.sim import effect_scene

    page = "docs/gap_scene.md"
    src = inspect.getsource(ws) + inspect.getsource(effect_scene)
    (sd,) = quoted(page, r"steady; drawn throw to throw around a mean \(sd ([\d.]+) m/s;")
    assert float(sd) == _case("s:wind-throw")[0]["sd"]
    rpm0, core, radius, grow, lo, hi = quoted(
        page,
        r"centre speed w · rpm / (\d+) falling as 1 / \(1 \+ depth / ([\d.]+) m\), radius "
        r"([\d.]+) m \+ ([\d.]+) · depth .*? rotor speeds (\d+)–(\d+) rpm",
    )
    assert f"rpm / {float(rpm0)} / (1.0 + depth" in src
    assert (float(core), float(radius)) == (_JET["core_m"], _JET["radius_m"])
    assert f"+ {grow} * depth" in src and f"rng.uniform({lo}, {hi})" in src
    wait, mu, e, roll, e_hop = quoted(
        page,
        r"where it still rolls (\d+) s after crossing .*? a floor of μ ([\d.]+), e ([\d.]+); "
        r"balls rolling on it with a rolling friction of ([\d.]+) m; every object on a bouncy "
        r"floor \(e ([\d.]+)\)",
    )
    assert float(wait) == ws.REST_WAIT_S
    slide, rolls, hop = (_case(n)[0] for n in ("s:bounce-slide", "s:bounce-roll", "s:bounce-hop"))
    assert (float(mu), float(e)) == (slide["friction"], slide["restitution"])
    assert float(roll) == rolls["rolling_m"] and float(e_hop) == hop["restitution"]
    s1, s2, lat, s3, s4, lat2 = quoted(
        page,
        r"\| s = ([\d.]+); s = ([\d.]+) with (\d+) ms latency; s = ([\d.]+); s = ([\d.]+); a "
        r"latency of (\d+) ms alone",
    )
    assert float(s1) == _case("s:scale")[0]["scale"]
    t2 = _case("s:scale+latency")[0]
    assert float(s2) == t2["scale"] and float(lat) == 1000 * t2["latency_s"]
    assert (float(s3), float(s4)) == (
        _case("s:scale-1.02")[0]["scale"],
        _case("s:scale-0.98")[0]["scale"],
    )
    assert float(lat2) == 1000 * _case("s:latency")[0]["latency_s"]
    side, side_x = quoted(page, r"\| a = ([\d.]+) m/s² across; ([\d.]+) m/s² along −x \|")
    assert float(side) == _case("s:side-force")[0]["y_mps2"]
    assert -float(side_x) == _case("s:side-force-x")[0]["x_mps2"]
    yaw_k, speed_k = quoted(page, r"\| yaw_k ([\d.]+) rad/m; speed_k ([\d.]+) /m \|")
    assert float(yaw_k) == _case("s:launch-yaw-stroke")[0]["yaw_k"]
    assert float(speed_k) == _case("s:launch-speed-stroke")[0]["speed_k"]
    sd2, mean2 = quoted(page, r"; sd ([\d.]+) m/s about ([\d.]+) m/s along x\)")
    wide = _case("s:wind-throw-wide")[0]
    assert (float(sd2), float(mean2)) == (wide["sd"], wide["x_mps"])
    *factors, k = quoted(page, r"constant \(factors ([\d.]+), ([\d.]+) and ([\d.]+)\); one factor "
                         r"per object; factor = k · stroke \(k (\d+) /m\)")  # fmt: skip
    names = ("s:drag-const", "s:drag-low", "s:drag-high")
    assert [float(f) for f in factors] == [_case(n)[0]["value"] for n in names]
    assert float(k) == _case("s:drag-stroke")[0]["k"]
    from cell.gap.check_scene import _JET_STRONG

    w, core2, rad2, grow2 = quoted(page, r"a wide, strong jet \(w (\d+) m/s, 1 / \(1 \+ depth / "
                                   r"([\d.]+) m\), radius ([\d.]+) m \+ ([\d.]+) · depth\)")  # fmt: skip
    assert (float(w), float(core2), float(rad2)) == tuple(
        _JET_STRONG[k] for k in ("w_mps", "core_m", "radius_m")
    )
    assert f"+ {grow2} * depth" in src
    mu3, mu5, hard = quoted(page, r"blocks on a floor of μ ([\d.]+); one ball size \(sphere55\) "
                            r"rolling; the bouncy floor at μ ([\d.]+); the balls on a hard floor, "
                            r"rolling friction ([\d.]+) m, where they roll")  # fmt: skip
    assert float(mu3) == _case("s:bounce-slide-mu03")[0]["friction"]
    assert float(mu5) == _case("s:bounce-hop-mu05")[0]["friction"]
    assert float(hard) == _case("s:bounce-roll-hard")[0]["rolling_m"]
    (rel,) = quoted(page, r"v\(t\) = w − w / \(1 \+ \(c/m\) w t\), within ([\d.]+) %\)")
    rels = re.findall(r"rel=([\d.e-]+)\)", (ROOT / "tests/test_gap_scene.py").read_text())
    assert float(rel) / 100 == pytest.approx(float(rels[0]))
    plane, scatter, share, o_lo, o_hi = quoted(
        page,
        r"the crossing of z = ([\d.]+) m .*? a tracker's scatter of (\d+) mm per axis .*? cases, "
        r"(\d+) % of landings moved by ([\d.]+)–(\d+) m",
    )
    assert float(plane) == ws.LAND_Z_M
    noise = inspect.signature(ws.draw_scene_campaign).parameters["noise_m"].default
    assert float(scatter) == 1000 * noise
    assert float(share) / 100 == dict(_case_options("s:none+outliers"))["outliers"]
    assert f"rng.uniform({o_lo}, {float(o_hi)}, pick.size)" in src
    a_lo, a_hi, d_lo, d_hi, box = quoted(
        page,
        r"Releases are ([\d.]+)–([\d.]+) m high \(([\d.]+)–([\d.]+) m under a drone\), within "
        r"±([\d.]+) m of the origin",
    )
    assert f"rng.uniform({d_lo}, {d_hi}) if drone else rng.uniform({a_lo}, {a_hi})" in src
    assert f"rng.uniform(-{box}, {box})" in src
    from cell.gap.check_other import PARAM_TOL
    from cell.gap.laws import MIN_LEVELS

    levels, tol = quoted(page, r"covariate takes at least (\d+) values in the log .*? every "
                         r"object's value within (\d+) % of the world's")  # fmt: skip
    assert int(levels) == MIN_LEVELS and float(tol) == 100 * PARAM_TOL
    (ratio,) = quoted(page, r"asks for the verdict's robust held-out RMSE A ≤ ([\d.]+) × that")
    assert float(ratio) == load_json("docs/figures/gap_check_scene.json")["criteria"]["floor_ratio"]


def _case_options(name: str) -> dict[str, Any]:
    from cell.gap.check_scene import SCENE_CASES

    return SCENE_CASES[name][4]


def check_the_gap_scene_prose() -> None:
    from cell.gap.diagnose import NONE_RATIO
    from cell.gap.world_scene import draw_scene_campaign

    check_the_gap_scene_worlds()
    page, doc = "docs/gap_scene.md", load_json("docs/figures/gap_check_scene.json")
    rows = {r["case"]: r for r in doc["campaigns"]}
    scatter, band = quoted(page, r"log with a scatter of (\d+) mm per axis \(a camera's landing "
                           r"spot\), under which this mismatch is within the (\d+) % band")  # fmt: skip
    noise = inspect.signature(draw_scene_campaign).parameters["noise_m"].default
    assert float(scatter) == 1000 * noise
    close(band, 100 * (NONE_RATIO - 1), 0)
    # the drag constants of the configured model against the scene's
    ratios = _drag_ratios()
    lo, hi, *named = quoted(
        page,
        r"by a factor of ([\d.]+)–([\d.]+) per object \(cube30 ([\d.]+), sphere40 ([\d.]+), "
        r"cube40 ([\d.]+), cyl40 ([\d.]+), cube50 ([\d.]+), …, cyl70 ([\d.]+)\)",
    )
    close(lo, min(ratios.values()), 2)
    close(hi, max(ratios.values()), 2)
    for q, k in zip(
        named, ("cube30", "sphere40", "cube40", "cyl40", "cube50", "cyl70"), strict=True
    ):
        close(q, ratios[k], 2)
    wind, n_obj, tol = quoted(page, r"a ([\d.]+) m/s wind over all (\d+) objects .*? configured "
                              r"drag constant is within (\d+) % of the scene's")  # fmt: skip
    assert float(wind) == _case("s:wind-all-objects")[0]["x_mps"]
    assert int(n_obj) == len(ratios)
    from cell.gap.world_scene import matched_objects

    close(tol, 100 * inspect.signature(matched_objects).parameters["tol"].default, 0)
    assert rows["s:wind"]["objects"] == sorted(k for k, r in ratios.items() if abs(r - 1) <= 0.1)
    # the run
    cases, n, n_free, workers, secs = quoted(
        page,
        r"\((\d+) cases, (\d+) throws each plus (\d+) effect-free; (\d) (?:Ray )?workers? .*? the "
        r"diagnoses alone (\d+) s\)",
    )
    assert int(cases) == doc["total"] == len(rows)
    assert {r["throws"] for r in rows.values()} == {int(n)} and int(n_free) == int(n)
    cmd_n, cmd_workers = quoted(page, r"`cell gap check --worlds scene --n (\d+) --workers (\d) "
                                r"--json docs/figures/gap_check_scene.json`\n\(")  # fmt: skip
    assert (cmd_n, cmd_workers) == (n, workers)
    close(secs, sum(r["seconds"] for r in rows.values()), 0)
    _check_what_passes(page, rows)
    from tests.figure_checks_scene import check_the_launch_jitter_and_floor, check_the_repeats_table

    check_the_launch_jitter_and_floor(rows)
    check_the_repeats_table()
    from tests.figure_checks_scene import check_what_does_not

    check_what_does_not(page, rows, ratios)
    # tests/test_gap_scene.py's strong-wind case
    test = (ROOT / "tests/test_gap_scene.py").read_text()
    speed, throws, within, ratio = quoted(
        page,
        r"a ([\d.]+) m/s wind thrown in the scene \((\d+) throws\) named `wind`, phase\s+flight, "
        r"its speed within (\d+) % and A within ([\d.]+) × the world's floor",
    )
    wx, wy = (float(v) for v in re.findall(r'"x_mps": ([\d.]+), "y_mps": -([\d.]+)', test)[0])
    close(speed, math.hypot(wx, wy), 1)
    assert f"n={throws}," in test and f"rel={int(within) / 100:g})" in test
    assert f"<= {ratio} * camp.floor_m" in test


def _term(row: dict[str, Any], pattern: str) -> float:
    """A proposal's coefficient (the first term matching `pattern`, one group)."""
    (value,) = re.findall(pattern, row["proposal"])
    return float(value)


def _check_what_passes(page: str, rows: dict[str, dict[str, Any]]) -> None:
    from cell.gap.check_other import PARAM_TOL

    (share,) = quoted(page, r"drone throws, with (\d+) % outliers, all four")
    assert float(share) / 100 == _case_options("s:none+outliers")["outliers"]
    for c in ("s:none", "s:none-drone", "s:none+outliers", "s:latency"):
        assert rows[c]["passes"], c
    out = rows["s:none+outliers"]
    assert out["outliers_found"] == out["outliers_true"] == 4 and out["outliers_false"] == 0
    lo, hi = quoted(page, r"with outliers \(within (\d+)–(\d+) % per component\)")
    winds = ("s:wind-throw", "s:wind+outliers", "s:wind-low", "s:wind-y")
    errs = [e for c in winds for e in rows[c]["param_errors"].values()]
    assert all(rows[c]["passes"] for c in winds)
    close(lo, 100 * min(errs), 0)
    close(hi, 100 * max(errs), 0)
    f1, tol, cube, sphere, f_low, f2 = quoted(
        page,
        r"drag at factors ([\d.]+) \(told per object, every object within (\d+) %: cube30 "
        r"([\d.]+), sphere40 ([\d.]+)\), ([\d.]+) and ([\d.]+) \(with outliers\)",
    )
    assert float(f_low) == _case("s:drag-low")[0]["value"] and rows["s:drag-low"]["passes"]
    assert float(f1) == _case("s:drag-const")[0]["value"] and float(tol) == 100 * PARAM_TOL
    per = rows["s:drag-const"]["params"]["drag_scale"]["per_object"]
    _as_written(cube, per["cube30"])
    _as_written(sphere, per["sphere40"])
    assert float(f2) == _case("s:drag+outliers")[0]["value"] and rows["s:drag+outliers"]["passes"]
    scales = quoted(page, r"the tracker scale in five cases \(([\d.]+); ([\d.]+) with a latency; "
                    r"([\d.]+); ([\d.]+); ([\d.]+) with outliers\), each within the check's ([\d.]+) %")  # fmt: skip
    names = ("s:scale", "s:scale+latency", "s:scale-1.02", "s:scale-0.98", "s:scale+outliers")
    for q, c in zip(scales[:5], names, strict=True):
        assert float(q) == _case(c)[0]["scale"] and rows[c]["passes"]
    doc = load_json("docs/figures/gap_check_scene.json")
    close(scales[5], 100 * doc["criteria"]["scale_tol"], 1)
    hop = rows["s:bounce-hop"]
    found, measured = quoted(page, r"the bouncy floor \(1/μ ([\d.]+) against ([\d.]+) measured\)")
    _as_written(found, hop["params"]["bounce"]["inv_mu"])
    _as_written(measured, hop["world_truth"]["inv_mu"])
    fy, wy, fx, wx, yaw, wyaw = quoted(
        page,
        r"a force along y of ([\d.]+) m/s² \(the world's ([\d.]+)\), a force along x of "
        r"(−[\d.]+) m/s² \((−[\d.]+)\), and a launch yaw error of ([\d.]+) rad per metre of "
        r"stroke \(([\d.]+)\)",
    )
    _as_written(fy, _term(rows["s:side-force"], r"force y \[m/s²\] = ([\d.-]+)(?: \+|$)"))
    assert float(wy) == _case("s:side-force")[0]["y_mps2"]
    _as_written(fx, _term(rows["s:side-force-x"], r"force x \[m/s²\] = ([\d.-]+)"))
    quoted(page, r"each `unknown` with a proposal that names it, (as its only term): a force")
    for c in ("s:side-force", "s:side-force-x", "s:launch-yaw-stroke"):
        assert " + " not in rows[c]["proposal"], (c, rows[c]["proposal"])  # one term
    assert float(wx.replace("−", "-")) == _case("s:side-force-x")[0]["x_mps2"]
    _as_written(
        yaw, _term(rows["s:launch-yaw-stroke"], r"azimuth error \[rad\] = ([\d.]+) · stroke")
    )
    assert float(wyaw) == _case("s:launch-yaw-stroke")[0]["yaw_k"]


def check_the_realtime_page() -> None:
    from cell.bench.bench_realtime import LAYOUT_SEEDS

    a, b = quoted("docs/realtime.md", r"on test layouts (\d+) and (\d+)")
    assert (int(a), int(b)) == LAYOUT_SEEDS
