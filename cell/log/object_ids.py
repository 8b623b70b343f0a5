"""Object ids that differ only by letter case (docs/throw_log.md).

Rows with the same `object_id` are the same object, and rows with different ids are
different objects: the diagnosis' per-object laws, `cell identify`'s per-object fit and
`cell learn`'s objects held out all read the id as it is written. A log that writes one
object as `cube50` in some rows and `Cube50` in others (a spreadsheet's autocorrect, two
people logging; a trailing space is already stripped) is read as two objects, and a
held-out object then has its twin in the training throws. That is not refused (two
objects may be named so on purpose), but said, naming the ids and a row of each.
"""

from __future__ import annotations

__all__ = ["ids_alike_by_case"]


def ids_alike_by_case(ids: list[str], path: str = "") -> list[str]:
    """One sentence per group of object ids that are equal but for letter case.

    Args:
        ids: the log's `object_id` column (cells stripped), in row order.
        path: the log's path, for the sentence.

    Returns:
        The sentences (empty where no two ids differ only by case).
    """
    first: dict[str, int] = {}
    for row, oid in enumerate(ids, start=1):
        first.setdefault(oid, row)
    groups: dict[str, list[str]] = {}
    for oid in first:
        groups.setdefault(oid.casefold(), []).append(oid)
    out = []
    for names in groups.values():
        if len(names) < 2:
            continue
        said = ", ".join(f"{n!r} (row {first[n]})" for n in names)
        out.append(
            f"{path + ': ' if path else ''}object ids {said} differ only by letter case: they "
            "are read as different objects (rows with one object_id are one object); write "
            "one id if they are one object"
        )
    return out
