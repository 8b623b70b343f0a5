"""01 — one throw with the nominal model: where does a 5 cm cube land?

Run: .venv/bin/python examples/01_one_throw.py
"""

import math

from cell.catalogue import get_object
from cell.model import DEFAULT_EE, ThrowBatch, band_state, predict_landing

cube = get_object("cube50")
throw = ThrowBatch.single(
    cube, stroke=0.0625, position=(0.0, 0.0, 0.6), elevation=math.radians(30), azimuth=0.0
)
landing = predict_landing(throw, DEFAULT_EE)
band = band_state(0.0625, cube.width, DEFAULT_EE)
print(
    f"lands at x = {landing.x[0]:.4f} m, y = {landing.y[0]:.4f} m after {landing.t_flight[0]:.4f} s"
)
print(
    f"band stretch {band.stretch:.5f} m, push {band.push:.3f} N, stored energy {band.energy:.3f} J"
)

# Reach falls as the stroke grows (less stretch): the handle the planner turns.
for stroke in (0.03, 0.05, 0.07, 0.09, 0.11):
    b = ThrowBatch.single(
        cube, stroke=stroke, position=(0, 0, 0.6), elevation=math.radians(30), azimuth=0
    )
    print(f"  L_s = {stroke:.2f} m -> reach {predict_landing(b, DEFAULT_EE).x[0]:.3f} m")
