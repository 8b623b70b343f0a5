"""The throwing end-effector as a PyBullet multibody (its URDF, generated).

End-effector frame E (the base link `ee_base`): origin on the base plate's
front face, +z the throw axis (the approach axis u of MODEL.md), x across the
band (the grip width), y completing a right-handed frame.

Links and joints (names shared with `robots/throwing_ee`):

* `ee_base`: the housing and base plate (mount side at z < 0).
* `ee_band` on the prismatic `ee_band_joint` along +z: the band carriage (the
  hoop and the moving part of the band, mass `BAND_MASS_KG`). Its joint value
  is the position of the carriage face, i.e. the stroke L_s [m]. The band force
  law drives it (cell.sim.band); its upper joint limit is the end stop where
  the rope that ties the hoop catches it once the band is slack.
* `ee_finger_left` / `ee_finger_right` on the prismatic
  `ee_finger_left_joint` / `ee_finger_right_joint`, riding on the carriage:
  pads that close on the item across x. Joint value = distance of the pad's
  inner face from the throw axis [m].

The item sits on the carriage face between the pads, its centre of mass at
z = L_s + size_z/2 in E.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

__all__ = ["EEGeometry", "DEFAULT_GEOMETRY", "ee_urdf_text", "write_ee_urdf"]


@dataclass(frozen=True)
class EEGeometry:
    """Dimensions and masses of the simulated end-effector (SI).

    Attributes:
        band_mass_kg: moving mass of the carriage (hoop plus band) [kg].
        finger_mass_kg: mass of each finger pad [kg] (moves with the carriage).
        base_mass_kg: mass of the housing [kg].
        carriage_half_xy_m: half side of the carriage plate [m].
        carriage_thickness_m: carriage plate thickness [m].
        pad_length_m: finger pad length along the throw axis [m]: no longer than the
            shortest catalogue box (0.03 m), so that a placed item touches down before
            the pads; the largest sphere (0.07 m) is then held 5 mm below its equator,
            where friction still holds it.
        pad_thickness_m: finger pad thickness across x [m].
        pad_half_width_m: half width of a pad along y [m].
        finger_open_m: widest pad opening from the axis [m].
        end_stop_m: carriage position where the rope catches it [m].
        stroke_lower_m: lowest carriage position [m].
        pad_friction: Coulomb friction of the pads (latex band on plastic).
    """

    band_mass_kg: float = 0.008
    finger_mass_kg: float = 0.002
    base_mass_kg: float = 0.6
    carriage_half_xy_m: float = 0.02
    carriage_thickness_m: float = 0.004
    pad_length_m: float = 0.03
    pad_thickness_m: float = 0.004
    pad_half_width_m: float = 0.012
    finger_open_m: float = 0.06
    end_stop_m: float = 0.138
    stroke_lower_m: float = 0.02
    pad_friction: float = 1.2

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


DEFAULT_GEOMETRY = EEGeometry()


def _box_inertia(m: float, x: float, y: float, z: float) -> str:
    ixx = m / 12 * (y * y + z * z)
    iyy = m / 12 * (x * x + z * z)
    izz = m / 12 * (x * x + y * y)
    return f'<inertia ixx="{ixx:.3e}" iyy="{iyy:.3e}" izz="{izz:.3e}" ixy="0" ixz="0" iyz="0"/>'


def _link(name: str, m: float, size: tuple[float, float, float], xyz: tuple, rgba: str) -> str:
    # The inertial frame stays at the link frame so that PyBullet's base and
    # constraint frames (which are inertial frames) coincide with the URDF frames.
    sx, sy, sz = size
    o = f'<origin xyz="{xyz[0]:.5f} {xyz[1]:.5f} {xyz[2]:.5f}"/>'
    box = f'<geometry><box size="{sx:.5f} {sy:.5f} {sz:.5f}"/></geometry>'
    return (
        f'<link name="{name}"><inertial><origin xyz="0 0 0"/><mass value="{m}"/>{_box_inertia(m, sx, sy, sz)}'
        f"</inertial><visual>{o}{box}<material name='{name}_m'><color rgba='{rgba}'/>"
        f"</material></visual><collision>{o}{box}</collision></link>"
    )


def ee_urdf_text(geo: EEGeometry = DEFAULT_GEOMETRY) -> str:
    """The end-effector's URDF as text."""
    g = geo
    c = g.carriage_half_xy_m
    t = g.carriage_thickness_m
    housing = _link("ee_base", g.base_mass_kg, (0.08, 0.06, 0.03), (0, 0, -0.015), "0.2 0.2 0.25 1")
    carriage = _link(
        "ee_band", g.band_mass_kg, (2 * c, 2 * c, t), (0, 0, -t / 2), "0.85 0.55 0.1 1"
    )
    pad = (g.pad_thickness_m, 2 * g.pad_half_width_m, g.pad_length_m)
    left = _link(
        "ee_finger_left",
        g.finger_mass_kg,
        pad,
        (-g.pad_thickness_m / 2, 0, g.pad_length_m / 2),
        "0.6 0.6 0.65 1",
    )
    right = _link(
        "ee_finger_right",
        g.finger_mass_kg,
        pad,
        (g.pad_thickness_m / 2, 0, g.pad_length_m / 2),
        "0.6 0.6 0.65 1",
    )

    def joint(name: str, parent: str, child: str, axis: str, lo: float, hi: float) -> str:
        return (
            f'<joint name="{name}" type="prismatic"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="0 0 0"/><axis xyz="{axis}"/>'
            f'<limit lower="{lo}" upper="{hi}" effort="1000" velocity="100"/>'
            f'<dynamics damping="0" friction="0"/></joint>'
        )

    joints = (
        joint("ee_band_joint", "ee_base", "ee_band", "0 0 1", g.stroke_lower_m, g.end_stop_m)
        + joint("ee_finger_left_joint", "ee_band", "ee_finger_left", "-1 0 0", 0.0, g.finger_open_m)
        + joint(
            "ee_finger_right_joint", "ee_band", "ee_finger_right", "1 0 0", 0.0, g.finger_open_m
        )
    )
    return (
        f'<?xml version="1.0"?><robot name="throwing_ee">{housing}{carriage}{left}{right}'
        f"{joints}</robot>"
    )


def write_ee_urdf(geo: EEGeometry = DEFAULT_GEOMETRY, folder: str | Path | None = None) -> Path:
    """Write the URDF to a file (in a temporary folder by default) and return its path."""
    d = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix="cell_ee_"))
    path = d / "throwing_ee_sim.urdf"
    path.write_text(ee_urdf_text(geo))
    return path
