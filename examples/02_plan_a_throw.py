"""02 — throw optimisation: a target in, the release pose and stroke out, checked by the model.

Run: .venv/bin/python examples/02_plan_a_throw.py
"""

from cell.catalogue import get_object
from cell.model import DEFAULT_EE, predict_landing
from cell.optimize.plan import plan_throw

obj = get_object("cyl50")
target = (1.8, 0.6, 0.15)  # a bin centre at its rim height [m, W]
for method in ("fast", "nlp"):
    plan = plan_throw(obj, target, DEFAULT_EE, method=method)
    check = predict_landing(plan.to_batch(obj), DEFAULT_EE)
    print(
        f"{method:4s}: release ({plan.x_m:.3f}, {plan.y_m:.3f}, {plan.z_m:.3f}) m, "
        f"elevation {plan.elevation_rad:.3f} rad, azimuth {plan.azimuth_rad:.3f} rad, "
        f"L_s {plan.stroke_m:.4f} m, energy {plan.energy_j:.3f} J -> lands "
        f"({check.x[0]:.4f}, {check.y[0]:.4f}) m, miss {plan.miss_m * 1000:.3f} mm"
    )
