"""Workflows over the plant: throw campaigns and the scene's calibration.

They drive the cell (`cell.sim`, the PyBullet plant) through the same item loop as a
sort job (`cell.loop`); they are not part of the plant.
"""
