"""The diagnosis report: terminal table, strict JSON, HTML with embedded plots."""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from cell.gap.diagnose import Diagnosis
from cell.gap.problem import GapProblem
from cell.outfile import write_whole

__all__ = ["jsonable", "write_json", "format_table", "write_html"]


def jsonable(v: Any) -> Any:
    """Plain JSON values: NumPy to Python, non-finite floats to None."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return [jsonable(x) for x in v.tolist()]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        f = float(v)
        return f if math.isfinite(f) else None
    return v


def write_json(report: dict[str, Any], path: str | Path) -> None:
    """Write the report as strict JSON (no NaN), atomically."""
    text = json.dumps(jsonable(report), indent=2, allow_nan=False)
    write_whole(path, lambda p: p.write_text(text + "\n"))


def _fmt_params(p: dict[str, float]) -> str:
    return " ".join(f"{k}={v:.4g}" for k, v in p.items())


def _ci_items(
    p: dict[str, Any], ci: dict[str, list[float]]
) -> list[tuple[str, float, list[float]]]:
    """Each interval's (name, value, [lo, hi]); a per-object law's fields `o0`, `o1`, …
    named by their objects (`per_object`, in field order) with their shrunk values."""
    per = list((p.get("per_object") or {}).items())
    out = []
    for k, iv in ci.items():
        j = int(k[1:]) if k not in p and k[:1] == "o" and k[1:].isdigit() else -1
        name, val = per[j] if 0 <= j < len(per) else (k, p[k])
        out.append((name, float(val), iv))
    return out


def _tracks_set_aside(tracks: dict[str, Any]) -> list[str]:
    """The table's line on the tracks given that the diagnosis could not use or mended
    (none: no line), each reason with how many tracks it covers, the commonest first; a
    reason whose words differ by track (its figures) by its kind, the words before ':', and
    its first track's."""
    bad, mended = tracks.get("unusable", []), tracks.get("mended", [])
    if not bad and not mended:
        return []
    parts = []
    if bad:
        kinds: dict[str, list[str]] = {}
        for b in bad:
            kinds.setdefault(b["why"].split(":")[0], []).append(b["why"])
        top = sorted(kinds.items(), key=lambda kv: -len(kv[1]))
        shown = "; ".join(
            f"{whys[0]} ({len(whys)})"
            if len(set(whys)) == 1
            else f"{kind} ({len(whys)}, e.g.{whys[0][len(kind) + 1 :]})"
            for kind, whys in top[:3]
        )
        more = f"; {len(top) - 3} other reasons" if len(top) > 3 else ""
        parts.append(f"{len(bad)} set aside, unused: {shown}{more}")
    if mended:
        parts.append(f"{len(mended)} mended (the JSON report's tracks.mended)")
    return [f"tracks           {', '.join(parts)}"]


def _outliers(report: dict[str, Any]) -> list[str]:
    """The table's line on the throws the diagnosis calls outliers (none: no line): how
    many of all, their first rows, and how many the verdict was fitted without."""
    out = report.get("outliers") or {}
    rows = out.get("rows") or []
    if not rows:
        return []
    shown = ", ".join(str(r) for r in rows[:5]) + (
        f" and {len(rows) - 5} more" if len(rows) > 5 else ""
    )
    left = int(out.get("left_out_of_fit", 0))
    robust = report["verdict"].get("heldout_rmse_robust_m")
    return [
        f"outliers         {len(rows)} of {report['throws']} throws miss by over "
        f"{out.get('threshold_sigma', float('nan')):.1f} σ (rows {shown}; the JSON report's "
        f"outliers)"
        + (
            f"; the verdict is fitted without {'them' if left == len(rows) else left}"
            if left
            else ""
        )
        + (f"; held-out {robust:.4f} m without them" if robust is not None else "")
    ]


def format_table(report: dict[str, Any]) -> str:
    """The report as a terminal table."""
    r = report
    lines = []
    other = r.get("other_launcher_throws", 0)
    other_out = (r.get("outliers") or {}).get("other_launcher", 0)
    lines.append(
        f"throws           {r['throws']} ({other} from another launcher, from tracks"
        + (f", {other_out} of them outliers" if other_out else "")
        + ")"
    )
    lines.extend(_tracks_set_aside(r.get("tracks") or {}))
    lines.extend(_outliers(r))
    nz = r.get("noise", {})
    val = nz.get("validated_m")
    with_val = val is not None and np.isfinite(val) and nz.get("validated_share", 0) > 0
    lines.append(
        f"noise floor F    {r['noise_floor_m']:.4f} m  ({nz.get('method', '?')}; "
        f"repeats {_m(nz.get('repeats_m'))}, neighbours {_m(nz.get('neighbours_m'))}, "
        f"model {_m(nz.get('model_m'))}"
        + (
            f"; validated {_m(val)}: the parameter file's held-out misfit of the throws' "
            f"objects ({100 * nz['validated_share']:.0f} % of the throws)"
            if with_val
            else ""
        )
        + ")"
    )
    b = r["baseline"]
    lines.append(
        f"baseline B       {b['heldout_rmse_m']:.4f} m held-out  (fit {b['fit_rmse_m']:.4f} m)"
    )
    w = r["where"]
    lines.append(f"where            {w.get('phase')}: {w.get('evidence', '')}")
    for c in w.get("worst", []):
        lines.append(
            f"  worst          {c['factor']} = {c['level']}: {c['heldout_rmse_m']:.4f} m "
            f"({c['throws']} throws"
            + (f"; after {c['after_rmse_m']:.4f} m" if "after_rmse_m" in c else "")
            + ")"
        )
    lines.append("candidates              held-out RMSE   shrink [95% CI]          params")
    tests = r.get("tests", {})
    for c in r["candidates"]:
        lo, hi = c.get("shrink_ci_pct", [float("nan")] * 2)
        t = tests.get(c["effect"], {})
        mark = ""
        if t:
            mark = "joins" if t.get("joins") else ("passes" if t.get("passes") else "rejected")
            perm = t.get("permutation")
            if perm is not None and not perm["survives"]:
                mark += " (permutation)"
        if c.get("refused"):
            mark += f" [refused: {c['refused']}]"
        name = c["effect"] + (f" ({c['law']})" if c.get("law") else "")
        lines.append(
            f"  {name:22s}{c['heldout_rmse_m']:8.4f} m   {c['shrink_pct']:6.1f}% "
            f"[{lo:6.1f}, {hi:6.1f}]   {_fmt_params(c['params'])}  {mark}"
        )
    v = r["verdict"]
    lo, hi = v.get("shrink_ci_pct", [float("nan")] * 2)
    lines.append(
        f"verdict          {' + '.join(v['effects'])}: held-out {b['heldout_rmse_m']:.4f} → "
        f"{v['heldout_rmse_m']:.4f} m, shrink {v['shrink_pct']:.1f}% [{lo:.1f}, {hi:.1f}]"
    )
    for eff, ci in (v.get("params_ci95") or {}).items():
        p = v["params"].get(eff, {})
        law = (v.get("laws") or {}).get(eff)
        lines.append(
            f"  {eff}{f' ({law})' if law else ''}: "
            + ", ".join(f"{k}={x:.4g} [{a:.4g}, {b:.4g}]" for k, x, (a, b) in _ci_items(p, ci))
            + " (95% intervals)"
        )
    pt = r.get("parameter_throw_to_throw")
    if pt and pt["names"]:
        lines.append(
            f"  {pt['effect']}'s {pt['param']} drawn throw to throw: its spread sets the floor at "
            f"{pt['floor_m']:.4f} m (F {r['noise_floor_m']:.4f} m from the repeats alone)"
        )
    if r.get("one_configuration"):
        lines.append(f"                 ({r['one_configuration']['why']})")
    elif v.get("partial_effects"):
        rest = "the rest is above 1.3 × F"
        if r.get("wind_not_steady"):
            rest = r["wind_not_steady"]["why"]
        if (r.get("parameter_drifts") or {}).get("why"):
            rest = r["parameter_drifts"]["why"]
        lines.append(
            f"                 (partly explained by {' + '.join(v['partial_effects'])}; {rest})"
        )
    return "\n".join(lines)


def _m(v: Any) -> str:
    return "—" if v is None or not np.isfinite(v) else f"{v:.4f} m"


def _png(fig: Any) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _after_title(r: dict[str, Any]) -> str:
    v = r["verdict"]
    if r.get("one_configuration") and v["params"]:  # the plot is the joined effects'
        return "with " + " + ".join(v["params"]) + " (one of those alike; verdict unknown)"
    if v.get("partial_effects"):
        return "with " + " + ".join(v["partial_effects"]) + " (partial; verdict unknown)"
    if v["effects"] == ["none"]:
        return "verdict none: nothing added"
    return "with " + " + ".join(v["effects"])


def _plots(d: Diagnosis, prob: GapProblem) -> list[tuple[str, str]]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = []
    r = d.report
    F = r["noise_floor_m"]
    # 1. landing misses before and after
    fig, axes = plt.subplots(1, 2, figsize=(9, 4.2), sharex=True, sharey=True)
    for ax, res, title in (
        (axes[0], d.baseline_residual, "configured model"),
        (axes[1], d.verdict_residual, _after_title(r)),
    ):
        ax.scatter(res[:, 0], res[:, 1], s=5, alpha=0.5)
        ax.add_patch(plt.Circle((0, 0), F, fill=False, color="k", ls="--", label="noise floor"))
        ax.set_title(title)
        ax.set_xlabel("observed − predicted x [m]")
        ax.set_aspect("equal")
    axes[0].set_ylabel("observed − predicted y [m]")
    axes[0].legend(loc="upper right")
    out.append(("Landing misses before and after (all throws)", _png(fig)))
    plt.close(fig)
    # 2. residuals against the factors that matter
    t = prob.table
    dist = np.hypot(prob.observed[:, 0] - t.num("x_m"), prob.observed[:, 1] - t.num("y_m"))
    factors = {
        "mass [kg]": t.num("mass_kg"),
        "stroke [m]": t.num("stroke_m"),
        "distance [m]": dist,
        "grip width [m]": t.num("size_x_m"),
    }
    if np.any(t.num("rotor_rpm") > 0):
        factors["rotor speed [rpm]"] = t.num("rotor_rpm")
    fig, axes = plt.subplots(1, len(factors), figsize=(3.2 * len(factors), 3.2), sharey=True)
    before = np.sqrt(d.baseline_sq)
    after = np.sqrt(d.verdict_sq)
    for ax, (label, x) in zip(np.atleast_1d(axes), factors.items(), strict=True):
        ax.scatter(x, before, s=4, alpha=0.4, label="before")
        ax.scatter(x, after, s=4, alpha=0.4, label="after")
        ax.axhline(F, color="k", ls="--", lw=1)
        ax.set_xlabel(label)
    np.atleast_1d(axes)[0].set_ylabel("held-out miss [m]")
    np.atleast_1d(axes)[0].legend()
    out.append(("Held-out miss against the logged factors", _png(fig)))
    plt.close(fig)
    # 3. the ranking
    cands = r["candidates"]
    fig, ax = plt.subplots(figsize=(7, 0.35 * len(cands) + 1.5))
    names = [c["effect"] for c in cands][::-1]
    vals = [c["heldout_rmse_m"] for c in cands][::-1]
    ax.barh(names, vals, color="tab:blue")
    ax.axvline(r["baseline"]["heldout_rmse_m"], color="tab:red", label="baseline B")
    ax.axvline(F, color="k", ls="--", label="noise floor F")
    ax.axvline(1.3 * F, color="k", ls=":", label="1.3 F")
    ax.set_xlabel("held-out RMSE [m]")
    ax.legend(loc="lower right")
    out.append(("Effects ranked by held-out RMSE", _png(fig)))
    plt.close(fig)
    return out


def write_html(d: Diagnosis, prob: GapProblem, path: str | Path) -> None:
    """Write the report as one self-contained HTML page (plots embedded as PNG)."""
    r = d.report
    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>cell gap</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}"
        "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 8px}"
        "pre{background:#f6f6f6;padding:1em;overflow-x:auto}</style></head><body>",
        "<h1>Sim-to-real diagnosis</h1>",
        f"<p><b>Verdict:</b> {html.escape(' + '.join(r['verdict']['effects']))} — held-out RMSE "
        f"{r['baseline']['heldout_rmse_m']:.4f} m → {r['verdict']['heldout_rmse_m']:.4f} m "
        f"(shrink {r['verdict']['shrink_pct']:.1f}%), noise floor {r['noise_floor_m']:.4f} m.</p>",
        f"<p><b>Where:</b> {html.escape(str(r['where'].get('phase')))} — "
        f"{html.escape(r['where'].get('evidence', ''))}</p>",
        "<pre>" + html.escape(format_table(r)) + "</pre>",
    ]
    for title, png in _plots(d, prob):
        parts.append(f"<h2>{html.escape(title)}</h2><img src='data:image/png;base64,{png}'>")
    parts.append(
        "<h2>Held-out RMSE by condition</h2><table><tr><th>factor</th><th>level</th>"
        "<th>throws</th><th>before [m]</th><th>after [m]</th></tr>"
    )
    for c in r.get("conditions", []):
        parts.append(
            f"<tr><td>{html.escape(c['factor'])}</td><td>{html.escape(str(c['level']))}</td>"
            f"<td>{c['throws']}</td><td>{c['heldout_rmse_m']:.4f}</td>"
            f"<td>{c.get('after_rmse_m', float('nan')):.4f}</td></tr>"
        )
    parts.append("</table>")
    parts.append("<h2>JSON</h2><pre>" + html.escape(json.dumps(jsonable(r), indent=1)) + "</pre>")
    parts.append("</body></html>")
    write_whole(path, lambda p: p.write_text("\n".join(parts)))
