"""Spec texts the sweep tests share: the PID servo on the link, whose stability boundary in (Km, tau) is
known in closed form, and the SIMNOG two-link arm, short runs."""

from __future__ import annotations

LINK = """\
name: link-sweep
plant:
  kind: link
  Km: 2.0
  tau: 0.5
  uncertainty: {{Km: [{km_lo}, {km_hi}], tau: [{tau_lo}, {tau_hi}]}}
controller: {{kind: pid_servo, poles: [-4, -5, -20], zero: -3}}
requirements: {{steady_state_error: 0.5}}
simulation: {{duration: {duration}}}
numerics: {{integrator: rk4}}
"""


def link(km=(0.1, 1.0), tau=(0.5, 4.0), duration=60.0, extra: str = "") -> str:
    """The PID servo designed on the link Km = 2, tau = 0.5 (poles -4, -5, -20, zero -3), swept over a box."""
    return LINK.format(km_lo=km[0], km_hi=km[1], tau_lo=tau[0], tau_hi=tau[1], duration=duration) + extra


SIMNOG = """\
name: simnog-sweep
plant:
  kind: robot
  robot: planar2r
  uncertainty: {m2: [2.0, 4.0]}
controller: {kind: decentralized_pid, poles: [-4, -5, -20], zero: -3}
requirements: {overshoot: 9, settling_time: 1.5, steady_state_error: 0.002, rise_time: 1.0, max_control: 300}
simulation:
  duration: 2.0
  step: [1.0, -0.5]
numerics: {integrator: rk4}
"""


def write(tmp_path, text: str, name: str = "spec.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path
