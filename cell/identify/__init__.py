"""Two-stage parameter identification of η_ee and η_o from throw logs (thesis §4.1)."""

from cell.identify.algorithm import IdentifyOptions, IdentifyResult, identify

__all__ = ["IdentifyOptions", "IdentifyResult", "identify"]
