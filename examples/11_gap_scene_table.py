"""Print docs/gap_scene.md's table from the JSON `cell gap check --worlds scene` writes.

cell gap check --worlds scene --n 80 --workers 2 --json docs/figures/gap_check_scene.json
python examples/11_gap_scene_table.py docs/figures/gap_check_scene.json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from cell.gap.scene_table import scene_table

MAX_BYTES = 10**7  # [bytes] a check's JSON is a few tens of kB


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("json", type=Path, help="the JSON of `cell gap check --worlds scene --json`")
    args = ap.parse_args(argv)
    try:
        if args.json.stat().st_size > MAX_BYTES:
            raise ValueError(f"larger than {MAX_BYTES} bytes")
        doc = json.loads(args.json.read_text())
        print(scene_table(doc), end="")
    except (OSError, ValueError, KeyError, TypeError, AttributeError, RecursionError) as e:
        print(f"cell: error: {args.json}: not a `cell gap check --worlds scene` JSON ({e})",
              file=sys.stderr)  # fmt: skip
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
