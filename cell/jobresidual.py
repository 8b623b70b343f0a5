"""A job's learned residual against the parameters the job plans with.

`cell learn` learns ΔL_s as the stroke that lands a throw less the stroke *its* model
(`cell learn --params`, by default the reference values) plans; the planner adds ΔL_s to
the stroke *the job's* model plans (its `cell.params`, by default the scene's calibrated
`robots/cell_scene/ee_params.yaml`). Where the two models' end-effector parameters
differ, L_s + ΔL_s means nothing it meant in training: a residual learned on a log of the
reference model, run with the scene's, threw a cube50 0.84 m past a bin 1.6 m out (the
same throw without the residual lands in it). The residual file keeps its model's η_ee
(`ResidualModel.ee`), so the job is refused before anything moves, naming the keys.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any

__all__ = ["residual_problems"]

# relative tolerance for "the same parameter": both sides are floats read from files
# (YAML and the residual's JSON metadata), which keep a float's 17 digits
SAME_REL = 1e-9


def residual_problems(job: Any, where: str) -> list[str]:
    """Why `job`'s `cell.residual` cannot correct the strokes its parameter file plans
    (an empty list where it can, or where either file does not load: the run refuses
    that file itself, saying why). `where` is "file, line N" of the job's cell section."""
    if not job.residual:
        return []
    from cell.errors import CellError
    from cell.model.params import EndEffectorParams
    from cell.params import load_params, scene_params_path
    from cell.residual.model import ResidualModel

    source = job.params or scene_params_path()
    try:
        learned = ResidualModel.load(job.residual).ee
        planned = load_params(source).ee
    except CellError:
        return []
    differ = [
        f.name
        for f in fields(EndEffectorParams)
        if not math.isclose(getattr(learned, f.name), getattr(planned, f.name), rel_tol=SAME_REL)
    ]
    if not differ:
        return []
    shown = ", ".join(
        f"{k} {getattr(learned, k):.6g} against {getattr(planned, k):.6g}" for k in differ[:4]
    )
    more = f" and {len(differ) - 4} more" if len(differ) > 4 else ""
    which = "its cell.params" if job.params else "the scene's calibrated file: no cell.params"
    return [
        f"{where}, cell.residual: {job.residual} learned ΔL_s against end-effector "
        f"parameters other than those this job plans with, {source} ({which}): {shown}{more} "
        f"(learned against planned); its ΔL_s corrects the stroke of the model it was learned "
        f"with, not this one's, and the throws would miss. Give cell.params the file "
        f"`cell learn --params` read, or learn it again with `cell learn THROWS.csv "
        f"--params {source} -o …`"
    ]
