"""The adaptive computed torque's figures (placeholder, filled below)."""

FIGURES: tuple = ()
