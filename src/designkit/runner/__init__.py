"""The family's own run of a spec, and its variants: what the pipeline, the fixes and the studies all run.

:func:`~designkit.runner.run.run_spec` is the one place a spec becomes a verdict: the true plant, the family's
design (with the spec's anti-windup), the simulation -- or the trials of a learning law, with the update between
them -- and every check the family offers.  :mod:`~designkit.runner.variants` changes one setting of a spec (its
YAML, re-validated as a file is) or the gains of a design (the law, the closed loop and the per-joint loops
rebuilt), so that a fix or a study runs exactly the loop the family designs, never a reduced copy of it.
"""
