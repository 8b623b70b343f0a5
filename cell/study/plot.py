"""The repeatability study's plot: the thesis' means ± std and the fitted downwash laws
against rotor speed (`cell.study.repeatability.run_study`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from cell.model.params import DEFAULT_EE, EndEffectorParams
from cell.study.repeatability import (
    THESIS_TRIALS,
    RepeatabilityStudy,
    _cube,
    _drone_reach,
)

__all__ = ["plot_study"]


def plot_study(
    study: RepeatabilityStudy, path: str | Path, ee: EndEffectorParams = DEFAULT_EE
) -> Path:
    """Write the study's plot (PNG): thesis means ± std and the fitted laws against rpm.

    Args:
        study: the study.
        path: output PNG file.
        ee: the end-effector parameters the study used.

    Returns:
        The written path.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    setup = study.setup
    obj = _cube(setup)
    rpm = np.linspace(0.0, 16000.0, 33)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [3, 1]})
    drone = [r for r in study.rows if r.platform == "drone"]
    ax.errorbar(
        [r.rotor_rpm for r in drone],
        [r.thesis_reach_m for r in drone],
        yerr=[r.thesis_std_m for r in drone],
        fmt="ko",
        capsize=4,
        label="thesis, mean ± std (20 throws)",
    )
    ax.errorbar(
        [r.rotor_rpm for r in drone],
        [r.thesis_reach_m for r in drone],
        yerr=[r.thesis_std_m / math.sqrt(THESIS_TRIALS) for r in drone],
        fmt="none",
        ecolor="0.3",
        elinewidth=3,
        capsize=0,
        label="thesis, ± SEM",
    )
    for fit, style in zip(study.fits, ("C0-", "C1--"), strict=True):
        curve = _drone_reach(
            obj, ee, setup, study.stroke_m, study.drone_release_m[2], list(rpm), fit.law
        )
        label = f"{fit.name}: c={fit.law.induced_mps_per_krpm:.3f} m/s/krpm" + (
            f", rpm0={fit.law.threshold_rpm:.0f}" if fit.name == "threshold" else ""
        )
        ax.plot(rpm, curve, style, label=label)
    ax.set_xlabel("rotor speed [rpm]")
    ax.set_ylabel("reach [m]")
    ax.set_title(
        f"Drone: cube thrown at L_s = {study.stroke_m * 1000:.1f} mm from "
        f"{study.drone_release_m[2]:.2f} m"
    )
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    arm = study.rows[0]
    ax2.errorbar([0], [arm.thesis_reach_m], yerr=[arm.thesis_std_m], fmt="ko", capsize=4)
    ax2.plot([0], [arm.reach_m], "C0s", label="model")
    ax2.set_xticks([0], ["arm"])
    ax2.set_title(f"Arm, from {study.arm_release_m[2]:.2f} m")
    ax2.set_ylabel("reach [m]")
    ax2.grid(True, alpha=0.3)
    ax2.legend(fontsize=8)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
