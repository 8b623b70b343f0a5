"""The composite grip cloud, its descriptors and the feature vectors."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cell.catalogue import catalogue, get_object
from cell.errors import InvalidInput, LogFormatError
from cell.log import ThrowTable
from cell.model import DEFAULT_EE, ObjectParams
from cell.residual.cloud import (
    DESCRIPTOR_NAMES,
    ObjectGeometry,
    composite_cloud,
    read_obj_mesh,
    sample_surface,
    shape_descriptors,
)
from cell.residual.features import (
    FEATURE_NAMES,
    GripPose,
    feature_matrix,
    geometry_of,
    table_features,
)


def _d(geom: ObjectGeometry, name: str) -> float:
    return float(shape_descriptors(geom)[DESCRIPTOR_NAMES.index(name)])


def test_surface_samples_lie_on_the_primitive_surfaces():
    box = sample_surface(ObjectGeometry("cuboid", (0.03, 0.05, 0.08)))
    on_face = np.isclose(np.abs(box), np.array([0.015, 0.025, 0.04]), atol=1e-12).any(axis=1)
    assert on_face.all() and np.all(np.abs(box) <= np.array([0.015, 0.025, 0.04]) + 1e-12)
    sph = sample_surface(ObjectGeometry("sphere", (0.06, 0.06, 0.06)))
    np.testing.assert_allclose(np.linalg.norm(sph, axis=1), 0.03, atol=1e-12)
    cyl = sample_surface(ObjectGeometry("cylinder", (0.04, 0.04, 0.07)))
    r = np.hypot(cyl[:, 0], cyl[:, 1])
    side = np.isclose(r, 0.02, atol=1e-12)
    cap = np.isclose(np.abs(cyl[:, 2]), 0.035, atol=1e-12) & (r <= 0.02 + 1e-12)
    assert np.all(side | cap)
    # area-weighted: the side of a cylinder takes 2πrh / (2πrh + 2πr²) of the samples
    assert abs(side.mean() - 0.07 / (0.07 + 0.02)) < 0.04


@pytest.mark.parametrize(
    "shape, fill",
    [("cube", 1.0), ("cylinder", math.pi / 4), ("sphere", math.pi / 6)],
)
def test_hull_fill_matches_the_closed_form(shape, fill):
    assert _d(ObjectGeometry(shape, (0.05, 0.05, 0.05)), "pc_hull_fill") == pytest.approx(
        fill, rel=0.03
    )


def test_a_flat_rear_takes_no_extra_band_and_a_round_one_does():
    assert _d(ObjectGeometry("cube", (0.05, 0.05, 0.05)), "pc_wrap_excess") == pytest.approx(
        0, abs=1e-9
    )
    assert _d(ObjectGeometry("cylinder", (0.05, 0.05, 0.07)), "pc_wrap_excess") == pytest.approx(
        0, abs=1e-9
    )
    sphere = _d(ObjectGeometry("sphere", (0.05, 0.05, 0.05)), "pc_wrap_excess")
    assert 0.1 < sphere < math.pi / 2 - 1  # below the full half circle's excess


def test_descriptors_are_seeded_scale_consistent_and_follow_the_grip_yaw():
    g = ObjectGeometry("cuboid", (0.03, 0.05, 0.06))
    np.testing.assert_array_equal(shape_descriptors(g), shape_descriptors(g))
    big = ObjectGeometry("cuboid", (0.06, 0.10, 0.12))
    dims = [i for i, n in enumerate(DESCRIPTOR_NAMES) if n.endswith("_m")]
    np.testing.assert_allclose(
        shape_descriptors(big)[dims], 2 * shape_descriptors(g)[dims], rtol=1e-9
    )
    turned = ObjectGeometry("cuboid", (0.03, 0.05, 0.06), grip_yaw=math.pi / 2)
    ext = shape_descriptors(turned)[:3]
    np.testing.assert_allclose(ext, [0.05, 0.03, 0.06], atol=1e-9)


def test_composite_cloud_has_object_pads_and_band():
    comp = composite_cloud(ObjectGeometry("cube", (0.05, 0.05, 0.05)))
    parts = set(np.unique(comp[:, 3]).tolist())
    assert parts == {0.0, 1.0, 2.0}
    pads = comp[comp[:, 3] == 1, :3]
    assert np.all(np.abs(np.abs(pads[:, 0]) - 0.025) <= 0.0025 + 1e-12)
    band = comp[comp[:, 3] == 2, :3]
    np.testing.assert_allclose(band[:, 2], -0.025, atol=1e-12)  # on the cube's rear face


def test_mesh_objects_are_sampled_from_their_faces(tmp_path):
    obj = tmp_path / "tet.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2/1 3/1 4/1\n")
    v, f = read_obj_mesh(obj)
    assert v.shape == (4, 3) and f.shape == (4, 3)
    o = ObjectParams("mesh", 0.05, (0.02, 0.02, 0.02), mesh=str(obj))
    g = geometry_of(o)
    pts = sample_surface(g)
    # scaled to the box extents and centred: every sample on one of the four planes
    p = pts + 0.01
    on = np.isclose(p, 0, atol=1e-12).any(axis=1) | np.isclose(p.sum(axis=1), 0.02, atol=1e-12)
    assert on.all()
    # tetrahedron / its box = 1/6; the samples miss the sharp corners, which shrinks the
    # sampled box a little more than the hull
    assert _d(g, "pc_hull_fill") == pytest.approx(1 / 6, abs=0.03)


def test_catalogue_meshes_give_finite_descriptors():
    for oid, e in catalogue().items():
        if e.params.shape == "mesh":
            d = shape_descriptors(geometry_of(e.params))
            assert np.all(np.isfinite(d)), oid
            assert d[DESCRIPTOR_NAMES.index("pc_hull_fill")] < 0.9, oid


def test_a_mesh_object_without_its_mesh_is_an_error():
    with pytest.raises(InvalidInput, match="mesh file"):
        geometry_of(ObjectParams("mesh", 0.05, (0.03, 0.03, 0.03)))


def _row(**kw):
    r = dict(
        throw_id="t1",
        object_id="cube50",
        shape="cube",
        mass_kg=0.06,
        size_x_m=0.05,
        size_y_m=0.05,
        size_z_m=0.05,
        stroke_m=0.06,
        x_m=0.0,
        y_m=0.0,
        z_m=0.6,
        elevation_rad=0.5,
        azimuth_rad=0.0,
        roll_rad=0.0,
        vx_mps=0.0,
        vy_mps=0.0,
        vz_mps=0.0,
        platform="arm",
        rotor_rpm=0.0,
        land_z_m=0.0,
        landed_x_m=1.2,
        landed_y_m=0.0,
    )
    r.update(kw)
    return r


def test_feature_rows_of_a_log_match_the_per_object_features():
    duck = get_object("duck")
    rows = [
        _row(),
        _row(
            throw_id="t2",
            object_id="duck",
            shape="mesh",
            mass_kg=duck.mass,
            size_x_m=duck.size[0],
            size_y_m=duck.size[1],
            size_z_m=duck.size[2],
        ),
    ]
    table = ThrowTable.from_records(rows, path="x.csv")
    x = table_features(table, np.array([0.06, 0.07]), DEFAULT_EE)
    assert x.shape == (2, len(FEATURE_NAMES)) and np.all(np.isfinite(x))
    ref = feature_matrix(
        [get_object("cube50"), duck], [GripPose(0.06, 0.5), GripPose(0.07, 0.5)], DEFAULT_EE
    )
    np.testing.assert_allclose(x, ref)
    assert x[1, FEATURE_NAMES.index("shape_mesh")] == 1.0


def test_an_unknown_mesh_row_names_the_row():
    rows = [_row(), _row(throw_id="t2", object_id="blob", shape="mesh", mesh="nowhere/blob.obj")]
    table = ThrowTable.from_records(rows, path="log.csv")
    with pytest.raises(LogFormatError, match=r"log.csv, row 2, column 'mesh'"):
        table_features(table, np.array([0.06, 0.06]), DEFAULT_EE)
