"""What a bounce in the scene world scatters between repeats, and which slide law its rest
points follow (docs/gap_scene.md, "Repeats"):

    python -m cell.gap.scene_repeats s:bounce-slide s:bounce-roll [--n 80] [--jitter 0.001]
        [--jitters 0.0001,0.01] [--json FILE]

For a scene case with a bounce, its plan (n throws, each configuration twice) is thrown
with the floor's contact and without it (the same air, the same launch jitter). Printed:
the repeats' scatter (sqrt of the pooled within-configuration variance, 2-D) of the rest
points and of the crossings of the landing plane, and the RMS of the slide (rest −
crossing) left by each slide law fitted to it by least squares on the crossing's velocity:
τ · v_h (rolling), 1/μ · v_h|v_h|/2g (friction), both, a hop term v_h|v_z|/g beside the
friction, the impact law (v_h − μ|v_z|)₊² / 2μg (`impact`, 1/μ `inv_mu_imp`: the
impact's friction impulse off v_h, then the slide), the drop law (`drop`: the fall from
the plane to the floor, then the impact law there; 1/μ and the floor's depth fitted,
`cell.sim.slide_fit.drop_fit`), the roll law (`roll`: the fall, then a ball brought to
rolling by the impact and braked by its rolling resistance, other shapes left at the
crossing; 1/μ_r fitted, the fall from the campaign's plane to the floor as the model's
roll law takes it from the log, `cell.sim.slide_fit.roll_fit`), and 1/μ or τ per
object. A law that leaves about the rest points' repeat scatter is all a perfect account
could do; a law that leaves much more is missing something.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from cell.gap.world_scene import JITTER_REL, LAND_Z_M, draw_plan, repeat_var, throw_plan
from cell.outfile import write_whole
from cell.sim.slide_fit import G, drop_fit, extents_and_balls, impact_fit, roll_fit

__all__ = ["slide_laws", "main"]


def _fit(d: np.ndarray, cols: list[np.ndarray]) -> tuple[float, np.ndarray]:
    """RMS 2-D residual [m] of the slides d (n, 2) after least squares on the columns
    (each (n, 2), one coefficient each), and the coefficients."""
    x = np.stack([c.reshape(-1) for c in cols], axis=1)
    coef, *_ = np.linalg.lstsq(x, d.reshape(-1), rcond=None)
    r = (d.reshape(-1) - x @ coef).reshape(-1, 2)
    return float(np.sqrt(np.mean(np.sum(r * r, axis=1)))), coef


def slide_laws(name: str, n: int = 80, seed: int = 7, jitter_rel: float = JITTER_REL
               ) -> tuple[dict[str, float], dict[str, float], float]:  # fmt: skip
    """The case's repeat scatter [m] (rest points, crossings) and each slide law's RMS
    residual [m] (see the module docstring); 1/μ per object [-]; the impact law's 1/μ [-]."""
    from cell.gap.check_scene import SCENE_CASES

    effects, _, _, _, opts = SCENE_CASES[name]
    if not any(e["kind"] == "bounce" for e in effects):
        raise ValueError(f"{name}: not a case with a bounce")
    plan = draw_plan(n, np.random.default_rng(seed), repeats=2, objects=opts.get("objects"))
    air = [e for e in effects if e["kind"] not in ("bounce", "tracker")]
    rest, _, _ = throw_plan(plan, [e for e in effects if e["kind"] != "tracker"], seed, jitter_rel)
    cross, _, vc = throw_plan(plan, air, seed, jitter_rel)
    ok = np.all(np.isfinite(rest), axis=1) & np.all(np.isfinite(cross), axis=1)
    d, v = (rest - cross)[ok], vc[ok]
    vh = v[:, :2]
    speed = np.linalg.norm(vh, axis=1)
    tau, fric = vh, vh * (speed / (2 * G))[:, None]
    hop = vh * (np.abs(v[:, 2]) / G)[:, None]
    objs = np.array([p.object_id for p in plan])[ok]
    names = sorted(set(objs))
    per = [objs == o for o in names]
    per_mu = _fit(d, [fric * m[:, None] for m in per])
    inv_mu_imp, imp_rms = impact_fit(d, v)
    sizes, balls = extents_and_balls(objs)
    return (
        {
            "repeat_sd_rest_m": float(np.sqrt(repeat_var(plan, rest, ok))),
            "repeat_sd_crossing_m": float(np.sqrt(repeat_var(plan, cross, ok))),
            "slide_rms_m": float(np.sqrt(np.mean(np.sum(d * d, axis=1)))),
            "tau": _fit(d, [tau])[0],
            "inv_mu": _fit(d, [fric])[0],
            "tau+inv_mu": _fit(d, [tau, fric])[0],
            "inv_mu+hop": _fit(d, [fric, hop])[0],
            "impact": imp_rms,
            "drop": drop_fit(d, v, sizes)[2],
            "roll": roll_fit(d, v, sizes, balls, LAND_Z_M)[2],
            "inv_mu per object": per_mu[0],
            "tau per object": _fit(d, [tau * m[:, None] for m in per])[0],
        },
        dict(zip(names, (float(c) for c in per_mu[1]), strict=True)),
        inv_mu_imp,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cases", nargs="+", help="scene cases with a bounce (s:bounce-slide, ...)")
    ap.add_argument("--n", type=int, default=80, help="throws (each configuration twice)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--jitter", type=float, default=JITTER_REL, help="stroke jitter, relative sd")
    ap.add_argument("--jitters", default="", help="more jitters for the repeats alone (a,b)")
    ap.add_argument("--json", type=Path, default=None, help="write every figure to FILE")
    args = ap.parse_args(argv)
    try:
        more = [float(j) for j in args.jitters.split(",") if j.strip()]
    except ValueError:
        more = [-1.0]
    from cell.gap.check_scene import SCENE_CASES

    bad = [c for c in args.cases if c not in SCENE_CASES]
    if bad or not 4 <= args.n <= 2000 or not all(0.0 <= j <= 0.1 for j in [args.jitter, *more]):
        print(f"cell: error: unknown case(s) {bad}, or --n outside 4–2000, or --jitter "
              f"outside 0–0.1; cases: {', '.join(SCENE_CASES)}", file=sys.stderr)  # fmt: skip
        return 2
    doc: dict = {"n": args.n, "seed": args.seed, "jitter": args.jitter, "cases": {}}
    for name in args.cases:
        try:
            r, mu, imp = slide_laws(name, args.n, args.seed, args.jitter)
            runs = {f"{j:g}": slide_laws(name, args.n, args.seed, j)[0] for j in more}
        except ValueError as e:
            print(f"cell: error: {e}", file=sys.stderr)
            return 2
        print(f"{name}: " + "; ".join(f"{k.removesuffix('_m')} {1000 * v:.0f} mm"
                                      for k, v in r.items()))  # fmt: skip
        print("  1/mu per object: " + ", ".join(f"{k} {v:.3f}" for k, v in mu.items()))
        print(f"  impact law: 1/mu {imp:.3f}")
        for j, rj in runs.items():
            print(f"  jitter {j}: rest {1000 * rj['repeat_sd_rest_m']:.0f} mm, crossing "
                  f"{1000 * rj['repeat_sd_crossing_m']:.1f} mm")  # fmt: skip
        doc["cases"][name] = {**r, "inv_mu_per_object": mu, "inv_mu_imp": imp, "jitters": runs}
    if args.json is not None:
        text = json.dumps(doc, indent=1) + "\n"
        write_whole(args.json, lambda p: p.write_text(text))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
