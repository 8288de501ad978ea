"""Reports: one :class:`~designkit.report.model.ReportModel` rendered as self-contained HTML and as PDF."""

from designkit.report.model import ReportModel, build_report_model
from designkit.report.writer import ReportFiles, write_report

__all__ = ["ReportFiles", "ReportModel", "build_report_model", "write_report"]
