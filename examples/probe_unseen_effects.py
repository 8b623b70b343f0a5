"""Probe `cell gap` with throw logs of effects its vocabulary does not have.

A world of its own draws campaigns of throws (several catalogue objects, strokes and
elevations, each configuration thrown twice, shuffled), writes each as a throw log
(docs/throw_log.md: the required columns, and `session`, `time_s`, `t_flight_s` where the
world has them), runs `python -m cell gap LOG.csv --json` on it in a separate process, one
at a time, and judges the verdict.

The world imports nothing of the cell's model or diagnosis. It implements the model's
documented launch (MODEL.md's band law with the reference end-effector's values: the
push f_o = 2 f_e(ΔL) cos α along the throw axis for dt = 12 ms, from the logged grip
centre) and its flight (gravity and quadratic drag ½ρC_dA|v|v with the shape's C_d and
the mean projected area surface / 4) with SciPy's `solve_ivp` (DOP853, the landing found
by a terminal event on the landing surface). Objects are read from the catalogue's file
(`cell/data/catalogue.yaml`: shape, mass, extents). Effects it can add (`EFFECTS`):

| case | what the world does | in the vocabulary? |
|---|---|---|
| `none` | Gaussian landing scatter only | control: `none` |
| `heavy_noise` | Student-t scatter (3 degrees of freedom), no effect | control: `none` |
| `ctl_wind` | a steady wind in the drag law | control: `wind` |
| `ctl_band_mass` | the push drives m + 8 g | control: `band_mass` |
| `ctl_rolling` | the item rolls on τ·v_h after touchdown | control: `bounce` |
| `magnus_v0` | backspin ω = c·(launch speed), Magnus lift ∝ ω × v | no (the tool's spin is one ω) |
| `latency` | landings read from a tracker lagging τ: the point where the item was τ before touchdown, `t_flight_s` late by τ | no |
| `band_wear` | the push force falls with the throw's row: × (1 − a·row / n) | no |
| `late_gust` | a level wind only while the item descends | no |
| `yaw_mass` | the throw axis turned in azimuth by k·mass | no |
| `tilted_floor` | the landing surface tilted 3° (logged as level) | no |
| `sessions` | two sessions (`session` column), the second's push force 4 % lower | no |

Each row gives: the world's floor F_w (RMS distance of the logged landings from the same
world's landings without scatter: what no model of the effect could remove; also its
robust version, the median distance scaled to a Gaussian scatter's RMS), the effect's
size E (RMS distance between the world's landings with and
without the effect, both without scatter), the tool's verdict, phase, law, its noise floor
F, baseline B and after A (plain and robust, held out), the proposal when `unknown`, and
the judgement:

- OK: a control named right with A within 1.3 × F_w (a `none` control `none`); an effect
  outside the vocabulary `unknown` with a law proposed, the proposal's phase and the
  report's `where` both the world's, or named as an in-vocabulary effect whose physics is
  the same (`EQUIVALENT`) with A within 1.3 × F_w.
- PARTIAL: `unknown` with `where` the world's phase but no law proposed.
- NOT OK: anything else: a traceback; an effect named that the world does not have (or
  in another phase); a named verdict whose robust A is over 1.3 × F_w; `none` where E is
  over 3 × F_w; `unknown` placed in another phase than the world's.

    PYTHONPATH=. python examples/probe_unseen_effects.py [--cases NAME ...] [--n 200]
        [--seed 0] [--json OUT.json] [--keep DIR] [--markdown]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
CATALOGUE = ROOT / "cell" / "data" / "catalogue.yaml"

G = 9.81  # [m/s²]
RHO = 1.225  # [kg/m³] air
# MODEL.md's reference end-effector (lengths [m], stiffnesses [N/m^k], push [s])
R_R, L1, PHI, HOOP, L_T, L0 = 0.010, 0.030, math.pi / 2, 0.020, 0.160, 0.095
KE3, KE2, KE1, KC, PUSH_S = 400.0, 150.0, 114.6, 0.0, 0.012
CD = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47}
PROBE_OBJECTS = ("cube30", "cube50", "cuboid_c", "cyl50", "cyl70", "sphere40", "sphere70")
STROKES_M = np.linspace(0.03, 0.11, 9)
ELEVATIONS_DEG = (10.0, 25.0, 40.0, 55.0)
NOISE_M = 0.010  # [m] landing scatter per axis (Gaussian)
FLOOR_RATIO = 1.3  # a named verdict must bring A within this × the world's floor
NONE_EFFECT_RATIO = 3.0  # `none` is wrong where the effect is over this × the floor

# case -> (effects, expected verdict or "unknown", the world's phase)
EFFECTS: dict[str, tuple[dict[str, Any], str, str]] = {
    "none": ({}, "none", "-"),
    "heavy_noise": ({"t_noise_df": 3.0}, "none", "-"),
    "ctl_wind": ({"wind_mps": (1.0, -0.6)}, "wind", "flight"),
    "ctl_band_mass": ({"band_mass_kg": 0.008}, "band_mass", "launch"),
    "ctl_rolling": ({"roll_tau_s": 0.05}, "bounce", "landing"),
    "magnus_v0": ({"magnus_per_mps": 8.0}, "unknown", "flight"),
    "latency": ({"latency_s": 0.04}, "unknown", "measurement"),
    "band_wear": ({"wear_share": 0.06}, "unknown", "launch"),
    "late_gust": ({"late_gust_mps": (1.5, 1.5)}, "unknown", "flight"),
    "yaw_mass": ({"yaw_per_kg": 0.6}, "unknown", "launch"),
    "tilted_floor": ({"tilt_deg": 3.0, "tilt_dir_deg": 30.0}, "unknown", "landing"),
    "sessions": ({"session_force": (1.0, 0.96)}, "unknown", "launch"),
}
# an outside effect the tool may name as one of its own: the physics is the same
# (case -> {effect name: why}); anything else named is wrong
EQUIVALENT: dict[str, dict[str, str]] = {
    "magnus_v0": {"spin": "the same Magnus lift, normal to v in its vertical plane"},
    "late_gust": {"wind": "air moving in the drag law, on part of the flight"},
}


def load_objects() -> dict[str, tuple[str, float, tuple[float, float, float]]]:
    """The probe's objects from the catalogue file: id -> (shape, mass [kg], extents [m])."""
    with CATALOGUE.open() as f:
        cat = yaml.safe_load(f)["objects"]
    out = {}
    for oid in PROBE_OBJECTS:
        o = cat[oid]
        out[oid] = (str(o["shape"]), float(o["mass_kg"]), tuple(float(s) for s in o["size_m"]))
    return out  # type: ignore[return-value]


def push_force(stroke_m: float, width_m: float) -> float:
    """The band's push on the item [N] (MODEL.md eqs. 3.1-3.9, C = 0)."""
    half = (width_m - HOOP) / 2.0
    l2 = math.hypot(half, L_T - stroke_m)
    dl = L1 + R_R * PHI + HOOP / 2.0 + l2 - L0
    fe = max(KE3 * dl**3 + KE2 * dl**2 + KE1 * dl + KC, 0.0) if dl > 0 else 0.0
    return 2.0 * fe * math.cos(math.atan2(width_m - HOOP, 2.0 * (L_T - stroke_m)))


def drag_area(shape: str, size: tuple[float, float, float]) -> float:
    """Mean projected area [m²]: the surface over 4 (Cauchy), x the diameter of round ones."""
    x, y, z = size
    if shape == "sphere":
        return math.pi * x * x / 4.0
    if shape == "cylinder":
        return (2.0 * math.pi * (x / 2) ** 2 + 2.0 * math.pi * (x / 2) * z) / 4.0
    return (x * y + y * z + z * x) / 2.0


def draw_throws(n: int, rng: np.random.Generator) -> list[dict[str, Any]]:
    """n throws: configurations (object, stroke, elevation, azimuth, grip centre) drawn at
    random, each thrown twice, the log's order shuffled."""
    objs = load_objects()
    names = list(objs)
    cfgs = []
    for _ in range(-(-n // 2)):
        oid = names[int(rng.integers(len(names)))]
        shape, mass, size = objs[oid]
        c = {
            "object_id": oid, "shape": shape, "mass_kg": mass, "size": size,
            "stroke_m": float(rng.choice(STROKES_M)),
            "elevation_rad": math.radians(float(rng.choice(ELEVATIONS_DEG))),
            "azimuth_rad": float(rng.uniform(-math.pi, math.pi)),
            "p0": (float(rng.uniform(-0.2, 0.4)), float(rng.uniform(-0.3, 0.3)),
                   float(rng.uniform(0.4, 0.9))),
        }  # fmt: skip
        cfgs += [c, c]
    order = rng.permutation(len(cfgs))[:n]
    return [dict(cfgs[i]) for i in order]


def _flight(throw: dict[str, Any], eff: dict[str, Any], row: int, n: int) -> dict[str, Any]:
    """One throw through this world: the touchdown point, time and velocity, and the
    dense solution of the flight (for a tracker's delayed reading)."""
    m = throw["mass_kg"]
    shape, size = throw["shape"], throw["size"]
    kd = 0.5 * RHO * CD[shape] * drag_area(shape, size) / m  # [1/m]
    e = throw["elevation_rad"]
    a = throw["azimuth_rad"] + eff.get("yaw_per_kg", 0.0) * m
    u = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    f_o = push_force(throw["stroke_m"], size[0])
    f_o *= 1.0 - eff.get("wear_share", 0.0) * row / n
    if "session_force" in eff:
        f_o *= eff["session_force"][0 if row < n // 2 else 1]
    m_push = m + eff.get("band_mass_kg", 0.0)
    wind = np.zeros(3)
    if "wind_mps" in eff:
        wind[:2] = eff["wind_mps"]

    def push(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty(6)
        out[:3] = y[3:]
        rel = y[3:] - wind
        acc = f_o / m_push * u - kd * m / m_push * math.sqrt(rel @ rel) * rel
        acc[2] -= G
        out[3:] = acc
        return out

    y0 = np.array([*throw["p0"], 0.0, 0.0, 0.0])
    sol = solve_ivp(push, (0.0, PUSH_S), y0, method="DOP853", rtol=1e-10, atol=1e-12)
    y1 = sol.y[:, -1]
    v0 = float(np.linalg.norm(y1[3:]))
    # backspin: ω along (throw direction × z), its size c · launch speed
    d_h = np.array([math.cos(a), math.sin(a), 0.0])
    omega = eff.get("magnus_per_mps", 0.0) * v0 * np.cross(d_h, [0.0, 0.0, 1.0])
    k_mag = 0.5 * RHO * drag_area(shape, size) * (size[0] / 2.0) / m  # lift coefficient ωr/|v|
    gust = np.zeros(3)
    if "late_gust_mps" in eff:
        gust[:2] = eff["late_gust_mps"]
    tilt = math.radians(eff.get("tilt_deg", 0.0))
    tdir = math.radians(eff.get("tilt_dir_deg", 0.0))
    slope = math.tan(tilt) * np.array([math.cos(tdir), math.sin(tdir)])

    spin = bool(omega.any())

    def rates(air: np.ndarray) -> Any:
        def f(t: float, y: np.ndarray) -> np.ndarray:
            out = np.empty(6)
            out[:3] = y[3:]
            rel = y[3:] - air
            acc = -kd * math.sqrt(rel @ rel) * rel
            if spin:
                acc += k_mag * np.cross(omega, y[3:])
            acc[2] -= G
            out[3:] = acc
            return out

        return f

    def ground(t: float, y: np.ndarray) -> float:
        return float(y[2] - float(slope @ y[:2]))

    ground.terminal = True  # type: ignore[attr-defined]
    ground.direction = -1  # type: ignore[attr-defined]

    def apex(t: float, y: np.ndarray) -> float:
        return float(y[5])

    apex.terminal = True  # type: ignore[attr-defined]
    apex.direction = -1  # type: ignore[attr-defined]
    segs = []
    t0, y = PUSH_S, y1
    events = [ground, apex] if gust.any() else [ground]
    s = solve_ivp(rates(wind), (t0, 6.0), y, method="DOP853", rtol=1e-10, atol=1e-12,
                  events=events, dense_output=True)  # fmt: skip
    segs.append(s)
    if gust.any() and s.t_events[1].size and not s.t_events[0].size:
        s = solve_ivp(rates(wind + gust), (s.t[-1], 6.0), s.y[:, -1], method="DOP853",
                      rtol=1e-10, atol=1e-12, events=[ground], dense_output=True)  # fmt: skip
        segs.append(s)
    if not segs[-1].t_events[0].size:
        raise RuntimeError("a throw did not land within 6 s")
    t_land = float(segs[-1].t_events[0][0])
    y_land = segs[-1].y_events[0][0]

    def at(t: float) -> np.ndarray:
        for sg in segs:
            if sg.t[0] <= t <= sg.t[-1]:
                return np.asarray(sg.sol(t))
        return y1 if t < PUSH_S else y_land

    xy = y_land[:2].copy()
    t_log = t_land
    if "latency_s" in eff:
        xy = at(t_land - eff["latency_s"])[:2].copy()
        t_log = t_land + eff["latency_s"]
    if "roll_tau_s" in eff:
        xy = xy + eff["roll_tau_s"] * y_land[3:5]
    return {"xy": xy, "t": t_log}


def world_landings(
    throws: list[dict[str, Any]], eff: dict[str, Any]
) -> tuple[np.ndarray, np.ndarray]:
    """(logged landing xy (n, 2) [m], logged flight time (n,) [s]) without scatter."""
    n = len(throws)
    out = [_flight(th, eff, i, n) for i, th in enumerate(throws)]
    return np.array([o["xy"] for o in out]), np.array([o["t"] for o in out])


def draw_campaign(case: str, n: int, seed: int) -> dict[str, Any]:
    """One case's campaign: the throws, the logged landings, the world's floor and the
    effect's size."""
    eff = EFFECTS[case][0]
    rng = np.random.default_rng([seed, sorted(EFFECTS).index(case)])
    throws = draw_throws(n, rng)
    xy, t_log = world_landings(throws, eff)
    plain, _ = world_landings(throws, {k: v for k, v in eff.items() if k == "t_noise_df"})
    if "t_noise_df" in eff:
        df = eff["t_noise_df"]
        noise = NOISE_M * rng.standard_t(df, (n, 2))
    else:
        noise = rng.normal(0.0, NOISE_M, (n, 2))
    obs = xy + noise
    dist = np.linalg.norm(noise, axis=1)
    return {
        "throws": throws, "landed": obs, "t_flight": t_log,
        "floor_m": float(np.sqrt(np.mean(dist**2))),
        # the floor a robust scale gives: the median 2-D distance of a Gaussian scatter is
        # σ√(2 ln 2), its RMS σ√2
        "floor_robust_m": float(np.median(dist) * math.sqrt(2.0) / math.sqrt(2.0 * math.log(2.0))),
        "effect_m": float(np.sqrt(np.mean(np.sum((xy - plain) ** 2, axis=1)))),
    }  # fmt: skip


def write_log(camp: dict[str, Any], case: str, path: Path) -> None:
    """The campaign as a throw log (docs/throw_log.md columns)."""
    eff = EFFECTS[case][0]
    n = len(camp["throws"])
    cols = ["throw_id", "object_id", "shape", "mass_kg", "size_x_m", "size_y_m", "size_z_m",
            "stroke_m", "x_m", "y_m", "z_m", "elevation_rad", "azimuth_rad", "roll_rad",
            "vx_mps", "vy_mps", "vz_mps", "platform", "rotor_rpm", "land_z_m", "landed_x_m",
            "landed_y_m", "time_s", "session", "t_flight_s"]  # fmt: skip
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for i, th in enumerate(camp["throws"]):
            sess = "s1"
            if "session_force" in eff and i >= n // 2:
                sess = "s2"
            w.writerow([
                f"p{i:04d}", th["object_id"], th["shape"], th["mass_kg"], *th["size"],
                th["stroke_m"], *th["p0"], th["elevation_rad"], th["azimuth_rad"], 0.0,
                0.0, 0.0, 0.0, "arm", 0.0, 0.0, *(f"{v:.6f}" for v in camp["landed"][i]),
                f"{30.0 * i:.1f}", sess, f"{camp['t_flight'][i]:.4f}",
            ])  # fmt: skip


def diagnose(path: Path, out: Path, seed: int) -> tuple[dict[str, Any] | None, str, float]:
    """`python -m cell gap LOG --json OUT` in its own process: (report or None, the
    error's last lines, its CPU time [s])."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    p = subprocess.run(
        [sys.executable, "-m", "cell", "gap", str(path), "--json", str(out), "--seed", str(seed)],
        capture_output=True, text=True, env=env, cwd=ROOT, check=False,
    )  # fmt: skip
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if p.returncode != 0 or not out.exists():
        return None, "\n".join((p.stderr or p.stdout).strip().splitlines()[-3:]), cpu
    return json.loads(out.read_text()), "", cpu


def judge(case: str, camp: dict[str, Any], rep: dict[str, Any] | None, err: str) -> dict[str, Any]:
    """The row: what the tool said and whether it is OK (module docstring)."""
    _, expect, world_phase = EFFECTS[case]
    row: dict[str, Any] = {
        "case": case, "expect": expect, "world_phase": world_phase,
        "world_floor_m": camp["floor_m"], "world_floor_robust_m": camp["floor_robust_m"],
        "effect_m": camp["effect_m"],
    }  # fmt: skip
    if rep is None:
        return {**row, "verdict": "traceback", "judged": "NOT OK", "ok": False, "why": err}
    v = rep["verdict"]
    verdict = "+".join(sorted(v["effects"]))
    after = float(v.get("heldout_rmse_robust_m", v["heldout_rmse_m"]))
    prop = rep.get("proposal") or {}
    row.update({
        "verdict": verdict, "where": rep["where"]["phase"], "phases": v.get("phases", {}),
        "laws": v.get("laws", {}), "params": v.get("params", {}),
        "partial": v.get("partial_effects", []),
        "tool_floor_m": rep["noise_floor_m"], "baseline_m": rep["baseline"]["heldout_rmse_m"],
        "after_m": float(v["heldout_rmse_m"]), "after_robust_m": after,
        "after_over_floor": after / camp["floor_m"],
        "outliers": len(rep.get("outliers", {}).get("rows", [])),
        "proposal": prop.get("law"), "proposal_phase": prop.get("phase"),
        "proposal_after_m": prop.get("heldout_rmse_after_m"),
    })  # fmt: skip
    return {**row, **judge_row(row)}


def judge_row(row: dict[str, Any]) -> dict[str, Any]:
    """`judged` (OK, PARTIAL or NOT OK), `ok` and `why` of a row (module docstring)."""
    if row["verdict"] == "traceback":
        return {"judged": "NOT OK", "ok": False, "why": row.get("why", "traceback")}
    expect, world_phase, floor = row["expect"], row["world_phase"], row["world_floor_m"]
    after = row["after_robust_m"]
    named = [e for e in row["verdict"].split("+") if e not in ("none", "unknown")]
    judged = "NOT OK"
    if expect == "none":
        ok, why = row["verdict"] == "none", "pure scatter: `none` expected"
    elif expect != "unknown":
        ok = row["verdict"] == expect and after <= FLOOR_RATIO * floor
        why = f"control: `{expect}` expected within {FLOOR_RATIO} × F_w"
    elif row["verdict"] == "unknown":
        phases = (row["where"], row["proposal_phase"])
        ok = row["proposal"] is not None and phases == (world_phase, world_phase)
        why = f"`unknown`; where {phases[0]}, proposal {phases[1]}, the world's {world_phase}"
        if row["proposal"] is None and row["where"] == world_phase:
            judged, why = "PARTIAL", f"`unknown` in the {world_phase}, no law proposed"
    elif row["verdict"] == "none":
        ok = row["effect_m"] <= NONE_EFFECT_RATIO * floor
        why = f"`none` with the effect {row['effect_m'] / floor:.1f} × F_w"
    else:
        eq = EQUIVALENT.get(row["case"], {})
        bad = [e for e in named if e not in eq]
        ok = not bad and after <= FLOOR_RATIO * floor
        why = (f"named {bad}: not in this world" if bad else
               f"named an equivalent effect; A/F_w = {after / floor:.2f}")  # fmt: skip
    return {"judged": "OK" if ok else judged, "ok": bool(ok), "why": why}


def run_case(case: str, n: int, seed: int, keep: Path | None) -> dict[str, Any]:
    """Draw, write, diagnose and judge one case."""
    c0 = time.process_time()
    camp = draw_campaign(case, n, seed)
    draw_cpu = time.process_time() - c0
    with tempfile.TemporaryDirectory() as tmp:
        d = keep if keep is not None else Path(tmp)
        d.mkdir(parents=True, exist_ok=True)
        log, out = d / f"{case}.csv", d / f"{case}.json"
        write_log(camp, case, log)
        if out.exists():
            out.unlink()
        rep, err, cpu = diagnose(log, out, seed)
    row = judge(case, camp, rep, err)
    row.update({"draw_cpu_s": draw_cpu, "diagnosis_cpu_s": cpu})
    return row


def format_rows(rows: list[dict[str, Any]]) -> str:
    head = (f"{'case':14s}{'verdict':>16s}{'where':>13s}{'E/Fw':>6s}{'Fw':>7s}{'B':>7s}"
            f"{'A':>7s}{'A/Fw':>6s}  judged  law or proposal")  # fmt: skip
    out = [head]
    for r in rows:
        if r["verdict"] == "traceback":
            out.append(f"{r['case']:14s}{'traceback':>16s}  NO  {r['why']}")
            continue
        law = "; ".join(f"{k}: {v}" for k, v in r["laws"].items())
        if r["proposal"]:
            law = f"[{r['proposal_phase']}] {r['proposal']}"
        out.append(
            f"{r['case']:14s}{r['verdict']:>16s}{r['where']:>13s}"
            f"{r['effect_m'] / r['world_floor_m']:6.1f}{r['world_floor_m']:7.3f}"
            f"{r['baseline_m']:7.3f}{r['after_robust_m']:7.3f}{r['after_over_floor']:6.2f}"
            f"  {r['judged']:7s} {law}"
        )
    return "\n".join(out)


def markdown_rows(rows: list[dict[str, Any]]) -> str:
    """The rows as docs/gap_laws.md's table (every number in code quotes)."""
    out = [
        "| case | verdict | where | E / F_w | F_w [m] | F [m] | B [m] | A / F_w | law or proposal "
        "| judged |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["verdict"] == "traceback":
            out.append(f"| `{r['case']}` | traceback | | | | | | | | NOT OK |")
            continue
        law = "; ".join(f"{k}: {v}" for k, v in r["laws"].items())
        if r["verdict"] == "unknown":
            law = "partial: " + (", ".join(r["partial"]) or "none")
        if r["proposal"]:
            law += (
                f"; proposed ({r['proposal_phase']}, A / F_w "
                f"{r['proposal_after_m'] / r['world_floor_m']:.2f}): {r['proposal']}"
            )
        out.append(
            f"| `{r['case']}` | {r['verdict']} | {r['where']} "
            f"| `{r['effect_m'] / r['world_floor_m']:.1f}` | `{r['world_floor_m']:.3f}` "
            f"| `{r['tool_floor_m']:.3f}` "
            f"| `{r['baseline_m']:.3f}` | `{r['after_over_floor']:.2f}` "
            f"| {'`' + law + '`' if law else ''} | {r['judged']} |"
        )
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", choices=sorted(EFFECTS), default=list(EFFECTS))
    ap.add_argument("--n", type=int, default=200, help="throws per campaign")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, help="write the rows as JSON")
    ap.add_argument("--keep", type=Path, help="keep each case's log and report in this folder")
    ap.add_argument("--markdown", action="store_true", help="also print docs/gap_laws.md's table")
    args = ap.parse_args()
    rows = []
    for case in args.cases:
        rows.append(run_case(case, args.n, args.seed, args.keep))
        print(format_rows(rows[-1:]).splitlines()[-1], flush=True)
    print(format_rows(rows))
    print(f"{sum(r['ok'] for r in rows)}/{len(rows)} rows OK")
    if args.markdown:
        print(markdown_rows(rows))
    if args.json:
        args.json.write_text(json.dumps({"n": args.n, "seed": args.seed, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
