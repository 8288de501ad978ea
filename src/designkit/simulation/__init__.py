"""Closed-loop simulation on the nonlinear model (CasADi fixed-step maps)."""

from designkit.simulation.linear import linear_response, linear_step
from designkit.simulation.result import SimulationResult
from designkit.simulation.run import simulate

__all__ = ["SimulationResult", "linear_response", "linear_step", "simulate"]
