"""Verification: each check returns a :class:`~designkit.verification.check.Check` with its evidence."""
