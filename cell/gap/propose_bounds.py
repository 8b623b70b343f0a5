"""The bounds of the proposal's terms (`cell.gap.propose`): a term whose size no throw of
a cell can have is not proposed.

The proposal's terms are the landing's first-order change in a coefficient θ about θ = 0
(each column a finite difference at a small θ). A term's size on a throw is what it
claims that throw had: θ·c for a launch term of covariate c (1, stroke, mass, width,
order, session, one object), the acceleration at the throw's launch speed for a flight
term, the term's own quantity for a landing term. A term beyond its kind's bound on any
throw of the log is left out and the law fitted again without it (`implausible_left_out`
lists it, its coefficient, its largest size and the bound), until the law's terms are
all within their bounds, or there is none (`law` None, `why` saying so).

| kind | size on a throw | bound | why |
|---|---|---|---|
| speed error [share] | \\|θ·c\\| | 0.5 | the landing distance goes as the launch speed squared: a speed (1 + θ)·v moves it by 2θ + θ² of itself, and the first-order term misses θ/2 of its own step: a quarter at θ = 0.5 (a share of −1 is no launch at all) |
| elevation, azimuth error [rad] | \\|θ·c\\| | 0.5 rad | a launch turned by Δ moves its landing along the chord 2 sin(Δ/2) where the first-order term moves it along the arc Δ, a direction off by Δ/2: a quarter of a radian at 0.5 rad (29°); the physical limit, a throw turned past the vertical or backwards, is ±π/2 |
| force x, y; along, across v; up; lift across v | \\|θ\\|·\\|v\\|^p at the launch speed (p = 0, 1, 2 by the unit: m/s², 1/s, 1/m) | g/3 + 3·k\\|v\\|² | a third of the object's weight: a force a against gravity stretches the time of flight by (1 − a/g)^−½ − 1 = a/2g + 3a²/8g² + …, whose second-order part is a quarter of the first at a = g/3 (no air of a cell pushes a thrown object of 20-500 g that hard: a 10 m/s wind's drag on a 35 g cube is 1.7 m/s²); plus three times the drag the model gives it there (k = ½ρC_dA/m: the vocabulary's drag factor is plausible up to 4, so a drag three times the model's more is the air's), for light objects whose drag is large |
| wind x, y × session [m/s] | \\|θ\\| | 10 m/s (`WIND_MAX_MPS`) | the change of the air between two sessions (`cell.gap.propose_sessions`): 10 m/s is a gale, no cell's air |
| lift coefficient C_L [-] | \\|θ\\| | 1.5 (`LIFT_CL_MAX`) | no spin gives a lift coefficient over about 0.6 |
| landing shift [s] (∝ v_h) | \\|θ\\| | 1 s | the vocabulary's rolling bounce rolls on at most 1 s per m/s (`BounceRolling`'s bound); a tracker a second late is no tracker |
| landing shift [s²/m] (∝ \\|v_h\\| v_h) | \\|θ\\| | 1 / (2 · 0.05 · g) = 1.02 s²/m | a slide v_h² / (2 μ g) with μ at least 0.05 (ice on steel is 0.03, no surface of a cell) |
| landing shift x, y [m] | \\|θ\\| | 1 m | every landing logged a metre off is a frame's mistake (`cell.gap.track_frame` names it), not a law of the landings |
| landing radial distortion [1/m²] | \\|θ\\|·r² at the landing | 0.25 | an uncorrected wide-angle lens moves a point at the image's edge by some 10-20 % of its distance from the centre; a quarter is beyond any camera a cell's landings are read with |
| landing plane height [m] (× 1) | \\|θ\\| | 0.25 m (`PLANE_MAX_M`) | the tool's own worlds land on planes at 0 and 0.25 m: a surface further off its logged height is no cell's |
| landing plane height [m] × x, y | \\|θ\\| [m/m] | 0.25 (14°) | a floor, a table or a bin's bottom tilted by more than 1 in 4 is one things slide down, not one they land on (the heights it gives grow with the distance from the world's origin, so they are not bounded) |

The law whose misses flag outliers (`cell.gap.run`, `extended` False) is not held to these
bounds (but for the landing plane's constant, as before them): it models the misses'
smooth part, not a quantity a person would test, and the verdict's passes hang on it.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

import numpy as np

from cell.gap.propose_terms import LIFT_CL_MAX

__all__ = [
    "BOUNDS",
    "G",
    "PLANE_MAX_M",
    "beyond",
    "size_of",
    "why_none",
    "within_bounds",
    "written",
]

G = 9.81  # [m/s²]
SPEED_SHARE_MAX = 0.5  # [-] a speed error's share on any throw
ANGLE_MAX_RAD = 0.5  # [rad] a launch's elevation or azimuth error on any throw
FORCE_G_SHARE = 1.0 / 3.0  # a flight force up to this share of g (the weight) ...
DRAG_MORE = 3.0  # ... plus DRAG_MORE times the model's drag at the launch speed
SHIFT_TIME_MAX_S = 1.0  # [s] a landing shift ∝ v_h
MU_MIN = 0.05  # the least friction coefficient of a slide ∝ |v_h| v_h
SHIFT_MAX_M = 1.0  # [m] every landing moved alike
# [m/s] a wind's change between two sessions (`cell.gap.propose_sessions`): a gale of
# 10 m/s inside a cell is no cell's air
WIND_MAX_MPS = 10.0
RADIAL_MAX = 0.25  # [-] a camera's radial distortion k r² at any landing
# [m] the largest height a landing plane's term may give: the tool's own worlds land on
# planes at 0 and 0.25 m (`cell.gap.world`), so a throw logged onto the other one is
# 0.25 m off; a surface further off its logged height than that is no cell's
PLANE_MAX_M = 0.25

# the term's name before " = " -> its kind: (what its size is, the bound)
BOUNDS: dict[str, tuple[str, float]] = {
    "speed error [share]": ("share", SPEED_SHARE_MAX),
    "elevation error [rad]": ("share", ANGLE_MAX_RAD),
    "azimuth error [rad]": ("share", ANGLE_MAX_RAD),
    "force x [m/s²]": ("accel0", 1.0),
    "force y [m/s²]": ("accel0", 1.0),
    "wind x [m/s]": ("coef", WIND_MAX_MPS),
    "wind y [m/s]": ("coef", WIND_MAX_MPS),
    "force along v [1/s]": ("accel1", 1.0),
    "force across v [1/s]": ("accel1", 1.0),
    "force along v [1/m]": ("accel2", 1.0),
    "force across v [1/m]": ("accel2", 1.0),
    "force up [1/m]": ("accel2", 1.0),
    "lift across v [1/m]": ("accel2", 1.0),
    "lift coefficient C_L [-]": ("coef", LIFT_CL_MAX),
    "landing shift [s]": ("coef", SHIFT_TIME_MAX_S),
    "landing shift [s²/m]": ("coef", 1.0 / (2.0 * MU_MIN * G)),
    "landing shift x [m]": ("coef", SHIFT_MAX_M),
    "landing shift y [m]": ("coef", SHIFT_MAX_M),
    "landing plane height [m]": ("coef", PLANE_MAX_M),
    "landing radial distortion [1/m²]": ("share", RADIAL_MAX),
}
# a landing plane's slope [m/m] (the plane height's term in x or y)
SLOPE_MAX = 0.25

_OBJECT = re.compile(r" · \[object = (.+)\]$")


def size_of(term: str, k: float, ctx: dict[str, Any], keep: np.ndarray) -> tuple[float, float]:
    """A term's largest size over the throws in `keep` and its bound there, as (size,
    bound) in the term's own unit (for a flight force, the size is the largest ratio of its
    acceleration to the bound at each throw's launch speed, and the bound 1).

    `ctx`: "cov" (a covariate's name -> its values over the throws: stroke_m, mass_kg,
    size_x_m, order, [session = s]), "object" (each
    throw's object id), "speed" (|launch velocity| [m/s]) and "drag_k" (k [1/m])."""
    head, _, tail = term.partition(" = k")
    what, bound = BOUNDS[head.strip()]
    on = np.asarray(keep, bool).copy()
    m = _OBJECT.search(tail)
    if m:  # a term of one object: its throws only
        on &= np.asarray(ctx["object"]) == m.group(1)
        tail = tail[: m.start()]
    if not on.any():
        return 0.0, bound
    if what == "coef":
        return abs(k), SLOPE_MAX if tail.strip() in ("· x_m", "· y_m") else bound
    if what == "share":
        c = tail.split(",")[0].removeprefix(" · ").strip()
        vals = np.ones(on.size) if not c else np.asarray(ctx["cov"][c], float)
        return float(np.max(np.abs(k * vals[on]))), bound
    p = int(what[-1])
    v = np.asarray(ctx["speed"], float)[on]
    room = FORCE_G_SHARE * G + DRAG_MORE * np.asarray(ctx["drag_k"], float)[on] * v**2
    return float(np.max(abs(k) * v**p / room)), 1.0


def beyond(terms: list[dict[str, Any]], ctx: dict[str, Any], keep: np.ndarray
           ) -> list[dict[str, Any]]:  # fmt: skip
    """The fitted terms (each with "term" and "k") beyond their kind's bound on some throw
    in `keep`: each as {"term", "k", "size", "bound"}."""
    out = []
    for t in terms:
        size, bound = size_of(t["term"], t["k"], ctx, keep)
        if size > bound:
            out.append({"term": t["term"], "k": float(t["k"]), "size": size, "bound": bound})
    return out


def written(term: str, k: float) -> str:
    """A term with its coefficient: "speed error [share] = -0.05 · order"."""
    return f"{term.split(' = ')[0]} = {k:.4g}{term.split(' = k')[1]}"


def within_bounds(
    fit: Callable[[list[dict[str, Any]], np.ndarray], tuple[dict[str, Any], np.ndarray]],
    terms: list[dict[str, Any]],
    a_all: np.ndarray,
    keep: np.ndarray,
    ctx: dict[str, Any],
    out: dict[str, Any],
    miss: np.ndarray,
) -> tuple[dict[str, Any], np.ndarray, list[dict[str, Any]], np.ndarray]:
    """The sparse law `out` (its misses `miss`) fitted again (`fit`: terms, their columns
    -> the law, its misses) without its term furthest beyond its bound at each step, until
    every term is within its bound or none is left: (the law, its misses, the terms and
    columns left). The terms left out are listed in `implausible_left_out`."""
    left: list[dict[str, Any]] = []
    while True:
        bad = beyond(out["terms"], ctx, keep)
        if not bad:
            break
        worst = max(bad, key=lambda b: b["size"] / b["bound"])
        left.append(worst)
        on = [t["term"] != worst["term"] for t in terms]
        terms, a_all = [t for t, o in zip(terms, on, strict=True) if o], a_all[:, on]
        out, miss = fit(terms, a_all)
    if left:
        out["implausible_left_out"] = left
    return out, miss, terms, a_all


def why_none(left: list[dict[str, Any]]) -> str:
    """Why no law is proposed where the terms left out (`within_bounds`) were the law's."""
    return (
        "no law within the terms' bounds: the sparse law's terms were beyond them ("
        + "; ".join(f"{written(b['term'], b['k'])}: {b['size']:.3g} against {b['bound']:.3g}"
                    for b in left)
        + ", `cell.gap.propose_bounds`)"
    )  # fmt: skip
