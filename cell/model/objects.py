"""Object parameters η_o: shape class, mass, box extents, and what follows
from them (inertia, drag coefficient, mean projected area).

Extents are in the object frame O: x across the band (the grip width), z along
the throw axis. All SI.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from cell.errors import InvalidParameter

__all__ = [
    "SHAPES",
    "DRAG_COEFFICIENT",
    "ObjectParams",
    "shape_code",
    "drag_area",
    "drag_coefficient",
    "inertia_diagonal",
    "MAX_DENSITY_KG_M3",
    "denser_than_any_solid",
    "MIN_DENSITY_KG_M3",
    "lighter_than_air",
]

SHAPES = ("cube", "cuboid", "cylinder", "sphere", "mesh")
DRAG_COEFFICIENT = {"cube": 1.05, "cuboid": 1.05, "cylinder": 0.82, "sphere": 0.47, "mesh": 1.0}
# [kg/m³] osmium's 22,590 rounded up: no solid at room conditions is denser. An object's
# box bounds its volume, so a mass over this times the box's volume is not a real object.
MAX_DENSITY_KG_M3 = 22_600.0


def denser_than_any_solid(mass_kg: float, size_m: Sequence[float]) -> str:
    """What is impossible about `mass_kg` in a box of extents `size_m` [m] ("" if nothing):
    the mass over the box's volume above `MAX_DENSITY_KG_M3` (a mass in grams, mostly)."""
    vol = float(np.prod(np.asarray(size_m, dtype=float)))
    if not vol > 0.0 or mass_kg <= MAX_DENSITY_KG_M3 * vol:
        return ""
    mm = " x ".join(f"{1000.0 * float(s):g}" for s in size_m)
    return (
        f"{mass_kg:g} kg in a {mm} mm box is {mass_kg / vol:,.0f} kg/m³, denser than any "
        "solid (osmium: 22,590 kg/m³)"
    )


# [kg/m³] an object whose mass over its box's volume is under this is lighter than the
# air (1.2 kg/m³) its box would displace: a balloon, or a mass written in another unit;
# the catalogue's lightest is 178 kg/m³ (o6_bottle), a random job's ad-hoc items 150
MIN_DENSITY_KG_M3 = 1.0


def lighter_than_air(mass_kg: float, size_m: Sequence[float]) -> str:
    """What is impossible about `mass_kg` in a box of extents `size_m` [m] ("" if nothing):
    the mass over the box's volume under `MIN_DENSITY_KG_M3`."""
    vol = float(np.prod(np.asarray(size_m, dtype=float)))
    if not vol > 0.0 or mass_kg >= MIN_DENSITY_KG_M3 * vol:
        return ""
    mm = " x ".join(f"{1000.0 * float(s):g}" for s in size_m)
    return (
        f"{mass_kg:g} kg in a {mm} mm box is {mass_kg / vol:.3g} kg/m³, lighter than the "
        f"air it would displace (1.2 kg/m³): it would float, not fall; the least valid is "
        f"{MIN_DENSITY_KG_M3 * vol:.3g} kg ({MIN_DENSITY_KG_M3:g} kg/m³ of its box)"
    )


_CD_BY_CODE = np.array([DRAG_COEFFICIENT[s] for s in SHAPES])


def shape_code(shape: str, *, where: str = "shape") -> int:
    """The index of a shape name in SHAPES.

    Raises:
        InvalidParameter: for an unknown shape, listing the valid ones.
    """
    try:
        return SHAPES.index(shape)
    except ValueError:
        raise InvalidParameter(
            f"{where}: unknown shape {shape!r}; valid: {', '.join(SHAPES)}"
        ) from None


def drag_coefficient(codes: np.ndarray) -> np.ndarray:
    """C_d per shape code (MODEL.md)."""
    return _CD_BY_CODE[np.asarray(codes, dtype=int)]


def drag_area(codes: np.ndarray, size: np.ndarray) -> np.ndarray:
    """Mean projected area A = surface / 4 [m^2] (Cauchy), per MODEL.md.

    Args:
        codes: shape codes, shape (n,).
        size: box extents (size_x, size_y, size_z) [m], shape (n, 3).
    """
    codes = np.asarray(codes, dtype=int)
    size = np.asarray(size, dtype=float).reshape(-1, 3)
    x, y, z = size[:, 0], size[:, 1], size[:, 2]
    box = (x * y + y * z + z * x) / 2
    sphere = math.pi * x**2 / 4
    r = x / 2
    cyl = (2 * math.pi * r**2 + 2 * math.pi * r * z) / 4
    return np.where(
        codes == SHAPES.index("sphere"),
        sphere,
        np.where(codes == SHAPES.index("cylinder"), cyl, box),
    )


def inertia_diagonal(code: int, mass: float, size: np.ndarray) -> np.ndarray:
    """Principal inertia (I_xx, I_yy, I_zz) [kg m^2] about the centre of mass, object frame.

    Solid primitives; a mesh is treated as its solid bounding box.
    """
    x, y, z = (float(v) for v in np.asarray(size, float))
    shape = SHAPES[code]
    if shape == "sphere":
        i = 2 / 5 * mass * (x / 2) ** 2
        return np.array([i, i, i])
    if shape == "cylinder":
        r = x / 2
        ixx = mass * (3 * r**2 + z**2) / 12
        return np.array([ixx, ixx, mass * r**2 / 2])
    return mass / 12 * np.array([y**2 + z**2, x**2 + z**2, x**2 + y**2])


@dataclass(frozen=True)
class ObjectParams:
    """One object's parameters η_o.

    Attributes:
        shape: one of SHAPES.
        mass: [kg], > 0.
        size: box extents (size_x, size_y, size_z) [m], each > 0. A cylinder has
            size_x = size_y = diameter, size_z = height; a sphere all = diameter.
        name: catalogue id, or "" for an ad-hoc object.
        mesh: a mesh file for shape "mesh" (pybullet_data relative or absolute), or "".
    """

    shape: str
    mass: float
    size: tuple[float, float, float]
    name: str = ""
    mesh: str = ""

    def __post_init__(self) -> None:
        shape_code(self.shape, where=f"object {self.name or '(ad hoc)'}")
        if not (math.isfinite(self.mass) and self.mass > 0):
            raise InvalidParameter(
                f"object {self.name or '(ad hoc)'}: mass {self.mass} kg must be > 0"
            )
        if len(self.size) != 3 or not all(math.isfinite(s) and s > 0 for s in self.size):
            raise InvalidParameter(
                f"object {self.name or '(ad hoc)'}: size {self.size} m must be three extents > 0"
            )

    @property
    def code(self) -> int:
        """Shape code (index in SHAPES)."""
        return SHAPES.index(self.shape)

    @property
    def width(self) -> float:
        """Grip width a = size_x [m]."""
        return self.size[0]

    def turned(self) -> ObjectParams:
        """The object as the pads grip it a quarter turn about its vertical axis: sizes x
        and y swapped (its inertia, computed from its sizes, with them)."""
        sx, sy, sz = self.size
        return replace(self, size=(sy, sx, sz))

    @property
    def inertia(self) -> np.ndarray:
        """Principal inertia about the centre of mass [kg m^2], shape (3,)."""
        return inertia_diagonal(self.code, self.mass, np.array(self.size))

    @property
    def area(self) -> float:
        """Mean projected area [m^2]."""
        return float(drag_area(np.array([self.code]), np.array([self.size]))[0])

    @property
    def cd(self) -> float:
        """Drag coefficient."""
        return DRAG_COEFFICIENT[self.shape]
