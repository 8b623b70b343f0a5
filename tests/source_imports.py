"""The modules a source file imports, read from its syntax tree (for the tests that a
world shares no code with the fit)."""

from __future__ import annotations

import ast
from pathlib import Path


def imported_modules(path: Path) -> list[str]:
    """Every module `path` imports (`import a.b` gives "a.b", `from a.b import c` "a.b";
    a relative `from . import c` gives "None")."""
    return [
        a.name if isinstance(node, ast.Import) else str(node.module)
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.Import | ast.ImportFrom)
        for a in (node.names if isinstance(node, ast.Import) else [node])
    ]
