"""Job texts several tests share."""

NEAR_AND_FAR = """
cell: {robot: panda}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - {id: far, position_m: [1.40, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}
items:
  - {%s}
seed: 0
"""
"""The Panda, the demo's pick station, a bin in place reach (`near`, 0.63 m out) and one a
throw reaches (`far`, 1.40 m out), and one item line: `NEAR_AND_FAR % "object: cube50, bin:
far"`."""
