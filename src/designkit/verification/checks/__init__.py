"""The generic checks, one module each: every module here defines ``RULE``, a
:class:`~designkit.verification.suite.CheckRule` (discovered by :func:`designkit.verification.suite.generic`).

A rule module says what the check needs and how it runs; the computation it calls lives in the
module of its concept (:mod:`designkit.verification.lyapunov`, :mod:`~designkit.verification.robustness`,
...), imported when the check runs.  A family's own checks are rules in the family's module.
"""
