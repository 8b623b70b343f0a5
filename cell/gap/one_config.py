"""A log of one configuration: effects it cannot tell apart, and the verdict it allows.

An effect moves a throw's landing through what the model reads of that throw. Where those
readings are one value across the diagnosed throws, every effect moves every landing
alike, and the landings cannot say which effect it was. Two scopes are checked:

* the launch (`LAUNCH_COVARIATES`): what a launch effect reads (`cell.model.effects_apply`'s
  push: the stroke, the grip width `size_x_m`, the shape (curved or not), the mass, the
  elevation; and the object id, which a per-object law reads). Where these are one value
  and every throw is the end effector's (a stroke logged), every launch effect (band_mass,
  band_damping, shape_stretch, stroke_offset, release_pitch) is one change of one launch
  velocity: the four that change its speed predict alike to the bit, release_pitch nearly
  so. A verdict naming a launch effect is then `unknown`.
* every covariate (`LAUNCH_COVARIATES` and `FLIGHT_COVARIATES`): the rest of what the
  model reads, the size along y and z (drag, spin's radius), the release position (x, y,
  z: the release height, downwash's centre, the tracker's origin), the azimuth and the
  roll, the base velocity, the rotor speed and the landing plane's height. Where these are
  one value too, the throws are one throw repeated: every effect is one shift of the
  landing, and a verdict naming any effect is `unknown`.

Values are one where they agree to 1e-9 of their unit (`cell.gap.laws.distinct`); the
stroke and the elevation are one too where, the launch's other covariates being one value,
their spread moves the nominal model's landings by no more than the noise floor (RMS, from
each throw's stroke and elevation to their medians; `spread_moves_m`): a stroke read with
a jitter of an encoder's count about one setting is one stroke, whose landings cannot tell
the launch effects apart any better. A
`none` verdict stands (there is no shift to explain), and so does an `unknown` one. The report's `one_configuration`
says why in a sentence, with the mean shift of the landings (along and across the throw)
and the effects that explain it alike (held-out RMSE within `VERDICT_RATIO` of the floor,
neither refused, at a bound nor implausible), which become the verdict's partial effects.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from cell.gap.laws import distinct
from cell.gap.problem import GapProblem
from cell.gap.select import VERDICT_RATIO
from cell.model.effects import EFFECTS

__all__ = [
    "LAUNCH_COVARIATES",
    "FLIGHT_COVARIATES",
    "SPREAD_COVARIATES",
    "one_scope",
    "one_configuration",
    "spread_moves_m",
]

LAUNCH_COVARIATES = ("object_id", "shape", "mass_kg", "size_x_m", "stroke_m", "elevation_rad")
FLIGHT_COVARIATES = (
    "size_y_m", "size_z_m", "x_m", "y_m", "z_m", "azimuth_rad", "roll_rad",
    "vx_mps", "vy_mps", "vz_mps", "rotor_rpm", "land_z_m",
)  # fmt: skip


def _columns(prob: GapProblem) -> dict[str, np.ndarray]:
    """Each covariate's value per throw, as the model reads it (the batch)."""
    b = prob.batch
    return {
        "object_id": prob.groups.astype(float),
        "shape": b.shape.astype(float),
        "mass_kg": b.mass,
        "size_x_m": b.size[:, 0],
        "stroke_m": b.stroke,
        "elevation_rad": b.elevation,
        "size_y_m": b.size[:, 1],
        "size_z_m": b.size[:, 2],
        "x_m": b.position[:, 0],
        "y_m": b.position[:, 1],
        "z_m": b.position[:, 2],
        "azimuth_rad": b.azimuth,
        "roll_rad": b.roll if b.roll.size == len(prob) else np.zeros(len(prob)),
        "vx_mps": b.base_velocity[:, 0],
        "vy_mps": b.base_velocity[:, 1],
        "vz_mps": b.base_velocity[:, 2],
        "rotor_rpm": np.asarray(prob.rotor_rpm, float),
        "land_z_m": b.land_z,
    }


SPREAD_COVARIATES = ("stroke_m", "elevation_rad")  # one where the landings cannot see their spread


def spread_moves_m(prob: GapProblem) -> float:
    """How far [m] (RMS over the throws) the nominal model's landing moves from each
    throw's logged stroke and elevation to their medians."""
    b = prob.batch
    at = replace(
        b,
        stroke=np.full_like(b.stroke, float(np.median(b.stroke))),
        elevation=np.full_like(b.elevation, float(np.median(b.elevation))),
    )
    idx = np.arange(len(prob))
    d = prob.landing(idx).xy - replace(prob, batch=at).landing(idx).xy
    d = d[np.all(np.isfinite(d), axis=1)]
    return float(np.sqrt(np.mean(np.sum(d * d, axis=1)))) if d.size else float("inf")


def one_scope(prob: GapProblem, floor_m: float | None = None) -> str | None:
    """ "all" where every covariate the model reads is one value across the throws,
    "launch" where only the launch's are, None otherwise (or where a throw was made by
    another launcher: its launch is its own track's). With `floor_m`, a stroke and an
    elevation whose spread moves the model's landings by no more than it
    (`spread_moves_m`) are one value."""
    if not bool(np.all(prob.has_stroke)) or len(prob) < 2:
        return None
    cols = _columns(prob)
    if not all(distinct(cols[c]) <= 1 for c in LAUNCH_COVARIATES if c not in SPREAD_COVARIATES):
        return None
    if not all(distinct(cols[c]) <= 1 for c in SPREAD_COVARIATES) and (
        floor_m is None or not spread_moves_m(prob) <= floor_m
    ):
        return None
    return "all" if all(distinct(cols[c]) <= 1 for c in FLIGHT_COVARIATES) else "launch"


def _alike(report: dict[str, Any], named: list[str]) -> list[str]:
    """The effects that explain the shift alike: the named ones, then every candidate
    whose held-out RMSE is within VERDICT_RATIO of the floor and that is not refused."""
    lim = VERDICT_RATIO * report["noise_floor_m"]
    out = [n for n in named if n in EFFECTS]
    for c in report["candidates"]:
        ok = not (c.get("refused") or c.get("at_bound") or c.get("implausible"))
        if ok and c["heldout_rmse_m"] <= lim and c["effect"] not in out:
            out.append(c["effect"])
    return out


def one_configuration(
    prob: GapProblem, report: dict[str, Any], verdict: list[str], r0: np.ndarray
) -> list[str]:
    """The verdict on a log of one configuration (`one_scope`), and the report's
    `one_configuration` where it applies (added to `report` in place).

    Args:
        prob: the problem diagnosed.
        report: the diagnosis' report (its `candidates` and `noise_floor_m` read).
        verdict: the verdict the rules gave.
        r0: the baseline's miss per throw, observed − predicted (n, 2) [m, W].

    Returns:
        The verdict: ["unknown"] where the scope cannot tell the effects named apart,
        else `verdict`.
    """
    if verdict[0] in ("none", "unknown"):
        return verdict
    scope = one_scope(prob, report["noise_floor_m"])
    if scope is None:
        return verdict
    named = list(verdict)
    if scope == "launch" and not any(EFFECTS[n].phase == "launch" for n in named):
        return verdict
    az = prob.batch.azimuth
    along = r0[:, 0] * np.cos(az) + r0[:, 1] * np.sin(az)
    across = -r0[:, 0] * np.sin(az) + r0[:, 1] * np.cos(az)
    a, c = float(along.mean()), float(across.mean())
    alike = _alike(report, named)
    what = (
        "one throw repeated (one object, stroke, elevation, release pose, base velocity, "
        "rotor speed and landing plane)"
        if scope == "all"
        else "one launch configuration (one object, stroke and elevation)"
    )
    moved = "every effect moves" if scope == "all" else "every launch effect moves"
    cols = _columns(prob)
    spread = [c for c in SPREAD_COVARIATES if distinct(cols[c]) > 1]
    moves = spread_moves_m(prob) if spread else 0.0
    if spread:  # inside the parenthesis `what` closes
        what = what[:-1] + (
            f"; their {' and '.join(c.split('_')[0] + 's' for c in spread)} spread by "
            + " and ".join(
                f"{float(np.ptp(cols[c])):.3g} {'m' if c == 'stroke_m' else 'rad'}" for c in spread
            )
            + f", which moves the model's landings {moves:.4f} m RMS, within the noise floor "
            f"{report['noise_floor_m']:.4f} m)"
        )
    names = ", ".join(alike[:-1]) + (" and " if len(alike) > 1 else "") + alike[-1]
    why = (
        f"the {len(prob)} throws are {what}, so {moved} their landings alike: on average they "
        f"land {abs(a):.4f} m {'beyond' if a >= 0 else 'short of'} the model's landing and "
        f"{abs(c):.4f} m to its {'left' if c >= 0 else 'right'}, a shift "
        + f"{names} {'explain' if len(alike) > 1 else 'explains'} alike"
        + ", and only throws of other "
        + ("configurations" if scope == "all" else "strokes, elevations or objects")
        + " can tell them apart"
    )
    report["one_configuration"] = {
        "scope": scope,
        "covariates": list(LAUNCH_COVARIATES) + (list(FLIGHT_COVARIATES) if scope == "all" else []),
        "would_name": named,
        "shift_along_m": a,
        "shift_across_m": c,
        "explained_alike": alike,
        "spread_moves_m": moves,
        "why": why,
    }
    return ["unknown"]
