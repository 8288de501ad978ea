"""Controller synthesis: one module per family, dispatched by :mod:`designkit.synthesis.registry`."""
