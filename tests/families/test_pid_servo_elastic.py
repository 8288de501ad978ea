"""pid_servo on the elastic joint: the rigid approximation against the stiff limit of the 4-state model, and the
5-state loop's poles against a closed loop assembled here from the model's NumPy state space."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.models.elastic import ElasticJointPlant, elastic_state_space, rigid_approximation
from designkit.models.robots.elastic_link import DEFAULTS, elastic_link


def _transfer(A, B, C, s):
    return (C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B)).item()


@pytest.mark.parametrize("overrides", [{}, {"J2": 0.3, "tau2": 0.8}, {"R1": 0.1, "tau1": 0.02, "J1": 1e-3}])
def test_rigid_approximation_is_the_stiff_limit(overrides):
    params = elastic_link(**overrides)
    Km, tau = rigid_approximation(params)
    stiff = elastic_link(**overrides, KR=1e8)
    A, B = elastic_state_space(stiff)
    for w in (0.3, 1.0, 3.0):
        s = 1j * w
        assert _transfer(A, B, np.eye(4)[[2]], s) == pytest.approx(Km / (s * (tau * s + 1)), rel=1e-4)


def test_elastic_design_loop_poles_and_stiff_limit():
    from designkit.families.pid_servo import elastic_design

    poles = [-4.0, -5.0, -6.0]
    d = elastic_design(ElasticJointPlant(DEFAULTS), poles, -5.5)
    K1, K2, K3, K4 = (float(d.gains[k]) for k in ("K1", "K2", "K3", "K4"))
    A, B = elastic_state_space(DEFAULTS)
    b = B[:, 0]
    # u = -K1 (x3 - r) - K2 x4 - K3 z + K3 K4 r, z' = x3 - r
    Acl = np.zeros((5, 5))
    Acl[:4, :4] = A
    Acl[:4, 2] -= K1 * b
    Acl[:4, 3] -= K2 * b
    Acl[:4, 4] = -K3 * b
    Acl[4, 2] = 1.0
    got = np.sort_complex(np.array(d.data.loop_poles))
    assert got == pytest.approx(np.sort_complex(np.linalg.eigvals(Acl)), rel=1e-8)
    assert max(got.real) < 0
    # with a stiff transmission the same gains place the requested poles (the rigid model is the limit)
    stiff = elastic_design(ElasticJointPlant(elastic_link(KR=1e7)), poles, -5.5)
    near = sorted(p.real for p in stiff.data.loop_poles if abs(p) < 100)
    assert near == pytest.approx(sorted(poles), abs=2e-3)


def test_fast_load_pid_destabilises_the_elastic_mode():
    from designkit.families.pid_servo import elastic_design

    d = elastic_design(ElasticJointPlant(DEFAULTS), [-8.0, -10.0, -12.0], -11.0)
    assert "UNSTABLE" in d.notes[-1]
    A = d.closed_loop.A
    assert max(np.linalg.eigvals(A).real) > 0


def test_uncontrollable_elastic_joint_is_refused_at_the_parameter(tmp_path, capsys):
    from tests.cli_input import assert_bad_input

    text = """\
name: pid-elastic-kr
plant: {kind: elastic_joint, KR: 1.0e-6}
controller: {kind: pid_servo, poles: [-4, -5, -6], zero: -5.5}
simulation: {duration: 2.0}
"""
    assert_bad_input(tmp_path, capsys, text, "plant.KR: makes the plant uncontrollable")
