"""What every study is built from: the declaration and result types, the budget, the variant runner and the
metrics (the studies themselves are the other modules of :mod:`designkit.studies`)."""
