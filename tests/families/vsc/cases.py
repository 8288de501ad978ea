"""The test cases the shared suites run for the vsc family (found by discovery): the ranged fields of its section
(tests/spec/test_ranges.py), its conformance cases (tests/problems.py) and its example specs' exit codes
(tests/test_cli.py)."""

from __future__ import annotations

BASE = """\
name: ranges-vsc
plant: {kind: link, Km: 2.0, tau: 0.5, uncertainty: {Km: [1.4, 2.6], tau: [0.35, 0.65]}}
controller: {kind: vsc, sliding_poles: [-5], perturbation_bound: 1.0, margin: 0.2, chattering_band: 0.005,
             alpha: [-2.0, -3.0], beta: [2.0, 1.0], relay_amplitude: 1.5}
simulation: {duration: 2.0}
"""
LAYER = BASE.replace("chattering_band: 0.005", "boundary_layer: 0.05")

RANGES = {f"controller.{k}": [(BASE, f"controller.{k}", f"controller.{k}")]
          for k in ("perturbation_bound", "margin", "chattering_band", "relay_amplitude")}
RANGES["controller.boundary_layer"] = [(LAYER, "controller.boundary_layer", "controller.boundary_layer")]
# alpha and beta each alone (given together, alpha_i < beta_i is a cross-field rule, tested in test_specs.py)
RANGES["controller.alpha[]"] = [(BASE.replace(" beta: [2.0, 1.0],", ""), "controller.alpha.0", "controller.alpha[0]")]
RANGES["controller.beta[]"] = [(BASE.replace(" alpha: [-2.0, -3.0],", ""), "controller.beta.1", "controller.beta[1]")]
"""Declared key path -> [(base spec, concrete path to set, the key path the loader names)]."""

CONFORMANCE = {
    # notes section 5.2, theorem 3: both link states switched, matched 0.5 N*m load from t = 1 s
    "link": ("{kind: vsc, sliding_poles: [-5], perturbation_bound: 0.5}",
             "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
             "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}"),
    # ROBEL figure 5.3 on the default elastic joint (no uncertainty), relay given
    "elastic_joint": ("{kind: vsc, sliding_poles: [-8, -10, -12], relay_amplitude: 0.05}", "{duration: 1.5}",
                      "{overshoot: 15, settling_time: 1.2, steady_state_error: 0.01}"),
    # the link as a transfer function and as a state-space model with named parameters, the same box and load
    "transfer_function": ("{kind: vsc, sliding_poles: [-5], perturbation_bound: 0.5}",
                          "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
                          "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}"),
    "state_space": ("{kind: vsc, sliding_poles: [-5], perturbation_bound: 0.5}",
                    "{duration: 3.0, perturbation: {value: 0.5, time: 1.0}}",
                    "{overshoot: 2, settling_time: 1.5, steady_state_error: 0.005}"),
}
"""Canonical plant -> (controller, simulation, requirements) of the conformance suite (tests/problems.py)."""

EXAMPLES = {
    "vsc-elastic-joint": 0,
    "vsc-link": 0,
    "vsc-third-order-drive": 0,  # theorem 3 on a state_space plant with a gearbox resonance
    "vsc-elastic-joint-narrow-gains": 1,  # gains bracketing l_i at the nominal plant only: the certificate fails
}
"""Example spec -> the exit code of ``designkit synth`` (tests/test_cli.py)."""
