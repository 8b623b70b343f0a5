"""The release-on-the-move search kept across decisions (`MovingRelease._choose_release`):
a kept choice is taken only where the search would make it again, so a decision is the
same with the kept searches as with none.

Independent checks: the same decision made afresh (nothing kept) on the scenario where
`choose_release` offers releases on the move (tests/test_moving_choice.py's random
layout 11, UR5, with its 0.05 s settle), bit for bit; and, on a stand-in search that
counts its runs, that a kept choice is not taken where an argument or an IK answer
differs by one bit.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cell.arm import release_moving
from cell.arm.tuning import TUNING
from cell.errors import IKFailed
from cell.jobs import parse_job
from cell.orchestrator import Orchestrator
from cell.robot import moving_release
from tests.test_moving_choice import JOB as JOB4
from tests.test_moving_choice import SETTLE_THEN_S

# layout 11's job with its fifth item, the cyl40 (tests/test_moving_choice.py runs the four
# before it): the item whose decision here takes a release on the move
JOB = JOB4.replace("seed: 11", "  - {object: cyl40, count: 1, bin: bin_3}\nseed: 11")
assert JOB != JOB4


def _decision(o: Orchestrator, k: int) -> tuple[Any, ...]:
    """Item k's decision, the arm where it is, as bits: (moving?, plan, stroke, release)."""
    spec = o.job.expanded_items()[k]
    o.present(k, spec.obj)
    try:
        d = o.decide(k, spec.obj, o.job.bin(spec.bin))
    finally:
        o.scene.remove_item(o._presented)
    return (
        bool(d.moving),
        release_moving._exact(d.plan),
        float(d.stroke_m).hex(),
        np.asarray(d.state.q_release, float).tobytes(),
    )


def test_a_kept_search_decides_as_a_fresh_one(tmp_path: Path) -> None:
    o = Orchestrator(
        parse_job(JOB, str(tmp_path / "job.yaml")),
        session="kept",
        release="auto",
        cycle_search=False,
        turn_release=False,
        tuning=replace(TUNING, settle_s=SETTLE_THEN_S),
    )
    runs = [0]
    search = moving_release.choose_release

    def counted(*a: Any, **k: Any) -> Any:
        runs[0] += 1
        return search(*a, **k)

    try:
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(moving_release, "SETTLE_S", SETTLE_THEN_S)
            mp.setattr(moving_release, "choose_release", counted)
            seen = []
            for k in (0, 2, 4):  # a 51 mm cube to bin_5, a cube50 to bin_3, the cyl40
                fresh = _decision(o, k)
                n = runs[0]
                again = _decision(o, k)  # the same item, where it was: the search kept
                assert runs[0] == n, k  # not searched again
                o._moving_kept.clear()
                assert _decision(o, k) == again == fresh, k
                seen.append(fresh[0])
            assert True in seen  # a release on the move was chosen from a kept search
    finally:
        o.close()


def test_a_kept_choice_is_taken_only_where_the_search_would_make_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    o = Orchestrator(parse_job(JOB, str(tmp_path / "job.yaml")), session="stand-in")
    runs: list[int] = []

    def stand_in(robot: Any, obj: Any, plan: Any, q: Any, ee: Any, ik: Any, **kw: Any) -> Any:
        runs.append(1)
        try:
            ik(np.array([0.4, 0.1, 0.6]), 0.3, 0.2)
        except IKFailed:
            pass
        return (ik(np.array([0.5, 0.0, 0.7]), 0.4, 0.1), len(runs))

    monkeypatch.setattr(moving_release, "choose_release", stand_in)
    answers = {0.6: IKFailed("out of reach"), 0.7: np.array([0.1, 0.2, 0.3])}

    def ik(t: np.ndarray, e: float, a: float) -> np.ndarray:
        out = answers[float(t[2])]
        if isinstance(out, Exception):
            raise out
        return out

    q = np.array([0.0, -0.5, 0.5])
    args = (o.robot, o.job.expanded_items()[0].obj, _plan(), q, o.params.ee)
    kw = dict(criterion="cycle", velocity_scale=1.0)
    try:
        first = o._choose_release(args, kw, ik)
        assert o._choose_release(args, kw, ik) == first and len(runs) == 1  # kept
        # an IK answer one bit off: searched again
        answers[0.7] = np.array([0.1, 0.2, np.nextafter(0.3, 1.0)])
        assert o._choose_release(args, kw, ik)[1] == 2
        # a failure that now solves: searched again
        answers[0.6] = np.array([0.0, 0.0, 0.0])
        assert o._choose_release(args, kw, ik)[1] == 3
        assert o._choose_release(args, kw, ik)[1] == 3  # and that one kept
        # an argument one bit off: another search
        q2 = q.copy()
        q2[1] = np.nextafter(q2[1], 0.0)
        assert o._choose_release((*args[:3], q2, args[4]), kw, ik)[1] == 4
        assert o._choose_release(args, {**kw, "velocity_scale": 0.5}, ik)[1] == 5
    finally:
        o.close()


def _plan() -> Any:
    """A static plan (its fields are the key's, not used by the stand-in search)."""
    from cell.optimize.plan import ThrowPlan

    fields = {f: 0.5 for f in ThrowPlan.__dataclass_fields__}
    fields.update(method="fast", object_id="cube")
    return ThrowPlan(**fields)
