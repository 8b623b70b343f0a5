"""The object catalogue: every entry valid, every mesh present, the thesis sets complete."""

import numpy as np

from cell.catalogue import catalogue, mesh_path, mesh_vertices


def test_sets_have_the_thesis_objects():
    sets = {}
    for e in catalogue().values():
        sets.setdefault(e.set, []).append(e)
    assert len(sets["thesis14"]) == 14
    shapes = {e.params.shape for e in sets["thesis14"]}
    assert shapes == {"cube", "cuboid", "cylinder", "sphere"}
    assert len(sets["fig33"]) == 7
    assert len(sets["unseen"]) == 7
    assert sum(e.params.shape == "mesh" for e in sets["unseen"]) == 5


def test_every_mesh_exists_and_its_extents_match_its_vertices():
    for e in catalogue().values():
        o = e.params
        assert all(s > 0 for s in o.size) and o.mass > 0
        if o.shape == "mesh":
            assert mesh_path(o.mesh).is_file()
            ext = np.ptp(mesh_vertices(o.mesh, e.mesh_scale), axis=0)
            np.testing.assert_allclose(ext, o.size, atol=1e-4)
            assert 0.01 < max(o.size) < 0.2  # graspable by a 2-finger band gripper


def test_golden_objects_are_exact():
    cat = catalogue()
    assert cat["cube50"].params.mass == 0.060
    assert cat["cuboid_c"].params.size == (0.05, 0.05, 0.10)
    assert cat["cyl70"].params.size == (0.07, 0.07, 0.06)
