"""The throwing end-effector's simulated mechanism, as its description states it.

`robots/throwing_ee/throwing_ee.urdf` is the one description of the end-effector: the
PyBullet scene loads it as the end-effector's body and the planner loads it inside each
arm's composite. `EEGeometry` holds the numbers the cell's code needs from it (dimensions,
masses, the stroke range and end stop, the pads' friction), read from that file by
`load_ee_geometry`; `DEFAULT_GEOMETRY` is the file's.

End-effector frame E: the plate face, FLANGE_TO_EE_M along z from the description's
`ee_base` (cell.sim.frames), +z the throw axis (the approach axis u of MODEL.md), x
across the band (the grip width), y completing a right-handed frame. The end-effector
body's base frame in PyBullet is E: `ee_base`'s mass is lumped there (its inertial
origin), and PyBullet puts a body's base frame at its inertial frame.

Links and joints (`DRIVEN_JOINTS` in PyBullet's joint order):

* `ee_base`: the housing (mount side at z < 0 in E).
* `ee_band` on the prismatic `ee_band_joint` along +z: the band carriage (the
  hoop and the moving part of the band). Its joint value is the position of the
  carriage face, i.e. the stroke L_s [m] from E. The band force law drives it
  (cell.sim.band); its upper joint limit is the end stop where the rope that ties
  the hoop catches it once the band is slack.
* `ee_finger_left` / `ee_finger_right` on the prismatic
  `ee_finger_left_joint` / `ee_finger_right_joint`, riding on the carriage:
  pads that close on the item across x. Joint value = distance of the pad's
  inner face from the throw axis [m].
* `ee_tcp` (fixed): the grip centre, the planner's TCP.

The item sits on the carriage face between the pads, its centre of mass at
z = L_s + size_z/2 in E.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from cell.errors import InvalidParameter, plural

__all__ = ["EEGeometry", "DEFAULT_GEOMETRY", "DRIVEN_JOINTS", "load_ee_geometry"]

DRIVEN_JOINTS = ("ee_band_joint", "ee_finger_left_joint", "ee_finger_right_joint")
"""The joints the scene drives (band carriage, pads), in PyBullet's joint order: indices
0, 1, 2 of the end-effector's body (cell.sim.band's BAND_JOINT, FINGER_LEFT, FINGER_RIGHT)."""


@dataclass(frozen=True)
class EEGeometry:
    """Dimensions and masses of the simulated end-effector (SI), as its description
    (robots/throwing_ee/throwing_ee.urdf) states them: build it with `load_ee_geometry`.

    Attributes:
        band_mass_kg: moving mass of the carriage (hoop plus band) [kg]: `ee_band`'s mass.
        finger_mass_kg: mass of each finger pad [kg] (moves with the carriage).
        base_mass_kg: mass of the housing [kg]: `ee_base`'s mass.
        carriage_half_xy_m: half side of the carriage plate [m] (`ee_band`'s box).
        carriage_thickness_m: carriage plate thickness [m].
        pad_length_m: finger pad length along the throw axis [m] (the pad box's z): no
            longer than the shortest catalogue box (0.03 m), so that a placed item
            touches down before the pads; the largest sphere (0.07 m) is then held 5 mm
            below its equator, where friction still holds it.
        pad_thickness_m: finger pad thickness across x [m] (the pad box's x).
        pad_half_width_m: half width of a pad along y [m] (half the pad box's y).
        finger_open_m: widest pad opening from the axis [m] (the pad joints' upper limit).
        end_stop_m: carriage position where the rope catches it [m] (`ee_band_joint`'s
            upper limit).
        stroke_lower_m: lowest carriage position [m] (`ee_band_joint`'s lower limit).
        pad_friction: Coulomb friction of the pads (latex band on plastic): the pads'
            `<contact><lateral_friction>`.
        housing_half_x_m, housing_half_y_m: half the housing's sides across the throw
            axis [m] (`ee_base`'s box; x across the pads).
        housing_to_tcp_m: from the housing's front face (toward the item) to the TCP,
            along the throw axis [m] (`ee_tcp_joint`'s origin less the box's front).
    """

    band_mass_kg: float
    finger_mass_kg: float
    base_mass_kg: float
    carriage_half_xy_m: float
    carriage_thickness_m: float
    pad_length_m: float
    pad_thickness_m: float
    pad_half_width_m: float
    finger_open_m: float
    end_stop_m: float
    stroke_lower_m: float
    pad_friction: float
    housing_half_x_m: float
    housing_half_y_m: float
    housing_to_tcp_m: float

    @property
    def housing_radius_m(self) -> float:
        """The circle about the housing's sides across the throw axis [m]: its reach from
        the axis at any heading."""
        return math.hypot(self.housing_half_x_m, self.housing_half_y_m)

    @property
    def pad_spin_friction_m(self) -> float:
        """The pads' torsional ("spinning") friction coefficient [m] for PyBullet.

        A pad pressed flat on an item's face resists a twist about its normal with
        μ r̄ N, r̄ the mean distance of the pad's face from its centre (uniform pressure):
        without it, the engine's few contact points, loaded unevenly, let a gripped item
        pivot about the pads' axis under its own weight. PyBullet combines the coefficient
        as s_pad μ_item + s_item μ_pad, so s_pad = μ_pad r̄ gives μ_pad μ_item r̄ (its
        combined lateral friction times r̄) against an item of small s_item.
        """
        import numpy as np

        u = (np.arange(64) + 0.5) / 64 - 0.5  # midpoints over the face, in units of its sides
        y, z = np.meshgrid(u * 2 * self.pad_half_width_m, u * self.pad_length_m)
        return self.pad_friction * float(np.hypot(y, z).mean())

    @property
    def moving_mass_kg(self) -> float:
        """Mass that the band drives besides the item [kg]."""
        return self.band_mass_kg + 2 * self.finger_mass_kg


def _floats(text: str | None, n: int, what: str, path: Path) -> tuple[float, ...]:
    try:
        vals = tuple(float(v) for v in (text or "").split())
    except ValueError:
        vals = ()
    if len(vals) != n or not all(math.isfinite(v) for v in vals):
        raise InvalidParameter(f"{path}: {what} must be {plural(n, 'finite number')}, got {text!r}")
    return vals


def _origin_xyz(el: ET.Element, what: str, path: Path) -> tuple[float, ...]:
    """The xyz of an element's <origin> (zero without one); its rpy must be zero."""
    o = el.find("origin")
    if o is None:
        return (0.0, 0.0, 0.0)
    if any(_floats(o.get("rpy", "0 0 0"), 3, f"{what} origin rpy", path)):
        raise InvalidParameter(f"{path}: {what}: the simulated mechanism has no rotated frames")
    return _floats(o.get("xyz", "0 0 0"), 3, f"{what} origin xyz", path)


class _Description:
    """The links and joints of the end-effector's URDF, looked up with clear errors."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            root = ET.parse(path).getroot()
        except (OSError, ET.ParseError) as exc:
            raise InvalidParameter(f"{path}: cannot read the end-effector's URDF ({exc})") from None
        self.links = {lk.get("name", ""): lk for lk in root.findall("link")}
        self.joints = {j.get("name", ""): j for j in root.findall("joint")}

    def link(self, name: str) -> ET.Element:
        if name not in self.links:
            raise InvalidParameter(f"{self.path}: no link {name!r}")
        return self.links[name]

    def mass(self, link: str) -> float:
        """The link's mass [kg], positive."""
        el = self.link(link).find("inertial/mass")
        if el is None:
            raise InvalidParameter(f"{self.path}: link {link!r} has no inertial mass")
        (m,) = _floats(el.get("value"), 1, f"link {link!r} mass", self.path)
        if m <= 0:
            raise InvalidParameter(f"{self.path}: link {link!r} mass {m} kg must be > 0")
        return m

    def inertial_origin(self, link: str) -> tuple[float, ...]:
        el = self.link(link).find("inertial")
        if el is None:
            raise InvalidParameter(f"{self.path}: link {link!r} has no <inertial>")
        return _origin_xyz(el, f"link {link!r} inertial", self.path)

    def box(self, link: str) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """(size [m], centre [m] in the link frame) of the link's one collision box."""
        cols = self.link(link).findall("collision")
        box = cols[0].find("geometry/box") if len(cols) == 1 else None
        if box is None:
            raise InvalidParameter(f"{self.path}: link {link!r} must have one collision box")
        size = _floats(box.get("size"), 3, f"link {link!r} box size", self.path)
        if min(size) <= 0:
            raise InvalidParameter(f"{self.path}: link {link!r} box size {size} must be > 0")
        return size, _origin_xyz(cols[0], f"link {link!r} collision", self.path)

    def friction(self, link: str) -> float:
        el = self.link(link).find("contact/lateral_friction")
        if el is None:
            raise InvalidParameter(
                f"{self.path}: link {link!r} needs <contact><lateral_friction value=.../>"
            )
        (mu,) = _floats(el.get("value"), 1, f"link {link!r} lateral_friction", self.path)
        if mu <= 0:
            raise InvalidParameter(f"{self.path}: link {link!r} friction {mu} must be > 0")
        return mu

    def prismatic(
        self, name: str, parent: str, child: str, axis: tuple[float, float, float]
    ) -> tuple[tuple[float, ...], float, float]:
        """(origin xyz [m], lower [m], upper [m]) of a prismatic joint, checked."""
        if name not in self.joints:
            raise InvalidParameter(f"{self.path}: no joint {name!r}")
        j = self.joints[name]
        par, chi, ax = j.find("parent"), j.find("child"), j.find("axis")
        got = (
            j.get("type"),
            par.get("link") if par is not None else None,
            chi.get("link") if chi is not None else None,
            _floats(ax.get("xyz") if ax is not None else "1 0 0", 3, f"{name} axis", self.path),
        )
        if got != ("prismatic", parent, child, axis):
            raise InvalidParameter(
                f"{self.path}: joint {name!r} must be prismatic from {parent!r} to {child!r} "
                f"along {axis}, got type, parent, child, axis = {got}"
            )
        lim = j.find("limit")
        if lim is None:
            raise InvalidParameter(f"{self.path}: joint {name!r} has no <limit>")
        (lo,) = _floats(lim.get("lower"), 1, f"joint {name!r} lower limit", self.path)
        (hi,) = _floats(lim.get("upper"), 1, f"joint {name!r} upper limit", self.path)
        if not lo < hi:
            raise InvalidParameter(f"{self.path}: joint {name!r} limits [{lo}, {hi}] are empty")
        return _origin_xyz(j, f"joint {name!r}", self.path), lo, hi

    def fixed(self, name: str, parent: str, child: str) -> tuple[float, ...]:
        """The origin xyz [m] of a fixed joint from `parent` to `child`, checked."""
        if name not in self.joints:
            raise InvalidParameter(f"{self.path}: no joint {name!r}")
        j = self.joints[name]
        par, chi = j.find("parent"), j.find("child")
        got = (
            j.get("type"),
            par.get("link") if par is not None else None,
            chi.get("link") if chi is not None else None,
        )
        if got != ("fixed", parent, child):
            raise InvalidParameter(
                f"{self.path}: joint {name!r} must be fixed from {parent!r} to {child!r}, "
                f"got type, parent, child = {got}"
            )
        return _origin_xyz(j, f"joint {name!r}", self.path)


def _pads(d: _Description, path: Path) -> list[tuple[float, tuple[float, ...], float, float]]:
    """Each pad's (mass [kg], box [m], friction, opening [m]), left then right, checked
    to be alike and to sit on their joints as the scene assumes."""
    pads = []
    for side, axis in (("left", (-1.0, 0.0, 0.0)), ("right", (1.0, 0.0, 0.0))):
        link = f"ee_finger_{side}"
        origin, lo, hi = d.prismatic(f"{link}_joint", "ee_band", link, axis)
        if origin != (0.0, 0.0, 0.0) or lo != 0.0:
            raise InvalidParameter(
                f"{path}: joint {link + '_joint'!r} must start at the carriage's frame "
                f"(origin 0 0 0) with its lower limit 0 (a pad closed on the axis)"
            )
        size, centre = d.box(link)
        if centre != (axis[0] * size[0] / 2, 0.0, size[2] / 2):
            raise InvalidParameter(
                f"{path}: link {link!r}: the pad's box must have its inner face on the joint "
                f"(x = 0) and start at the carriage face (z = 0): centre "
                f"{(axis[0] * size[0] / 2, 0.0, size[2] / 2)}, got {centre}"
            )
        pads.append((d.mass(link), size, d.friction(link), hi))
    if pads[0] != pads[1]:
        raise InvalidParameter(
            f"{path}: the two pads must have the same mass, box, friction and opening; "
            f"got (left) {pads[0]} and (right) {pads[1]}"
        )
    return pads


def load_ee_geometry(path: str | Path | None = None) -> EEGeometry:
    """The simulated end-effector's numbers, read from its description.

    Besides reading them, this checks what the scene relies on: the links and prismatic
    joints of the module's docstring; `ee_base`'s mass at the carriage's seat E (the
    origin of `ee_band_joint`), the carriage's and each pad's at its link frame (PyBullet's
    base and link frames are the inertial frames: the mount, the band force and the pads'
    gear act there); both pads alike.

    Args:
        path: the URDF (default robots/throwing_ee/throwing_ee.urdf).

    Returns:
        The EEGeometry of that file.

    Raises:
        InvalidParameter: the file is missing, unreadable, or not that mechanism; the
            message names the file and the element.
    """
    from cell.robot.composite import end_effector_urdf

    path = Path(path) if path is not None else end_effector_urdf()
    d = _Description(path)
    seat, lower, end_stop = d.prismatic("ee_band_joint", "ee_base", "ee_band", (0.0, 0.0, 1.0))
    if d.inertial_origin("ee_base") != seat:
        raise InvalidParameter(
            f"{path}: ee_base's inertial origin {d.inertial_origin('ee_base')} must be "
            f"ee_band_joint's origin {seat} (E, where the scene holds the end-effector)"
        )
    pads = _pads(d, path)
    for link in ("ee_band", "ee_finger_left", "ee_finger_right"):
        if d.inertial_origin(link) != (0.0, 0.0, 0.0):
            raise InvalidParameter(f"{path}: link {link!r}: its mass must sit at its frame")
    carriage, _ = d.box("ee_band")
    if carriage[0] != carriage[1]:
        raise InvalidParameter(f"{path}: the carriage plate (ee_band's box) must be square")
    pad_mass, (pad_x, pad_y, pad_z), mu, opening = pads[0]
    housing, h_centre = d.box("ee_base")
    tcp = d.fixed("ee_tcp_joint", "ee_base", "ee_tcp")
    if tcp[:2] != (0.0, 0.0) or h_centre[:2] != (0.0, 0.0):
        raise InvalidParameter(
            f"{path}: the TCP (ee_tcp_joint) and the housing's box must lie on the throw "
            f"axis (x = y = 0), got {tcp} and {h_centre}"
        )
    return EEGeometry(
        band_mass_kg=d.mass("ee_band"),
        finger_mass_kg=pad_mass,
        base_mass_kg=d.mass("ee_base"),
        carriage_half_xy_m=carriage[0] / 2,
        carriage_thickness_m=carriage[2],
        pad_length_m=pad_z,
        pad_thickness_m=pad_x,
        pad_half_width_m=pad_y / 2,
        finger_open_m=opening,
        end_stop_m=end_stop,
        stroke_lower_m=lower,
        pad_friction=mu,
        housing_half_x_m=housing[0] / 2,
        housing_half_y_m=housing[1] / 2,
        housing_to_tcp_m=tcp[2] - (h_centre[2] + housing[2] / 2),
    )


DEFAULT_GEOMETRY = load_ee_geometry()
"""The end-effector of robots/throwing_ee/throwing_ee.urdf."""
