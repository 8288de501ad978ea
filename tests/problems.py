"""Canonical problems with known answers, shared by the tests of every layer."""

from __future__ import annotations

POSSPEED_YAML = """\
name: posspeed-link
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_servo, poles: [-4, -5, -20], zero: -3}
"""
# Hand-derived answer: S1 = -29, S2 = 200, S3 = -400 (1/s, 1/s^2, 1/s^3), Km = 2, tau = 0.5:
# K1 = tau S2 / Km = 50, K2 = -(tau S1 + 1)/Km = 6.75, K3 = -tau S3 / Km = 100,
# K4 = -(K3 + K1 z)/(K3 z) = -(100 - 150)/(-300) = -1/6.
POSSPEED_GAINS = {"K1": 50.0, "K2": 6.75, "K3": 100.0, "K4": -1.0 / 6.0}

TRACKING_YAML = """\
name: tracking
plant: {kind: link, Km: 2.0, tau: 0.5}
controller: {kind: pid_tracking, poles: [-10, -12, -15]}
"""
# S1 = -37, S2 = 120 + 150 + 180 = 450, S3 = -1800: K1 = 112.5, K2 = 9.25, K3 = 450.
TRACKING_GAINS = {"K1": 112.5, "K2": 9.25, "K3": 450.0}

COMPLEX_YAML = """\
name: complex-poles
plant: {kind: link, Km: 1.3, tau: 0.8}
controller: {kind: pid_servo, poles: ['-3+4j', '-3-4j', -12], zero: -2}
"""
