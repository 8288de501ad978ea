"""Analyses of a finished run that answer questions about it (read a ``PipelineResult``, return frozen values).

They sit between the pipeline and the report: the report draws what they return and never computes it.
"""

from designkit.analysis.lab import LabAnswers, lab_answers

__all__ = ["LabAnswers", "lab_answers"]
