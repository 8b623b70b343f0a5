"""The speed–accuracy trade-off: items per hour against in-bin rate as the arm's
speed scale varies, on random layouts (`cell bench tradeoff`).

Each point is `cell bench sort` over the same layouts with the arm's moves at a
fraction of its joint limits (`Orchestrator(speed_scale=…)`; a carry may still go
slower, as the grip allows), drawn from one set of layouts (`cell bench tradeoff --set`,
the `test` set by default: `cell.bench.bench_sort.LAYOUT_SETS`). The plot shows items
per hour (honest cycle: `cell.orchestrator`) on x and the in-bin rate with its 95 %
Wilson interval on y.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["tradeoff_units", "tradeoff_rows", "plot_tradeoff"]


def tradeoff_units(
    scales: tuple[float, ...],
    layouts: int,
    seed: int,
    robots: tuple[str, ...],
    max_items: int = 0,
) -> list[Any]:
    """One LayoutUnit per (scale, layout): the same layouts at every scale."""
    from cell.bench.bench_sort import layout_units

    return [
        u
        for s in scales
        for u in layout_units(layouts, seed, robots, max_items=max_items, speed_scale=s)
    ]


def tradeoff_rows(results: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """`summarise_layouts` per speed scale, slowest first, each with its `speed_scale`."""
    from cell.bench.bench_sort import summarise_layouts

    scales = sorted({float(r["speed_scale"]) for r in results})
    rows = []
    for s in scales:
        fig = summarise_layouts([r for r in results if float(r["speed_scale"]) == s])
        rows.append({"speed_scale": s, **fig})
    return rows


def plot_tradeoff(rows: list[dict[str, Any]], path: str | Path, layout_set: str = "") -> Path:
    """Items per hour (x) against in-bin rate (y, 95 % interval), one point per scale;
    `layout_set` (tune or test, `cell.bench.bench_sort.LAYOUT_SETS`) named in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = [r["items_per_hour"] for r in rows]
    y = [r["in_bin_rate"] for r in rows]
    lo = [r["in_bin_rate"] - r["in_bin_rate_lo"] for r in rows]
    hi = [r["in_bin_rate_hi"] - r["in_bin_rate"] for r in rows]
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.errorbar(x, y, yerr=[lo, hi], fmt="o-", color="tab:blue", capsize=3)
    for r, xi, yi in zip(rows, x, y, strict=True):
        ax.annotate(
            f"×{r['speed_scale']:.2g}", (xi, yi), textcoords="offset points", xytext=(6, -12)
        )
    ax.axhline(0.95, color="tab:green", ls=":", lw=1)
    ax.axvline(1500, color="tab:green", ls=":", lw=1)
    ax.set_xlabel("items per hour in the right bin (simulated, honest cycle)")
    ax.set_ylabel("in-bin rate (95 % interval)")
    n = rows[0]["layouts"] if rows else 0
    which = f"{n} {layout_set}-set random layouts" if layout_set else f"{n} random layouts"
    ax.set_title(f"Speed scale of the arm's limits vs accuracy ({which})")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
