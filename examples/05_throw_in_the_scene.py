"""05 — a throw in the PyBullet cell: the launch comes out of the band's physics, and the
calibrated model predicts where the item lands.

Run: .venv/bin/python examples/05_throw_in_the_scene.py
"""

import math

from cell.catalogue import get_object
from cell.endeffector.pybullet_backend import PyBulletEndEffector
from cell.model import ThrowBatch, predict_landing
from cell.params import load_params, scene_params_path
from cell.sim import BinSpec, CellScene
from cell.workflows.campaign import throw_once

params = load_params(scene_params_path())
with CellScene(None, [BinSpec("bin", (0.0, 1.5), (0.3, 0.3), 0.15)]) as scene:
    ee = PyBulletEndEffector(scene)
    row = throw_once(
        scene,
        ee,
        "cube50",
        stroke=0.07,
        position=(0, 0, 0.8),
        elevation=math.radians(35),
        land_z=0.1,
    )
obj = params.objects.get("cube50", get_object("cube50"))
pred = predict_landing(
    ThrowBatch.single(
        obj, stroke=0.07, position=(0, 0, 0.8), elevation=math.radians(35), azimuth=0, land_z=0.1
    ),
    params.ee,
)
print(
    f"scene: ({row['landed_x_m']:.3f}, {row['landed_y_m']:.3f}) m; "
    f"calibrated model: ({pred.x[0]:.3f}, {pred.y[0]:.3f}) m"
)
