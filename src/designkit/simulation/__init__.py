"""Closed-loop simulation on the nonlinear model (CasADi fixed-step maps)."""
