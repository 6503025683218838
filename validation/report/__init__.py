"""The HTML validation report and the nightly run (``scatterbench report`` / ``nightly``)."""

from .build import build_report, write_report
from .nightly import compare_results, nightly

__all__ = ["build_report", "write_report", "nightly", "compare_results"]
