"""Pole migration over the uncertainty box: the lattice's closed-loop poles, drawn coloured by a parameter."""

from __future__ import annotations

import numpy as np
import pytest

import designkit as dk
from designkit.verification.figures.robustness import pole_migration_figure


def test_the_migration_is_the_lattice_the_robustness_check_judged():
    result = dk.run(dk.load_spec("specs/posspeed-perturbation.yaml"), simulate=False)
    check = next(c for c in result.checks if c.name == "robust_grid")
    poles = np.asarray(check.data["poles"])
    assert poles.shape[0] == check.certificate["plants"]
    # the rightmost pole is the check's worst spectral abscissa (an independent eigvals of the same matrices)
    assert poles.real.max() == pytest.approx(check.certificate["worst_abscissa"]["spectral_abscissa"], rel=1e-9)
    # each plant's poles are those of the link's PID loop with its (Km, tau), from the characteristic polynomial
    # tau s^3 + (1 + Km K2) s^2 + Km K1 s + Km K3 (the servo's, derived in docs/verification.md)
    K1, K2, K3 = (float(result.design.gains[k]) for k in ("K1", "K2", "K3"))
    names = list(check.data["names"])
    for i in (0, len(poles) // 2, len(poles) - 1):
        Km, tau = (float(check.data["theta"][i][names.index(k)]) for k in ("Km", "tau"))
        expected = np.sort_complex(np.roots([tau, 1 + Km * K2, Km * K1, Km * K3]))
        assert np.sort_complex(poles[i]) == pytest.approx(expected, rel=1e-8, abs=1e-8)
    fig = pole_migration_figure(result, check)
    assert fig is not None and f"{check.certificate['plants']} plants" in fig.caption
