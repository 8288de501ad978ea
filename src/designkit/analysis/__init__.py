"""Analyses of a finished run that explain it (read a ``PipelineResult``, return frozen values): why it failed, and
the nonlinear elements' own analyses.

They sit between the pipeline and the report: the report draws what they return and never computes it.  What
interprets a verdict by running variants of the design is a study (:mod:`designkit.studies`).
"""
