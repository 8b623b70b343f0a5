"""`scene_reach_err_pct`: does the planner's model of the scene hold over the envelope?

Throws of objects the calibration never threw (ad-hoc primitives of every
shape, 20–250 g at plausible densities, 25–90 mm) are made in the PyBullet scene
with the end-effector held at random release states over the whole envelope
(strokes from the end-effector's shortest up to what the grip holds the item at,
elevations 0–65°, release heights 0.5–0.9 m, any azimuth). Each is predicted by
the planner's model: the scene's parameter file, the object taken through
`ModelParams.model_object` (the mass rule). The figure is the RMS over throws of
(model reach − scene reach) / scene reach, reach being the horizontal distance
from the release point to the crossing of the landing plane.

Strokes are drawn up to what the grip holds; the figure counts the throws inside
the cell's throw envelope: launched (by the model) at
`cell.orchestrator.LAUNCH_SPEED_MIN_MPS` or faster, or flat enough
(`cell.orchestrator.clean_launch`; the planner throws no other: a slow steep launch
falls back onto the pads). The throws drawn beyond it are reported apart
(`scene_reach_slow_*`), so the edge stays in view.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["run", "scene_reach_errors", "breakdown", "main"]

LAND_Z_M = 0.1  # [m] the landing plane (a typical rim)


def scene_reach_errors(
    n: int, seed: int = 0, params_path: str | None = None
) -> tuple[np.ndarray, list[dict]]:
    """Relative reach errors (model − scene) / scene of n throws, and their settings
    (each row's `in_envelope`: its launch is one the cell makes, `clean_launch`; see the
    module).

    Args:
        n: number of throws.
        seed: the draw (items and settings come from the random stream [seed, 0x5C], which
            the calibration's ad-hoc campaign, stream 0xCA1, never draws from).
        params_path: the parameter file to predict with (default: the shipped scene file).
    """
    from cell.arm.grip_limits import grip_stroke_limit
    from cell.arm.launch import clean_launch
    from cell.endeffector.factory import make_end_effector
    from cell.errors import CellError
    from cell.jobgen import _adhoc_item
    from cell.log.table import ThrowTable
    from cell.model.objects import ObjectParams
    from cell.model.throw import launch_state, predict_landing
    from cell.params import load_params, scene_params_path
    from cell.sim import CellScene
    from cell.workflows.campaign import throw_once

    params = load_params(params_path or scene_params_path())
    rng = np.random.default_rng([seed, 0x5C])
    errs: list[float] = []
    rows: list[dict] = []
    with CellScene(robot=None) as sc:
        ee = make_end_effector("pybullet", plant=sc)
        k = 0
        while len(errs) < n and k < 4 * n:
            k += 1
            d = _adhoc_item(rng)
            obj = ObjectParams(
                shape=d["shape"], mass=d["mass_kg"], size=tuple(d["size_m"]), name=""
            )
            try:
                s_max = grip_stroke_limit(params, obj)
            except CellError:
                continue  # the cell refuses it: not part of its envelope
            stroke = float(rng.uniform(params.ee.stroke_min, s_max))
            z0 = float(rng.uniform(0.5, 0.9))
            elevation = math.radians(float(rng.uniform(0.0, 65.0)))
            setting = {
                "stroke": stroke,
                "position": (0.0, 0.0, z0),
                "elevation": elevation,
                "azimuth": float(rng.uniform(-math.pi, math.pi)),
            }
            try:
                rec = throw_once(sc, ee, obj, land_z=LAND_Z_M, **setting)  # type: ignore[arg-type]
            except CellError:
                continue
            table = ThrowTable.from_records([rec])
            batch = table.to_batch(objects={obj.shape: params.model_object(obj)})
            pred = predict_landing(batch, params.ee, strict=False)
            speed = float(np.linalg.norm(launch_state(batch, params.ee)[1][0]))
            p0 = np.zeros(2)  # the release point's (x, y)
            r_scene = float(np.hypot(*(table.landed[0] - p0)))
            r_model = float(np.hypot(pred.x[0] - p0[0], pred.y[0] - p0[1]))
            if not math.isfinite(r_model) or r_scene < 0.2:
                continue
            errs.append((r_model - r_scene) / r_scene)
            rows.append(
                {
                    **d,
                    **setting,
                    "rel_err": errs[-1],
                    "in_envelope": clean_launch(speed, elevation),
                }
            )
    return np.array(errs), rows


_BINS: dict[str, tuple[str, float, list[float]]] = {
    # name: (row key, scale to the unit in the name, bin edges)
    "mass_g": ("mass_kg", 1000.0, [20, 60, 90, 120, 160, 200, 251]),
    "width_mm": ("width", 1000.0, [25, 40, 55, 70, 80, 91]),
    "stroke_mm": ("stroke", 1000.0, [30, 50, 70, 90, 111]),
    "elevation_deg": ("elevation", 180.0 / math.pi, [0, 15, 30, 45, 66]),
}


def _stats(e: np.ndarray) -> dict[str, float]:
    return {
        "n": int(e.size),
        "rms_pct": float(100 * np.sqrt(np.mean(e**2))) if e.size else float("nan"),
        "bias_pct": float(100 * np.mean(e)) if e.size else float("nan"),
    }


def _by_envelope(errs: np.ndarray, rows: list[dict]) -> tuple[np.ndarray, list[dict], np.ndarray]:
    """(the errors and rows of the throws inside the throw envelope, the errors of those
    beyond it)."""
    inside = np.array([bool(r["in_envelope"]) for r in rows], dtype=bool)
    kept = [r for r, k in zip(rows, inside, strict=True) if k]
    return errs[inside], kept, errs[~inside]


def breakdown(errs: np.ndarray, rows: list[dict]) -> dict[str, object]:
    """The relative reach errors by mass, grip width, stroke, elevation and shape bins,
    of the throws inside the throw envelope; those beyond it as `slow`."""
    errs, rows, slow = _by_envelope(errs, rows)
    out: dict[str, object] = {"all": _stats(errs), "slow": _stats(slow)}
    for name, (key, scale, edges) in _BINS.items():
        x = np.array(
            [(r["size_m"][0] if key == "width" else r[key]) * scale for r in rows], dtype=float
        )
        out[name] = {
            f"{lo:g}-{hi:g}": _stats(errs[(x >= lo) & (x < hi)])
            for lo, hi in zip(edges[:-1], edges[1:], strict=True)
        }
    shapes = np.array([r["shape"] for r in rows])
    out["shape"] = {s: _stats(errs[shapes == s]) for s in sorted(set(shapes))}
    return out


def main(argv: list[str] | None = None) -> int:
    """`python -m cell.bench.bench_scene_reach [--n N] [--seed S] [--params FILE] [--json OUT]`:
    the figure and its breakdown for one draw and parameter file."""
    import argparse
    import json

    ap = argparse.ArgumentParser(prog="python -m cell.bench.bench_scene_reach")
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--params", default=None, help="parameter file (the shipped scene file)")
    ap.add_argument("--json", default=None, help="write the breakdown here")
    args = ap.parse_args(argv)
    e, rows = scene_reach_errors(args.n, seed=args.seed, params_path=args.params)
    doc = {
        "n": args.n,
        "seed": args.seed,
        "params": args.params or "robots/cell_scene/ee_params.yaml",
        **breakdown(e, rows),
    }
    text = json.dumps(doc, indent=1)
    if args.json:
        with open(args.json, "w") as fh:
            fh.write(text + "\n")
    print(text)
    return 0


def run(quick: bool) -> dict[str, float]:
    """scene_reach_err_pct (RMS), its bias and 95th percentile over the throws of n
    inside the throw envelope; the RMS of those drawn beyond it (NaN when none were)."""
    e, _, slow = _by_envelope(*scene_reach_errors(12 if quick else 60))
    return {
        "scene_reach_throws": float(e.size),
        "scene_reach_err_pct": float(100 * np.sqrt(np.mean(e**2))),
        "scene_reach_bias_pct": float(100 * np.mean(e)),
        "scene_reach_err_p95_pct": float(100 * np.percentile(np.abs(e), 95)),
        "scene_reach_slow_throws": float(slow.size),
        "scene_reach_slow_err_pct": (
            float(100 * np.sqrt(np.mean(slow**2))) if slow.size else math.nan
        ),
    }


if __name__ == "__main__":
    raise SystemExit(main())
