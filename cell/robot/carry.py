"""Carrying an item without letting it slip: the grip's limit on the arm's motion.

The pads hold an item of mass m with a friction force of at most F = 2 μ f_g(L_s, a)
(`cell.model.grip`). In the end-effector's frame the item feels the specific force
f = a_c − g, a_c the acceleration of its centre of mass c in the world frame W and g
gravity (0, 0, −9.81) m/s²; it stays put while m |f| ≤ F. So the grip sets a bound
on |a_c − g| [m/s²], the same for every direction (the pads' normal direction is
held by the band, the two in-plane directions by friction: bounding the magnitude is
the conservative union).

The pads also hold the item against turning about their common normal (x): each
pad's contact patch resists a torque of at most μ f_g r_t (r_t the patch's torsional
radius, the mean distance of its points from its centre), two pads 2 μ f_g r_t. The
carry asks for τ_x = m (r × f)_x + I_xx α_x about the patch centre, r the centre of
mass seen from it (a tall item's centre of mass sits above the short pads). While the
item is pressed onto the carriage (f_z > 0 in the grip's axes: the throw axis tilted
up) its base face rights it as well, with up to m f_z times half its base. A carry
is within the grip while its use of the force and of the torque together stays under
1: m |f| / F + |τ_x| / T ≤ 1/margin (each used fraction takes from the same friction).

A tall item is also tilted about y (the pads' faces' other axis) by the specific force
along the pads' normal: τ_y = m (r × f)_y + I_yy α_y = m l f_x + I_yy α_y (l the lever).
The pads resist the tilt with their pressure (each pad's normal force f_g may move to
its patch's edge, ±L_p/2: f_g L_p for both) and with their friction along the throw
axis (μ f_g on each, w apart: F w / 2): T_y = F (L_p / (2 μ) + w / 2)
(`cell.orchestrator.carry_hold`), plus m f_z w / 2 while the item is pressed onto the
carriage. Measured in the scene (`cell.sim.grip_probe`, tests/test_grip_probe.py), a
torque about y turns boxes and cylinders at 1.02-1.23 T_y. The tilt's use is not
friction's alone (the pressure takes most of it), so it adds to the rest in quadrature:
use = √((m |f| / F + |τ_x| / T)² + (|τ_y| / T_y)²) (`uses`). Measured: pushed along x
at the centre of mass, the 200 mm bottle, a tetrapack and a 100 mm cuboid slid where
that use was 0.96-1.10 (the bottle: 0.49 by m |f| / F alone), nine boxes and cylinders
where it was up to 1.8; the linear sum of the three said 1.34-2.41. A spherical or mesh
item has no T_y (held at points) and keeps the first law.

Where the tilt is counted: held still (`static_grip_use`; the arm's release elevation
and swing route, `cell.arm.grip_limits.release_grip_use`), and in the carry's time
scaling only where it binds (`plan_carry`): a carry is timed within 1/margin of the
force-and-twist use, and where it then asks more than the pads hold with the tilt
(`tilt_use` over TILT_SLOWS_OVER), it is timed again keeping its use with the tilt
(`carry_use`) within 1/margin or, where the path held still already asks more (a level
swing past the horizontal with a tall item's weight on a pad, which the routes check),
within what it asks there. Counted against 1/margin alone, the demo's cuboid_b's level
swing went at GENTLE_SCALE (1,505 -> 1,399 items per hour); counted in every carry's
timing, it slowed carries the pads held and changed the routes timed by them (the merge
reverted at cf2d90b); left out, carries that asked 0.73 without the tilt and 1.23 with
it dropped their items (issue 59).

`plan_carry` finds the fastest toppra path through the waypoints whose use of the
grip stays under that bound, evaluating a_c exactly from the joint state with Pinocchio
(a_c = a_o + α × r + ω × (ω × r), o the grip centre). Two ways, the sooner is taken:
- a uniform slow-down: it time-scales the path (velocity limits × √s, acceleration
  limits × s, so that every acceleration scales by s, centripetal terms included) by
  bisection on s;
- the path shaped by the grip: toppra with the grip's bound as a second-order path
  constraint (`grip_constraint`, a polytope inside the bound), which slows the path only
  where the grip asks it. A tall box hung from the pads and carried sideways: 1.11 s
  against 1.36 s uniformly slowed (tests/test_carry.py).

The grip's laws are in `cell.robot.grip_hold`, the toppra constraint in
`cell.robot.grip_constraint`, `plan_carry` in `cell.robot.carry_plan`; this module
re-exports their names.
"""

from __future__ import annotations

from cell.robot.carry_plan import _Dilated as _Dilated
from cell.robot.carry_plan import plan_carry
from cell.robot.grip_constraint import grip_constraint
from cell.robot.grip_hold import (
    CARRY_MARGIN,
    GENTLE_SCALE,
    GripHold,
    grip_use,
    item_accelerations,
    item_motion,
    patch_torsion_radius_m,
    peak_specific_force,
    static_grip_use,
    uses,
)
from cell.robot.grip_hold import _sphere_directions as _sphere_directions

__all__ = [
    "CARRY_MARGIN",
    "GENTLE_SCALE",
    "GripHold",
    "grip_constraint",
    "grip_use",
    "item_accelerations",
    "item_motion",
    "patch_torsion_radius_m",
    "peak_specific_force",
    "plan_carry",
    "static_grip_use",
    "uses",
]
