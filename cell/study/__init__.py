"""Case studies that hold the cell's model against the thesis' experiments."""

from cell.study.plot import plot_study
from cell.study.repeatability import (
    THESIS_TABLE,
    RepeatabilityStudy,
    StudySetup,
    run_study,
)

__all__ = ["THESIS_TABLE", "RepeatabilityStudy", "StudySetup", "plot_study", "run_study"]
