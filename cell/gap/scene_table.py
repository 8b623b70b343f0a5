"""The Markdown table docs/gap_scene.md shows, made from the JSON that
`cell gap check --worlds scene --json FILE` writes (one row per case).

Parameters found are printed to 3 significant figures (a per-object law's value for each
object by the object's name); a world's parameter in brackets
(the case's setting, or a bounce's as measured in the world, `world_truth`); A / world
floor to 2 decimals and the floor F in mm, both on the rows A was counted on (the rows the
tool flags left out; with F0, the effect-free throws' part, where the effect's own repeat
scatter raises F by 1 mm or more, and F on every row where the flagged rows move it by
1 mm or more); a proposal by its number of terms and its first two terms."""

from __future__ import annotations

from typing import Any

__all__ = ["scene_table", "scene_summary", "case_truths", "flat_params"]

HEAD = (
    "| case | truth | verdict | phases | parameters found (truth) | A / world floor | passes |\n"
    "|---|---|---|---|---|---|---|"
)


def case_truths(row: dict[str, Any]) -> dict[str, float]:
    """The world's parameters of a case as `effect.param` -> value: the case's setting
    (`cell.gap.check_scene.SCENE_CASES`) or, for a bounce, the slide measured in the world."""
    from cell.gap.check_scene import SCENE_CASES

    _, _, _, expect, _ = SCENE_CASES[row["case"]]
    out: dict[str, float] = {}
    for eff, params in expect.items():
        for k, v in params.items():
            if isinstance(v, (int, float)):
                out[f"{eff}.{k}"] = float(v)
    for k, v in (row.get("world_truth") or {}).items():
        out[f"bounce.{k}"] = float(v)
    return out


def flat_params(params: dict[str, Any]) -> dict[str, float]:
    """An effect's parameters with a per-object law's values one by one (`per_object`:
    {object: value} becomes object: value)."""
    out: dict[str, float] = {}
    for k, v in params.items():
        out.update(v if isinstance(v, dict) else {k: v})
    return out


def _params(row: dict[str, Any]) -> str:
    truths = case_truths(row)
    parts = []
    for eff, params in row["params"].items():
        items = []
        for k, v in flat_params(params).items():
            key = f"{eff}.{k}"
            t = f" ({truths[key]:.3g})" if key in truths else ""
            items.append(f"{key} {v:.3g}{t}")
        law = row["laws"].get(eff)
        parts.append("; ".join(items) + (f" — {law}" if law else ""))
    text = "; ".join(parts) or "—"
    if row.get("proposal"):
        terms = row["proposal"].split(" + ")
        first = " + ".join(terms[:2]).replace("|", "\\|")  # a cell of the table
        more = " + …" if len(terms) > 2 else ""
        text += f" proposal ({len(terms)} term{'s' if len(terms) > 1 else ''}): {first}{more}"
    return text


def _floor(row: dict[str, Any]) -> str:
    """F in mm on the rows A was counted on (the flagged rows left out), and F0 (the
    effect-free throws' alone) where the effect's own repeat scatter raises it by a
    millimetre or more; F on every row beside it where the flagged rows move it by as
    much."""
    every = 1000 * row["world_floor_m"]
    f = 1000 * row.get("world_floor_kept_m", row["world_floor_m"])
    f0 = 1000 * row.get("world_floor0_kept_m", row.get("world_floor0_m", float("nan")))
    text = f"F {f:.0f} mm" + (f", F0 {f0:.0f}" if f - f0 >= 1.0 else "")
    return text + (f"; {every:.0f} with the flagged rows" if abs(every - f) >= 1.0 else "")


def scene_row(row: dict[str, Any]) -> str:
    phases = "; ".join(f"{k}: {v}" for k, v in row["phases"].items()) or "—"
    cells = (
        row["case"],
        row["truth"],
        row["verdict"],
        phases,
        _params(row),
        f"{row['after_over_floor']:.2f} ({_floor(row)})",
        "yes" if row["passes"] else "no",
    )
    return "| " + " | ".join(cells) + " |"


def scene_summary(doc: dict[str, Any]) -> str:
    ratio = f"{doc['criteria']['floor_ratio']:g}"
    return (
        f"{doc['passes']}/{doc['total']} pass; diagonal {doc['diagonal']}, phase "
        f"{doc['phase_ok']}, parameters {doc['params_ok']}, A ≤ {ratio} F {doc['floor_ok']}"
    )


def scene_table(doc: dict[str, Any]) -> str:
    """The table and its summary line, as docs/gap_scene.md shows them."""
    rows = "\n".join(scene_row(r) for r in doc["campaigns"])
    return f"{HEAD}\n{rows}\n\n{scene_summary(doc)}\n"
