"""Comparisons: several controllers run on one task, the same metrics for each, and what the comparison answers.

:mod:`~designkit.comparison.metrics` computes the metrics from one run's arrays;
:mod:`~designkit.comparison.table` assembles the table and says who wins on each metric;
:mod:`~designkit.comparison.verdicts` writes each controller's verdict from its checks' statuses;
:mod:`~designkit.comparison.answers` gives the sections a comparison's report answers (the generic one from the
metrics alone, then the comparison studies' of :mod:`designkit.studies`, which the result runs).  The layer sits
above ``analysis`` (it reads the families, the simulation and the checks) and below ``studies`` and ``report``,
which build on and lay out what it returns.
"""
