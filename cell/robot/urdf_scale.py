"""A URDF whose lengths are not metres: the arm's chain far longer than any arm's.

URDF lengths are metres. A description exported from CAD in millimetres (every joint
`<origin xyz>` 1000 times too long) loaded as metres is an arm about a kilometre long: its
IK then misses every pose by tens of metres, and the job check says the arm "reaches about
919 m out" of a station it misses, true of the file and of no arm. Refused when the mount
file is read instead, naming the file and the likely cause.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence

from cell.errors import InvalidParameter

__all__ = ["LONGEST_CHAIN_M", "chain_length_m", "check_chain_scale"]

# The joints' offsets from the URDF's root to the flange add up to under this for any arm a
# cell holds: the largest industrial arms reach under 5 m (a 4.7 m FANUC M-2000iA), a
# humanoid's chain from its pelvis under 2 m. An arm written in millimetres is 1000 times
# its length in metres: a 0.02 m chain (smaller than any arm that carries the gripper) would
# read as 20 m. Not a tuned figure: a bound between lengths three orders apart.
LONGEST_CHAIN_M = 20.0


def chain_length_m(chain: Sequence[ET.Element]) -> float:
    """The sum of the joints' `<origin xyz>` offsets [m, as written] along `chain`."""
    total = 0.0
    for joint in chain:
        origin = joint.find("origin")
        if origin is None:
            continue
        try:
            xyz = [float(v) for v in origin.get("xyz", "0 0 0").split()]
        except ValueError:
            continue  # said by the loaders, with the joint named
        total += math.sqrt(sum(v * v for v in xyz))
    return total


def check_chain_scale(chain: Sequence[ET.Element], where: str, urdf: str) -> None:
    """Refuse an arm whose chain from the root to the flange is longer than
    LONGEST_CHAIN_M.

    Raises:
        InvalidParameter: naming the mount file, the field `arm_urdf`, the chain's length,
            and the likely cause (millimetres).
    """
    length = chain_length_m(chain)
    if length > LONGEST_CHAIN_M:
        raise InvalidParameter(
            f"{where}: field 'arm_urdf': the joints' offsets from the root of {urdf} to the "
            f"flange add up to {length:,.1f} m, longer than any arm ({LONGEST_CHAIN_M:g} m at "
            "most): is it written in millimetres? A URDF's lengths are metres (its joints' "
            "<origin xyz>, each to divide by 1000 if so)"
        )
