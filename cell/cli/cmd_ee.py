"""`cell ee`: drive the Dynamixel end-effector (or an emulated one) by hand."""

from __future__ import annotations

import argparse
import time

from cell.cli.common import add_json_arg, json_to_stdout, print_json, write_json
from cell.endeffector.factory import DEFAULT_DYNAMIXEL_CONFIG

_EPILOG = """\
No hardware? Add --emulate: the same driver then talks Protocol 2.0 to an
emulated servo bus on a pseudo-terminal, e.g.
  cell ee --emulate grasp --stroke 0.06
To keep an emulated end-effector between commands, serve one in a terminal
  cell ee emulate
and point the other commands at the port it prints: cell ee --port /dev/pts/N status
Torque is turned off when a command ends.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ee",
        help="drive the end-effector hardware (Dynamixel); --emulate without hardware",
        description="Drive the throwing end-effector's Dynamixel servos: M1 latch, M2 spool.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument(
        "--config",
        default=str(DEFAULT_DYNAMIXEL_CONFIG),
        help="hardware description YAML (default: %(default)s)",
    )
    p.add_argument("--port", help="serial port, overriding the configuration's")
    p.add_argument(
        "--emulate",
        action="store_true",
        help="use an emulated servo bus instead of hardware (nothing to plug in)",
    )
    add_json_arg(p, "the status")
    acts = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    acts.add_parser("status", help="servo and stroke state")
    s = acts.add_parser("stroke", help="read the stroke, or wind/unwind to L [m]")
    s.add_argument("length", type=float, nargs="?", metavar="L", help="stroke L_s [m]")
    g = acts.add_parser("grasp", help="engage the latch and wind to a stroke")
    g.add_argument("--stroke", type=float, metavar="L", help="stroke L_s [m] (default: mid-range)")
    acts.add_parser("place", help="unwind slowly: release the object gently")
    acts.add_parser("throw", help="open the latch at once (refused unless engaged and on stroke)")
    e = acts.add_parser("emulate", help="serve an emulated end-effector bus until Ctrl-C")
    e.add_argument("--time-scale", type=float, default=1.0, help="emulated s per real s")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from cell.endeffector.dynamixel import load_config
    from cell.endeffector.factory import make_end_effector

    if args.action == "emulate":
        return _serve(args)
    ee = make_end_effector("dynamixel", args.config, port=args.port, emulate=args.emulate)
    with ee:
        if args.action == "stroke" and args.length is not None:
            ee.set_stroke(args.length)
        elif args.action == "stroke":
            print(f"{ee.stroke():.4f}")
            return 0
        elif args.action == "grasp":
            cfg = load_config(args.config).stroke
            ee.grasp(
                args.stroke if args.stroke is not None else round((cfg.min_m + cfg.max_m) / 2, 4)
            )
        elif args.action == "place":
            ee.place()
        elif args.action == "throw":
            ee.throw()
        st = ee.status()
    doc = {
        "stroke_m": st.stroke_m,
        "latch_engaged": st.latch_engaged,
        "holding": st.holding,
        "detail": st.detail,
    }
    if json_to_stdout(args):
        print_json(doc)
        return 0
    latch = "engaged" if st.latch_engaged else "open"
    print(f"stroke {st.stroke_m:.4f} m, latch {latch}, holding {str(st.holding).lower()}")
    print(st.detail)
    write_json(args, doc)
    return 0


def _serve(args: argparse.Namespace) -> int:
    from cell.endeffector.dynamixel import EmulatedBus, load_config

    cfg = load_config(args.config)
    with EmulatedBus.from_config(cfg, time_scale=args.time_scale) as emu:
        print(f"emulated end-effector bus on {emu.port} (servo IDs {sorted(emu.servos)})")
        print(f"try: cell ee --config {args.config} --port {emu.port} status   (Ctrl-C stops)")
        try:
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            print("stopped")
    return 0
