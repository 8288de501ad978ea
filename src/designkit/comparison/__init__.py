"""Comparisons: several controllers run on one task, the same metrics for each, and what the comparison answers.

:mod:`~designkit.comparison.metrics` computes the metrics from one run's arrays;
:mod:`~designkit.comparison.table` assembles the table and says who wins on each metric;
:mod:`~designkit.comparison.answers` collects the sections a comparison's report answers (the generic one
from the metrics alone, and those contributed for particular sets of families, e.g.
:mod:`~designkit.comparison.lab2`, lab experiment 2: MRAC against SELFTUNE).  The layer sits above
``analysis`` (it reads the families, the simulation and the checks) and below ``report``, which lays out
what it returns.
"""
