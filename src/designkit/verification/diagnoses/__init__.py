"""Why a generic check failed and what would fix it, one module per check that has something to say.

Each is a ``(result, check) -> (cause, fix) | None`` named in its rule's ``diagnose``
(:mod:`designkit.verification.checks`); :mod:`designkit.analysis.diagnosis` asks the rule of every
failing check, then the design's family (``Family.diagnoses``).
"""
