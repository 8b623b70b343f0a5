"""Inputs written by hand, a sixth round: the three loose ends of the fifth (a push model
that diverged for items of a fraction of a gram, a partial parameter file read without a
word, a big job parsed by the Python YAML parser) and inputs of kinds the rounds before
did not try. Each test was seen failing with its fix undone."""

from __future__ import annotations

from dataclasses import fields
from pathlib import Path

import numpy as np
import pytest
import yaml

from cell.errors import InvalidInput, InvalidParameter, JobError, LogFormatError
from cell.jobs import parse_job
from cell.log import read_throws_csv, read_tracks_csv, write_throws_csv
from cell.model.objects import shape_code
from cell.model.params import EndEffectorParams
from cell.model.throw import ThrowBatch, predict_landing, reference_landing
from cell.params import load_params, scene_params_path
from cell.synth import Campaign, default_world, draw_campaign
from tests.cli_exit import cell_exit

ROOT = Path(__file__).resolve().parents[1]


def _light_batch() -> ThrowBatch:
    """Cubes of 25 mm of 0.1-0.5 g thrown at both ends of the stroke range."""
    ee = EndEffectorParams()
    masses = np.array([1e-4, 2e-4, 3e-4, 5e-4] * 2)
    strokes = np.repeat([ee.stroke_min, ee.stroke_max], 4)
    return ThrowBatch.build(
        stroke=strokes,
        position=np.tile([0.0, 0.0, 0.6], (8, 1)),
        elevation=0.6,
        azimuth=0.0,
        shape=shape_code("cube"),
        mass=masses,
        size=[0.025] * 3,
    )


def test_the_push_of_an_item_of_a_fraction_of_a_gram_converges() -> None:
    """Two RK4 steps across the push launched a 0.2 g cube at 1e59 m/s (the drag's
    stiffness times the step past RK4's stability); the push now takes the steps its drag
    needs, and the fast path lands where the reference integrator (0.2 ms steps, drag
    throughout) does."""
    ee = EndEffectorParams()
    batch = _light_batch()
    fast = predict_landing(batch, ee)
    ref = reference_landing(batch, ee)
    speed = np.linalg.norm(fast.launch_velocity, axis=1)
    speed_ref = np.linalg.norm(ref.launch_velocity, axis=1)
    assert np.all(np.isfinite(speed)) and speed.max() < 300.0
    np.testing.assert_allclose(speed, speed_ref, rtol=2e-3)
    reach = np.hypot(fast.x, fast.y)
    np.testing.assert_allclose(reach, np.hypot(ref.x, ref.y), rtol=5e-3)


def test_a_partial_parameter_file_names_every_key_it_takes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A file of two end-effector keys took the reference values for the other twelve
    without a word; a warning now names each, with the value taken. The scene's own file
    (every key) gives none."""
    p = tmp_path / "part.yaml"
    p.write_text("end_effector: {Ke1: 120.0, dt: 0.01}\n")
    mp = load_params(p)
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"cell: warning: {p}: end_effector gives 2")
    ref = EndEffectorParams()
    for f in fields(EndEffectorParams):
        if f.name in ("Ke1", "dt"):
            assert f" {f.name} = " not in err
        else:
            assert f" {f.name} = {getattr(ref, f.name):g}" in err
            assert getattr(mp.ee, f.name) == getattr(ref, f.name)
    scene = scene_params_path()
    assert scene is not None
    load_params(scene)
    assert capsys.readouterr().err == ""


def test_a_job_is_parsed_by_libyaml_and_its_errors_worded_by_pyyaml(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A 30,000-item job took 8.4-8.7 CPU-s to parse with PyYAML's Python parser (twice:
    bounds, then the tree); libyaml now parses it (2.0-2.3 CPU-s), and the Python parser
    reads only a text libyaml refuses, for its wording. Shown here by a Python parser
    that fails on any text: a valid job parses without it, a tab is said as a tab with
    it back."""
    if getattr(yaml, "CSafeLoader", None) is None:
        pytest.skip("PyYAML built without libyaml")
    text = (ROOT / "tasks" / "bins.yaml").read_text()
    parse_job(text, "bins.yaml", check_reach=False)  # the shipped catalogue read first

    class Broken(yaml.SafeLoader):
        def __init__(self, stream: str) -> None:
            raise AssertionError("the Python parser read a valid text")

    with monkeypatch.context() as m:
        m.setattr(yaml, "SafeLoader", Broken)
        job = parse_job(text, "bins.yaml", check_reach=False)
    assert job.items
    bad = text.replace("\n  - ", "\n\t- ", 1)
    with pytest.raises(JobError, match=r"bins.yaml, line \d+, column 1: not valid YAML: a tab"):
        parse_job(bad, "bins.yaml", check_reach=False)
    with pytest.raises(InvalidInput, match="a tab; YAML indents with spaces"):
        from cell.yamlsafe import safe_load

        safe_load("a:\n\tb: 1\n", "p.yaml")


JOB = """\
cell: {robot: panda}
pick_station: {position_m: [0.45, -0.40, 0.20]}
bins:
  - {id: near, position_m: [0.55, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.12}
  - FAR
items:
  - ITEM
"""
FAR = "{id: far, position_m: [1.50, 0.00], size_m: [0.30, 0.30], rim_height_m: 0.15}"
ITEM = "{object: cube50, bin: far}"


def _job(far: str = FAR, item: str = ITEM) -> str:
    return JOB.replace("FAR", far).replace("ITEM", item)


def test_bins_whose_walls_meet_are_refused_as_such() -> None:
    """Bins 15 mm apart were accepted: their walls (10 mm each, outside the inner size)
    stand in each other in the scene. Bins that only touch (0.85 - 0.55 < 0.3 in floating
    point) were refused as overlapping; both are now refused for their walls; 25 mm apart
    is accepted."""
    for x in ("0.865", "0.85"):
        far = f"{{id: far, position_m: [{x}, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.15}}"
        with pytest.raises(JobError, match="the walls of bin 'far' meet those of bin 'near'"):
            parse_job(_job(far), "j.yaml", check_reach=False)
    far = "{id: far, position_m: [0.875, 0.35], size_m: [0.30, 0.30], rim_height_m: 0.15}"
    assert parse_job(_job(far), "j.yaml", check_reach=False).bins[1].id == "far"


def test_a_bins_distance_from_the_base_is_its_nearest_wall() -> None:
    """The base clearance took the bin's centre less its half-diagonal: a 0.30 m bin 0.45 m
    out (its wall 0.29 m from the base) was refused as reaching "within 0.24 m", one at
    0.20 m (its wall 0.04 m away) as "within 0.00 m"."""
    near = "{id: near, position_m: [0.55, 0.35]"
    text = _job().replace(near, "{id: near, position_m: [0.45, 0.0]")
    assert parse_job(text, "j.yaml", check_reach=False).bins[0].position == (0.45, 0.0)
    text = _job().replace(near, "{id: near, position_m: [0.20, 0.0]")
    with pytest.raises(JobError, match="the bin's nearest wall is 0.040 m from the robot base"):
        parse_job(text, "j.yaml", check_reach=False)


def test_a_bin_sent_more_than_it_holds_is_warned_of() -> None:
    """200 cube50s to a 0.10 x 0.10 m bin with a 0.05 m rim were accepted without a word;
    their boxes take 62.5 times its inside. A warning says so; six fit the shipped
    demo's bins and give none."""
    far = "{id: far, position_m: [1.50, 0.00], size_m: [0.10, 0.10], rim_height_m: 0.05}"
    item = "{object: cube50, bin: far, count: 200}"
    job = parse_job(_job(far, item), "j.yaml", check_reach=False)
    (w,) = [w for w in job.warnings if "m³" in w]
    assert "bin 'far' is sent 200 items" in w and "62.5 times" in w
    job = parse_job(_job(item="{object: cube50, bin: far, count: 6}"), "j.yaml", check_reach=False)
    assert not [w for w in job.warnings if "m³" in w]


def test_a_decimal_comma_is_said_as_such() -> None:
    """`mass_kg: 0,05` in a flow mapping is mass_kg 0 and a key '05': it was refused as
    "unknown key '05'" alone."""
    item = "{shape: cube, mass_kg: 0,05, size_m: [0.03, 0.03, 0.03], bin: far}"
    with pytest.raises(JobError, match=r"items\[0\].05: unknown key '05' \(a decimal comma\?"):
        parse_job(_job(item=item), "j.yaml", check_reach=False)


@pytest.mark.parametrize(
    ("encoding", "said"),
    [
        ("utf-32", "UTF-32"),
        ("utf-16-be", r"UTF-16 \(big-endian, without a byte-order mark\)"),
        ("utf-16-le", r"UTF-16 \(little-endian, without a byte-order mark\)"),
    ],
)
def test_a_log_in_utf16_without_its_mark_or_utf32_is_named(
    tmp_path: Path, encoding: str, said: str
) -> None:
    """UTF-32 was called UTF-16 (its mark begins with UTF-16's); UTF-16 without a mark
    reads as UTF-8 with a NUL in every other byte, refused as "required column missing".
    The tracks reader the same."""
    log = tmp_path / "ok.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=12), seed=3), log)
    bad = tmp_path / "bad.csv"
    bad.write_bytes(log.read_text().encode(encoding))
    with pytest.raises(LogFormatError, match=f"bad.csv: is not a readable CSV text file: {said}"):
        read_throws_csv(bad)
    bad.write_bytes("throw_id,t_s,x_m,y_m,z_m\nt1,0.0,0,0,1\n".encode(encoding))
    with pytest.raises(LogFormatError, match=said):
        read_tracks_csv(bad)


def test_a_track_whose_samples_share_one_time_says_so() -> None:
    """A track of 60 samples all at t = 0.05 s (a time column copied down) was set aside
    as "too short: 1 sample"; the repeated stamps are now said."""
    from cell.gap.track_check import check_track

    t = np.linspace(0.0, 0.6, 60)
    track = np.c_[np.full(60, 0.05), t, 0.0 * t, 1.0 + 2.0 * t - 4.9 * t * t]
    why = check_track(track).why
    assert why is not None and why.startswith("too short: 1 sample")
    assert "59 of its 60 samples were dropped for repeating a time stamp" in why


ELBOW_LIMIT = '<limit effort="150.0" lower="-3.14159265359" upper="3.14159265359" velocity="3.15"/>'


@pytest.mark.parametrize(
    ("old", "new", "said"),
    [
        ("</robot>", '<joint name="j2" type="fixed"><parent link="wrist_3_link"/>'
         '<child link="shoulder_link"/></joint></robot>',
         "link 'shoulder_link' is the child of two joints, 'shoulder_pan_joint' and 'j2'"),
        ("</robot>", '<joint name="loop" type="fixed"><parent link="tool0"/>'
         '<child link="world"/></joint></robot>',
         "its joints form a loop through link 'tool0'"),
        (ELBOW_LIMIT, "", "joint 'elbow_joint' \\(revolute\\) has no <limit>"),
        (ELBOW_LIMIT, ELBOW_LIMIT.replace(' velocity="3.15"', ""), "its <limit> has no velocity"),
        (ELBOW_LIMIT, ELBOW_LIMIT.replace('lower="-3.14159265359"', 'lower="-pi"'),
         "its <limit> lower='-pi' is not a number"),
        (ELBOW_LIMIT, ELBOW_LIMIT.replace("-3.14159265359", "9"), "the wrong way round"),
        (ELBOW_LIMIT, ELBOW_LIMIT.replace('velocity="3.15"', 'velocity="0"'),
         "its velocity limit 0.0 must be > 0"),
    ],
)  # fmt: skip
def test_an_arm_urdf_that_is_no_tree_or_has_no_limits_is_named(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, old: str, new: str, said: str
) -> None:
    """A UR5 URDF (in a copy of example-robot-data, `$CELL_EXAMPLE_ROBOT_DATA`) with a link
    under two joints or joints in a loop was refused listing a chain of 1,000 joints; an
    elbow without <limit> or without its velocity passed the mount's checks and ended in
    Pinocchio's traceback ("does not contain a valid URDF model") when the job was
    parsed; limits the wrong way round or 'nan' were said as a home outside "[3.14,
    -3.14]" or "[nan, 3.14]". Each is now refused by the joint and what it needs."""
    from cell.robot.mount import check_against_urdf, load_mount
    from cell.robot.paths import example_robot_data_dir

    erd = example_robot_data_dir()
    copy = tmp_path / "erd"
    copy.mkdir()
    for d in erd.iterdir():
        (copy / d.name).symlink_to(d)
    (copy / "ur_description").unlink()
    (copy / "ur_description" / "urdf").mkdir(parents=True)
    src = (erd / "ur_description" / "urdf" / "ur5_robot.urdf").read_text()
    assert src.count(old) == 1
    (copy / "ur_description" / "urdf" / "ur5_bad.urdf").write_text(src.replace(old, new))
    mount = (ROOT / "robots" / "ur5_throwing" / "mount.yaml").read_text()
    (tmp_path / "m.yaml").write_text(
        mount.replace("ur5_robot.urdf", "ur5_bad.urdf").replace("arm: ur5", "arm: ur5bad")
    )
    monkeypatch.setenv("CELL_EXAMPLE_ROBOT_DATA", str(copy))
    example_robot_data_dir.cache_clear()
    try:
        with pytest.raises(InvalidParameter, match=f"m.yaml: field 'arm_urdf': .*{said}"):
            check_against_urdf(load_mount(str(tmp_path / "m.yaml")))
    finally:
        monkeypatch.undo()
        example_robot_data_dir.cache_clear()


def test_an_empty_output_path_is_refused_before_the_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`cell predict LOG -o ""` (an unset shell variable) predicted every throw, then
    failed writing "": "cell: error: .tmp: No such file or directory"."""
    log = tmp_path / "ok.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=12), seed=3), log)
    assert cell_exit(["predict", str(log), "-o", ""]) == 2
    assert "cell: error: -o '': an empty path; give a file name" in capsys.readouterr().err


def test_a_thrown_item_lighter_than_the_calibrated_objects_is_warned_of() -> None:
    """A 0.2 g cube of 25 mm thrown 1.5 m was planned without a word and missed by 0.75 m
    (2 g: 0.24 m; 20 g: 0.04 m): the throw model is calibrated on the catalogue, 20 g and
    up. Thrown, it is now warned of by line; placed (`policy: place`), not."""
    item = "{shape: cube, mass_kg: 0.0002, size_m: [0.025, 0.025, 0.025], bin: far}"
    job = parse_job(_job(item=item), "j.yaml", check_reach=False)
    (w,) = [w for w in job.warnings if "calibrated on" in w]
    assert w.startswith("j.yaml, line 7, mass_kg: 0.0002 kg is lighter than the lightest")
    assert "(cube30, 0.02 kg)" in w
    job = parse_job(_job(item=item) + "policy: place\n", "j.yaml", check_reach=False)
    assert not [w for w in job.warnings if "calibrated on" in w]
    job = parse_job(_job(), "j.yaml", check_reach=False)
    assert not [w for w in job.warnings if "calibrated on" in w]


@pytest.mark.parametrize(
    ("item", "said"),
    [
        ('{shape: cube, mass_kg: "50 g", size_m: [0.03, 0.03, 0.03], bin: far}',
         r"mass_kg: '50 g' must be a number \(a number with a unit: the unit is the key's"),
        ('{shape: cube, mass_kg: 0.05, size_m: ["30 mm", 0.03, 0.03], bin: far}',
         r"size_m\[0\]: '30 mm' must be a number \(a number with a unit"),
        ('{shape: cube, mass_kg: "0.05", size_m: [0.03, 0.03, 0.03], bin: far}',
         r"'0.05' must be a number \(it is in quotes, so YAML reads it as text"),
        ('{object: cube50, bin: far, count: "3"}', r"count: '3' must be a whole number .* quotes"),
        ("{shape: cube, mass_kg: .inf, size_m: [0.03, 0.03, 0.03], bin: far}",
         "mass_kg: inf must be a finite number"),
        ("{shape: cube, mass_kg: 0.05, size_m: [30, 30, 30], bin: far}",
         r"is it \[0.03, 0.03, 0.03\] m written in millimetres\?"),
        ("{object: cube50, bin: 7}", "items\\[0\\].bin: 7 is a number; this is a name: write it "
         "in quotes, '7'"),
    ],
)  # fmt: skip
def test_a_number_written_as_text_or_a_name_as_a_number_is_said_so(item: str, said: str) -> None:
    """'50 g', '30 mm' and "0.05" were "must be a number" alone; .inf "inf must be a number";
    extents in millimetres "do not fit the grip" without a word of the unit; a bin named 7
    "7 must be a non-empty text"."""
    with pytest.raises(JobError, match=said):
        parse_job(_job(item=item), "j.yaml", check_reach=False)


def test_a_track_id_padded_or_with_an_invisible_character(tmp_path: Path) -> None:
    """Track ids written `t1 ` (a spreadsheet's padding) matched no throw of the log, whose
    own cells are read stripped: every track "no throw with this id" and `cell gap`
    refused the log. They are now read stripped too. An id holding a zero-width space
    was said as "t1​: no throw with this id", the character unseen: now it is named."""
    from cell.gap.track_check import check_tracks

    t = np.linspace(0.0, 0.6, 40)
    rows = "".join(f"t1 ,{x:.3f},{0.5 * x:.3f},0.0,{1.0 + 2.0 * x - 4.9 * x * x:.4f}\n" for x in t)
    f = tmp_path / "tracks.csv"
    f.write_text("throw_id,t_s,x_m,y_m,z_m\n" + rows)
    tracks = read_tracks_csv(f)
    assert list(tracks) == ["t1"]
    usable, bad, _ = check_tracks(["t1"], tracks)
    assert list(usable) == ["t1"] and not bad
    usable, bad, _ = check_tracks(["t1"], {"t1\u200b": tracks["t1"]})
    assert not usable and bad[0]["throw_id"] == "t1<U+200B>"
    assert "U+200B ZERO WIDTH SPACE" in bad[0]["why"]


def test_a_log_cell_with_a_decimal_comma_or_a_unit_says_so(tmp_path: Path) -> None:
    """A quoted '0,06' or '60 g' in `mass_kg` was "is not a number" alone."""
    log = tmp_path / "ok.csv"
    write_throws_csv(draw_campaign(default_world(), Campaign(n=12), seed=3), log)
    head, *rows = log.read_text().splitlines()
    col = head.split(",").index("mass_kg")
    for cell, said in (('"0,06"', "decimal point: 0.06"), ("60 g", "a number with a unit")):
        cells = rows[2].split(",")
        cells[col] = cell
        bad = tmp_path / "bad.csv"
        bad.write_text("\n".join([head, rows[0], rows[1], ",".join(cells)]) + "\n")
        with pytest.raises(LogFormatError, match=f"row 3, column 'mass_kg': .*{said}"):
            read_throws_csv(bad)
