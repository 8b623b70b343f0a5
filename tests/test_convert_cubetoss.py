"""examples/convert_cubetoss.py: the converter of the shipped slice
tests/data/contactnets_cube, on toss files written here in the source's form (PyTorch's
legacy serialization of a (1, frames, 19) double tensor, made without PyTorch: stand-in
modules named as PyTorch's, so that the pickle refers to them as a saved tensor does)."""

from __future__ import annotations

import csv
import gzip
import importlib.util
import io
import pickle
import struct
import sys
import types
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "convert_cubetoss", ROOT / "examples/convert_cubetoss.py"
)
conv = importlib.util.module_from_spec(_spec)  # type: ignore[arg-type]
_spec.loader.exec_module(conv)  # type: ignore[union-attr]


class _Storage:
    pass


def _save(path: Path, data: np.ndarray) -> None:
    """`data` (frames, 19) as PyTorch's legacy format saves a (1, frames, 19) tensor."""
    torch = types.ModuleType("torch")
    utils = types.ModuleType("torch._utils")

    def _rebuild_tensor_v2(*args: object) -> None:
        return None

    _rebuild_tensor_v2.__module__ = "torch._utils"
    _rebuild_tensor_v2.__qualname__ = "_rebuild_tensor_v2"
    _Storage.__module__, _Storage.__qualname__ = "torch", "DoubleStorage"
    utils._rebuild_tensor_v2 = _rebuild_tensor_v2  # type: ignore[attr-defined]
    torch.DoubleStorage = _Storage  # type: ignore[attr-defined]
    saved = {k: sys.modules.get(k) for k in ("torch", "torch._utils")}
    sys.modules.update({"torch": torch, "torch._utils": utils})
    try:
        storage = _Storage()

        class _P(pickle.Pickler):
            def persistent_id(self, obj: object) -> object:
                return (
                    ("storage", _Storage, "7", "cpu", data.size, None) if obj is storage else None
                )

            def reducer_override(self, obj: object) -> object:
                if obj is tensor:
                    n, c = data.shape
                    return _rebuild_tensor_v2, (storage, 0, (1, n, c), (n * c, c, 1), False, {})
                return NotImplemented

        tensor = object()
        fh = io.BytesIO()
        for head in (0x1950A86A20F9469CFC6C, 1001, {"little_endian": True}):
            pickle.dump(head, fh, protocol=2)
        _P(fh, protocol=2).dump(tensor)
        pickle.dump(["7"], fh, protocol=2)
        fh.write(struct.pack("<q", data.size) + data.astype("<f8").tobytes())
        path.write_bytes(fh.getvalue())
    finally:
        for k, v in saved.items():
            if v is None:
                sys.modules.pop(k, None)
            else:
                sys.modules[k] = v


def _toss(frames: int, contact: int) -> np.ndarray:
    """A cube falling under g at 148 Hz, level (identity quaternion), that meets the board
    (lowest corner at 0) half a frame before frame `contact` and rests there."""
    t = np.arange(frames) / 148.0
    tc = (contact - 0.5) / 148.0
    z0 = conv.HALF_WIDTH_M + 0.5 * 9.81 * tc**2
    z = np.where(t < tc, z0 - 0.5 * 9.81 * t**2, conv.HALF_WIDTH_M)
    a = np.zeros((frames, conv.COLUMNS))
    a[:, 0], a[:, 1], a[:, 2], a[:, 3] = 0.5 * t, 0.1, z, 1.0
    a[:, :3] /= conv.HALF_WIDTH_M
    return a


def test_the_converter_keeps_each_toss_up_to_10_frames_after_its_contact(tmp_path) -> None:  # type: ignore[no-untyped-def]
    src = tmp_path / "tosses_processed"
    src.mkdir()
    _save(src / "0.pt", _toss(40, 17))
    _save(src / "1.pt", _toss(30, 12))
    out = tmp_path / "flights.csv.gz"
    assert conv.main([str(src), str(out)]) == 0
    with gzip.open(out, "rt") as fh:
        rows = list(csv.DictReader(fh))
    by = {k: [r for r in rows if r["toss"] == k] for k in ("0", "1")}
    # frames 0 .. contact - 1 free, the contact frame, then 10 more
    assert len(by["0"]) == 17 + 1 + conv.AFTER_CONTACT and len(by["1"]) == 12 + 1 + 10
    z = [float(r["z_m"]) for r in by["0"]]
    assert z[17] == pytest.approx(conv.HALF_WIDTH_M, abs=1e-5) and z[16] > z[17]
    assert float(by["0"][0]["z_m"]) == pytest.approx(
        conv.HALF_WIDTH_M + 0.5 * 9.81 * (16.5 / 148) ** 2, abs=1e-5
    )
    first = out.read_bytes()
    assert conv.main([str(src), str(out)]) == 0 and out.read_bytes() == first


def test_a_file_that_is_no_saved_tensor_is_named(tmp_path) -> None:  # type: ignore[no-untyped-def]
    src = tmp_path / "tosses_processed"
    src.mkdir()
    (src / "0.pt").write_bytes(pickle.dumps({"not": "a tensor"}))
    with pytest.raises(SystemExit, match=r"0\.pt: not a legacy PyTorch double tensor"):
        conv.main([str(src), str(tmp_path / "f.csv.gz")])
