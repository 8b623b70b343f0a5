"""A throw or track log given in another file format, named by its first bytes.

A lab exports what its tools write: a gzipped CSV, a Parquet or Feather table, an Excel
workbook, JSON lines, a SQLite file. Read as CSV text they fail on their first bytes with a
message about NUL bytes or a missing column, which names neither the format nor what to
do. `other_format` names it, and the log reader refuses it with that sentence: a log is
read as CSV text only (docs/throw_log.md), nothing is decompressed or converted for it.
"""

from __future__ import annotations

import json

__all__ = ["other_format"]

_CSV = "a throw or track log is read as plain CSV text (comma-separated, a header row; docs/throw_log.md)"

# (first bytes, what the file is, what to do) -- each a format's documented magic number
_MAGIC: tuple[tuple[bytes, str, str], ...] = (
    (b"\x1f\x8b", "gzip-compressed", "decompress it first (gunzip -k FILE)"),
    (b"BZh", "bzip2-compressed", "decompress it first (bunzip2 -k FILE)"),
    (b"\xfd7zXZ\x00", "xz-compressed", "decompress it first (unxz -k FILE)"),
    (b"\x28\xb5\x2f\xfd", "zstd-compressed", "decompress it first (unzstd FILE)"),
    (
        b"PAR1",
        "a Parquet file",
        "write it as CSV (pandas: pd.read_parquet(F).to_csv(O, index=False))",
    ),
    (
        b"ARROW1",
        "an Arrow/Feather file",
        "write it as CSV (pandas: pd.read_feather(F).to_csv(O, index=False))",
    ),
    (
        b"PK\x03\x04",
        "a ZIP archive (an Excel .xlsx workbook is one)",
        "save the sheet as 'CSV UTF-8', or unzip it",
    ),
    (
        b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1",
        "an Excel 97-2003 workbook (.xls)",
        "save the sheet as 'CSV UTF-8'",
    ),
    (
        b"SQLite format 3\x00",
        "an SQLite database (a throw store?)",
        "`cell log export --db FILE -o log.csv` writes a store's throws as CSV",
    ),
    (b"\x89HDF\r\n\x1a\n", "an HDF5 file", "write the table as CSV"),
    (b"\x93NUMPY", "a NumPy .npy array", "write the table as CSV with a header row"),
)


def other_format(path: str) -> str:
    """A sentence naming the format of `path` when its first bytes are another format's (a
    compressed file, a binary table, JSON), else "". Reads at most the first 64 kB."""
    try:
        with open(path, "rb") as fh:
            start = fh.read(65536)
    except OSError:
        return ""  # the reader's own open says why
    for magic, what, todo in _MAGIC:
        if start.startswith(magic):
            return f"is {what}, not CSV text: {_CSV}; {todo}"
    text = start.removeprefix(b"\xef\xbb\xbf").lstrip()
    if text[:1] not in (b"{", b"["):
        return ""
    first = text.split(b"\n", 1)[0].strip()
    try:
        json.loads(first)
    except ValueError:  # a JSON document over several lines: its first key written so
        if not (first[:1] == b"[" and first.strip() == b"[") and b'":' not in first:
            return ""
        kind = "JSON"
    else:
        kind = "JSON lines" if first[:1] == b"{" and b"\n" in text.strip() else "JSON"
    return (
        f"is {kind}, not CSV text: {_CSV}; write it as CSV "
        "(pandas: pd.read_json(F, lines=True).to_csv(O, index=False))"
    )
