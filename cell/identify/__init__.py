"""Two-stage parameter identification of η_ee and η_o from throw logs (thesis §4.1)."""

from cell.identify.algorithm import IdentifyOptions, IdentifyResult, identify
from cell.identify.refit import RefitReport, refit_objects

__all__ = ["IdentifyOptions", "IdentifyResult", "RefitReport", "identify", "refit_objects"]
