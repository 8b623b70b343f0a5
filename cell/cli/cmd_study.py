"""`cell study repeatability`: the thesis' repeatability table (Table 5.2) against the model."""

from __future__ import annotations

import argparse
import math

from cell.cli.common import add_json_arg, json_to_stdout, print_json, write_json


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("study", help="case studies against the thesis' experiments")
    studies = p.add_subparsers(dest="study", metavar="STUDY", required=True)
    r = studies.add_parser(
        "repeatability",
        help="Table 5.2: reach from the arm and from the drone at 4 rotor speeds, "
        "with the downwash law fitted to the drone means",
    )
    add_json_arg(r, "the rows (a list of objects)")
    r.add_argument("--plot", metavar="FILE.png", help="write the plot (thesis vs fitted laws)")
    r.add_argument(
        "--arm-height",
        type=float,
        default=0.6,
        metavar="M",
        help="the arm's release height [m] (0.6); the stroke follows from its reach",
    )
    r.add_argument(
        "--elevation",
        type=float,
        default=0.0,
        metavar="RAD",
        help="throw-axis elevation of both platforms [rad] (0: horizontal)",
    )
    r.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cell.study.plot import plot_study
    from cell.study.repeatability import StudySetup, run_study

    setup = StudySetup(arm_height_m=args.arm_height, elevation_rad=args.elevation)
    study = run_study(setup)
    if json_to_stdout(args):
        print_json(study.as_rows())
        if args.plot:
            plot_study(study, args.plot)
        return 0
    print(
        f"Repeatability (thesis §5.3.1, Table 5.2): cube50 at stroke {study.stroke_m * 1000:.2f} mm, "
        f"elevation {math.degrees(setup.elevation_rad):.0f}°"
    )
    print(
        f"  arm releases at z = {study.arm_release_m[2]:.3f} m; drone hovers at "
        f"{study.drone_hover_height_m:.3f} m, releases at z = {study.drone_release_m[2]:.3f} m"
    )
    print(
        f"{'platform':<9}{'rpm':>7}{'model [m]':>11}{'threshold [m]':>15}"
        f"{'thesis [m]':>18}{'model−thesis':>14}"
    )
    for r in study.rows:
        rpm = "n/a" if r.rotor_rpm is None else f"{r.rotor_rpm:.0f}"
        print(
            f"{r.platform:<9}{rpm:>7}{r.reach_m:>11.4f}{r.reach_threshold_m:>15.4f}"
            f"{r.thesis_reach_m:>10.4f} ± {r.thesis_std_m:.4f}{r.residual_m:>+14.4f}"
        )
    for f in study.fits:
        params = ", ".join(f"{k}={getattr(f.law, k):.4g}" for k in f.fitted)
        print(
            f"fit {f.name:<9} {params}; RMS {f.rms_sem:.2f} SEM; within spread: "
            f"{'yes' if f.within_spread else 'no'}; within 2 SEM: {'yes' if f.within_sem else 'no'}; "
            f"C_T {f.thrust_coefficient:.3f}; thrust at max rpm {f.thrust_at_max_n:.1f} N"
        )
    print(study.verdict)
    if args.plot:
        plot_study(study, args.plot)
        print(f"plot: {args.plot}")
    write_json(args, study.as_rows())
    return 0
