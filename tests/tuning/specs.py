"""Specs the tuning tests run: short, cheap variants of the repository's examples."""

from __future__ import annotations

from pathlib import Path

LINK = """\
name: link-tune
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
requirements: {overshoot: 5, settling_time: 1.5, max_control: 40}
simulation: {duration: 3.0}
tune: {fixed: [zero]}
"""
"""The one-link PID servo of specs/posspeed-link.yaml (zero fixed at -3 1/s) with an overshoot, a settling-time
and a torque requirement: the torque limit makes the three trade off."""

SIMNOG = """\
name: simnog-tune
plant:
  kind: robot
  robot: planar2r
  uncertainty: {m2: [2.0, 4.0], grid: 5}
controller: {kind: decentralized_pid}
requirements: {overshoot: 5, settling_time: 1.0}
simulation:
  duration: 2.5
  step: [1.0, -0.5]
"""
"""specs/simnog-decentralized-pid.yaml with 5 % overshoot and 1 s settling over m2 in [2, 4] kg: the poles the
requirements derive (dominant pair, third pole 5x further) overshoot by 15 % at the light end of the box."""


def write(folder: Path, text: str, name: str = "spec.yaml") -> Path:
    """``text`` written as ``folder/name``."""
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path
