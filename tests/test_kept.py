"""`cell.robot.kept.Kept`: a value made once per key, cleared when full, an error kept by
its message."""

from __future__ import annotations

import pytest

from cell.errors import TrajectoryError
from cell.robot.kept import Kept, array_key


def test_a_value_is_made_once_per_key_and_all_cleared_when_full() -> None:
    made: list[bytes] = []
    kept: Kept[list[bytes]] = Kept(3)

    def make(k: bytes) -> list[bytes]:
        made.append(k)
        return [k]

    first = kept.get(b"a", lambda: make(b"a"))
    assert kept.get(b"a", lambda: make(b"a")) is first and made == [b"a"]
    kept.get(b"b", lambda: make(b"b"))
    kept.get(b"c", lambda: make(b"c"))
    assert len(kept) == 3
    kept.get(b"d", lambda: make(b"d"))  # full: cleared, then d kept
    assert len(kept) == 1
    assert kept.get(b"a", lambda: make(b"a")) is not first and made.count(b"a") == 2


def test_an_error_is_kept_by_its_message_and_raised_again() -> None:
    calls = []
    kept: Kept[int] = Kept(8, TrajectoryError)

    def fails() -> int:
        calls.append(1)
        raise TrajectoryError("leaves the limits")

    for _ in range(3):
        with pytest.raises(TrajectoryError, match="leaves the limits"):
            kept.get(b"k", fails)
    assert len(calls) == 1
    with pytest.raises(ValueError):  # another error is not kept
        kept.get(b"v", lambda: int("x"))
    assert len(kept) == 1


def test_array_key_tells_apart_values_and_order() -> None:
    assert array_key([1.0, 2.0], [3.0]) == array_key([1, 2], [3])
    assert array_key([1.0, 2.0], [3.0]) != array_key([1.0], [2.0, 3.0][::-1])
    assert array_key([0.0]) != array_key([-0.0])
