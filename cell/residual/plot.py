"""Figures of the residual: landing points around their targets with and without
the residual (thesis Fig. 5.2), and the Table 5.1 comparison of learners."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from cell.residual.campaign import TargetedThrows

__all__ = ["plot_targeted", "plot_table51"]


def plot_targeted(throws: TargetedThrows, path: str | Path, title: str = "") -> None:
    """One panel per object: each throw's landing minus its target [m, W's x and y],
    without (red) and with (green) the residual; the dotted circle is 5 cm.

    Args:
        throws: the targeted throws.
        path: output image (PNG, PDF, SVG by suffix).
        title: figure title.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ids = sorted(set(throws.object_id))
    n = len(ids)
    cols = min(4, n)
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), squeeze=False)
    oid = np.asarray(throws.object_id)
    lim = float(
        np.nanmax(
            np.abs(
                np.concatenate(
                    [
                        throws.landed_model - throws.target_xy,
                        throws.landed_residual - throws.target_xy,
                    ]
                )
            )
        )
    )
    lim = max(lim * 1.1, 0.02)
    for ax, o in zip(axes.flat, ids, strict=False):
        m = oid == o
        d0 = throws.landed_model[m] - throws.target_xy[m]
        d1 = throws.landed_residual[m] - throws.target_xy[m]
        ax.add_patch(plt.Circle((0, 0), 0.05, fill=False, ls=":", color="0.5"))
        ax.plot(0, 0, "k+", ms=12)
        ax.plot(d0[:, 0], d0[:, 1], "o", color="tab:red", mfc="none", label="model")
        ax.plot(d1[:, 0], d1[:, 1], "o", color="tab:green", label="model + ΔL_s")
        r0 = np.sqrt(np.mean(np.sum(d0**2, axis=1)))
        r1 = np.sqrt(np.mean(np.sum(d1**2, axis=1)))
        ax.set_title(f"{o}\nRMSE {r0 * 100:.1f} → {r1 * 100:.1f} cm", fontsize=9)
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7, loc="lower left")
    fig.supxlabel("landing - target, x [m]")
    fig.supylabel("landing - target, y [m]")
    fig.suptitle(
        title
        or f"Unseen objects at set targets: RMSE {throws.rmse(False):.3f} m without, "
        f"{throws.rmse(True):.3f} m with the residual",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_table51(summary: dict[str, Any], path: str | Path) -> None:
    """Bar chart of Table 5.1: ΔL_s MSE mean ± std [mm²] per learner, and the
    held-out landing RMSE before and after [m].

    Args:
        summary: learner -> `LearnerSummary` (or its `as_dict()`).
        path: output image.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(summary)
    rows = [s if isinstance(s, dict) else s.as_dict() for s in summary.values()]
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(8, 3.2))
    x = np.arange(len(names))
    a0.bar(x, [r["dls_mse_mean"] for r in rows], yerr=[r["dls_mse_std"] for r in rows], capsize=4)
    a0.set_xticks(x, names)
    a0.set_ylabel("held-out ΔL_s MSE [mm²]")
    a1.bar(x - 0.2, [r["heldout_rmse_before_m"] for r in rows], 0.4, label="model")
    a1.bar(x + 0.2, [r["heldout_rmse_after_m"] for r in rows], 0.4, label="model + ΔL_s")
    a1.set_xticks(x, names)
    a1.set_ylabel("held-out landing RMSE [m]")
    a1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
