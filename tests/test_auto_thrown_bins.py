"""`policy: auto` throws into a bin within `limits.place_reach_m` that the arm cannot place
into: decided once, when the job loads, from the job check's inverse kinematics of the place
(`cell.jobcheck.job_problems` -> `Job.thrown_bins`), and read alike by the run's decision
(`cell.jobbins.places`), its check that every item can be sorted (`cell.arm.launch`) and the
random jobs (`cell.jobgen`).

The bins (Panda, the default pick station): `high`, 0.75 m out with its rim 0.80 m up, whose
place the Panda's grip pointing down misses by about 120 mm (the grip does not point down that
high), and which a throw reaches; `tower`, 0.60 m out with its rim 1.00 m up, which neither a
place nor a throw reaches (the throw's release box ends 0.20 m short of it).
"""

from __future__ import annotations

import pytest

from cell.errors import JobError
from cell.jobs import Job, parse_job
from cell.orchestrator import Orchestrator

HIGH = "{id: high, position_m: [0.0, 0.75], size_m: [0.30, 0.30], rim_height_m: 0.80}"
TOWER = "{id: tower, position_m: [0.0, 0.60], size_m: [0.30, 0.30], rim_height_m: 1.00}"


def _job(bin_row: str, bin_id: str, policy: str = "auto") -> str:
    return (
        f"bins:\n  - {bin_row}\nitems:\n  - {{object: cube50, count: 1, bin: {bin_id}}}\n"
        f"policy: {policy}\nseed: 0\n"
    )


@pytest.fixture(scope="module")
def loaded() -> dict[str, Job]:
    """The jobs of one cube50 to `high` and to `tower`, each parsed (and so checked) once for
    the tests that read them (a `Job` is frozen): the job check's IK of a place missed, and
    of the reach its message states, is most of a parse (about 0.6 CPU-s each)."""
    return {
        b: parse_job(_job(row, b), f"{b}.yaml") for b, row in (("high", HIGH), ("tower", TOWER))
    }


def _run(job):  # type: ignore[no-untyped-def]
    # the decision is checked, not the release search or the turn: both off, for speed
    orch = Orchestrator(job, cycle_search=False, turn_release=False)
    try:
        return orch.run()
    finally:
        orch.close()


def test_auto_throws_into_a_near_bin_the_arm_cannot_place_into_and_it_lands(
    loaded: dict[str, Job],
) -> None:
    job = loaded["high"]
    assert job.thrown_bins == frozenset({"high"})
    (warning,) = job.warnings
    assert "the panda arm cannot place into bin 'high'" in warning
    assert "is out of reach (missed by" in warning
    assert "under policy auto its items are thrown into it instead" in warning
    s = _run(job)
    (r,) = s.results
    # the scene's own scoring: the item came to rest inside the bin's walls
    assert (r.action, r.failure, r.bin_id) == ("throw", "", "high"), r
    # the check's witness: the same job with the check skipped places, and the scene's arm
    # does not reach the place (the item fails `ik`, recorded)
    unchecked = parse_job(_job(HIGH, "high"), "high.yaml", check_reach=False)
    assert unchecked.thrown_bins == frozenset()
    (r,) = _run(unchecked).results
    assert (r.action, r.failure) == ("failed", "ik"), r


def test_policy_place_still_refuses_the_bin() -> None:
    with pytest.raises(JobError, match=r"line 2, bins\[0\].position_m: the panda arm cannot "):
        parse_job(_job(HIGH, "high", "place"), "high.yaml")


def test_a_near_bin_neither_placed_nor_thrown_into_is_refused_by_its_item_line(
    loaded: dict[str, Job],
) -> None:
    job = loaded["tower"]
    assert job.thrown_bins == frozenset({"tower"})
    with pytest.raises(JobError) as err:
        Orchestrator(job).close()
    msg = str(err.value)
    assert msg.startswith("tower.yaml, line 4: item cube50 to bin 'tower': ")
    assert "is out of reach" in msg
    assert "the arm cannot place into it either" in msg


def test_random_jobs_send_an_item_only_where_the_loaded_job_sorts_it(
    loaded: dict[str, Job],
) -> None:
    """`cell.jobgen.sortable_bins`, told the bins the job would throw into
    (`NearBins.thrown_with`), agrees with the loaded job: `high` is thrown into, `tower`
    refused; a place-reach-only draw (main's, before the job throws into them) took both."""
    from cell.jobgen import NearBins, _object_of, sortable_bins
    from cell.params import load_params, scene_params_path

    params = load_params(scene_params_path())
    bins = [
        {"id": "high", "position_m": [0.0, 0.75], "size_m": [0.30, 0.30], "rim_height_m": 0.80},
        {"id": "tower", "position_m": [0.0, 0.60], "size_m": [0.30, 0.30], "rim_height_m": 1.0},
    ]
    entry = {"object": "cube50"}
    thrown = NearBins("panda", bins).thrown_with(_object_of(entry))
    assert thrown == frozenset({"high", "tower"})
    assert sortable_bins(entry, bins, params) == ["high", "tower"]  # as if placed
    assert sortable_bins(entry, bins, params, thrown) == ["high"]
    # the loaded job's own verdicts, bin by bin
    for b in ("high", "tower"):
        job = loaded[b]
        assert job.thrown_bins == frozenset({b})
        try:
            Orchestrator(job).close()
            sorted_there = True
        except JobError:
            sorted_there = False
        assert sorted_there == (b in sortable_bins(entry, bins, params, thrown))


def test_a_random_job_with_such_bins_loads_and_passes_the_runs_check(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """`random_job` on a layout given it (its bins' draw replaced): `tower` and `high` as
    above, `edge` 0.60 m out with its rim 0.70 m up (the Panda places into it an item 30 mm
    high, not one 35 mm high: thrown into once a taller item is sent there), and a chute
    1.5 m out. The job it writes loads and its items pass the run's check (`Orchestrator`'s:
    a JobError names each item whose bin is neither placed nor thrown into). The draw is of
    12 items (`LayoutRanges.items` held there; a random layout draws 20-40, seed 0 40: 4.1
    against 1.0 CPU-s for the draw), which send items to `high`, `edge` and `chute` and a
    0.08 m cylinder to `edge`; drawn as if the near bins were placed into
    (`NearBins.thrown_with` answering none), they send two o4_cylinder50 to `tower`, which
    the check refuses."""
    import yaml

    from cell import jobgen

    layout = [
        {"id": "tower", "position_m": [0.0, 0.60], "size_m": [0.30, 0.30], "rim_height_m": 1.0},
        {"id": "high", "position_m": [-0.60, 0.45], "size_m": [0.30, 0.30], "rim_height_m": 0.8},
        {"id": "edge", "position_m": [0.45, 0.40], "size_m": [0.30, 0.30], "rim_height_m": 0.7},
        {"id": "chute", "position_m": [1.50, 0.30], "size_m": [0.30, 0.30], "rim_height_m": 0.15},
    ]
    monkeypatch.setattr(jobgen, "_bins", lambda rng, robot: [dict(b) for b in layout])
    monkeypatch.setattr(jobgen.LayoutRanges, "items", (12, 12))  # the docstring says why
    doc = jobgen.random_job(0, "panda")
    job = parse_job(yaml.safe_dump(doc, sort_keys=False), "random.yaml")
    assert job.thrown_bins == {"tower", "high", "edge"}  # `edge` holds a 0.08 m cylinder
    assert {"high", "edge", "chute"} <= {it.bin for it in job.items}
    Orchestrator(job).close()  # raises JobError if an item cannot be sorted


def test_a_random_job_sends_no_item_that_would_have_a_bin_thrown_into_with_one_placed_there() -> (
    None
):
    """A bin 0.60 m out with its rim 0.55 m up: the Panda places a 0.11 m item into it, not a
    0.20 m one. The 220 g tetrapack (0.11 m, held only carried slowly: never thrown) sent
    there, a bottle (0.20 m) sent after it would have the job throw into the bin, the
    tetrapack too: `NearBins.keeps_sorted` refuses the bottle that bin, as the loaded job
    (the two items together) is refused."""
    from cell.jobgen import NearBins, _object_of, sortable_bins
    from cell.params import load_params, scene_params_path

    params = load_params(scene_params_path())
    row = {"id": "low", "position_m": [0.0, 0.60], "size_m": [0.30, 0.30], "rim_height_m": 0.55}
    near = NearBins("panda", [row])
    pack, bottle = {"object": "o5_tetrapack", "bin": "low"}, {"object": "o6_bottle"}
    assert near.thrown_with(_object_of(pack)) == frozenset()
    assert sortable_bins(pack, [row], params) == ["low"]  # placed
    near.send(pack, _object_of(pack))
    thrown = near.thrown_with(_object_of(bottle))
    assert thrown == frozenset({"low"})
    assert sortable_bins(bottle, [row], params, thrown) == ["low"]  # the bottle is thrown
    assert not near.keeps_sorted("low", thrown, params)  # the tetrapack could not be
    # the loaded jobs: the tetrapack alone is placed; with the bottle, refused by its line
    one = (
        "bins:\n  - {id: low, position_m: [0.0, 0.60], size_m: [0.30, 0.30], "
        "rim_height_m: 0.55}\nitems:\n  - {object: o5_tetrapack, bin: low}\n"
    )
    assert parse_job(one, "low.yaml").thrown_bins == frozenset()
    both = parse_job(one + "  - {object: o6_bottle, bin: low}\n", "low.yaml")
    assert both.thrown_bins == frozenset({"low"})
    with pytest.raises(JobError, match=r"line 4: item o5_tetrapack to bin 'low': .* held only"):
        Orchestrator(both).close()
