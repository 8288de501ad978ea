"""Base inertial parameters: tau = Wb beta, full column rank, literature counts, exact regrouping coefficients.

Counts (gravity in the plane of motion / along joint 1, no friction, no rotors):

* planar 2R: 6 = 3 per link (ZZR, MXR, MY): a link turning about a fixed-direction
  axis shows only its inertia about that axis and its first moments in the plane
  (Gautier & Khalil, IEEE T-RA 6(3), 1990; Khalil & Dombre, *Modeling, Identification
  and Control of Robots*, 2002, ch. 9), and each ``m_j`` regroups into link ``j-1``.
* PUMA 560 (60 standard parameters): 36 = 1 + 7*5.  Link 1 turns about the gravity
  axis, so only ``ZZ1R`` remains; every other link keeps the Gautier--Khalil seven
  (``XXR, XY, XZ, YZ, ZZR, MXR, MYR``).  With rotor inertias: 40, because ``Ia1``
  regroups into ``ZZ1R`` and ``Ia2`` into ``ZZ2R`` (axis 2 is perpendicular to axis 1).

Each count is also checked against an independent route: the SVD rank of the full
regressor stacked on 500 random states.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from designkit.errors import ModelError
from designkit.models.base_parameters import base_parameters
from designkit.models.description import ChainDescription, LinkDescription
from designkit.models.robot import robot_from_dh
from designkit.models.robots import robot
from tests.models.support import TOL_EXACT, random_states, scaled_error


@pytest.fixture(scope="module")
def puma():
    arm = robot("puma560")
    return arm, base_parameters(arm)


@pytest.fixture(scope="module")
def puma_rotors():
    arm = robot("puma560", friction=True, motor_inertia=True)
    return arm, base_parameters(arm)


def svd_rank(arm, count: int = 500, seed: int = 11) -> int:
    """Rank of W stacked on random states, identically zero columns removed first (independent route)."""
    q, qd, qdd = random_states(np.random.default_rng(seed), arm.n, count)
    W = arm.regressor(q, qd, qdd).reshape(-1, len(arm.parameter_names))
    norms = np.linalg.norm(W, axis=0)
    W = W[:, norms > 1e-9 * norms.max()]
    s = np.linalg.svd(W / np.linalg.norm(W, axis=0), compute_uv=False)
    return int(np.sum(s > 1e-8 * s[0]))


def random_chain(seed: int) -> ChainDescription:
    """A chain with generic but well-conditioned geometry (lengths >= 0.1 m), mixed joints and conventions."""
    rng = np.random.default_rng(seed)
    links = []
    for _ in range(int(rng.integers(2, 5))):
        links.append(LinkDescription(
            joint=str(rng.choice(["revolute", "revolute", "prismatic"])),
            a=float(rng.choice([0.0, 1.0]) * rng.uniform(0.1, 0.5)),
            alpha=float(rng.choice([0.0, math.pi / 2, -math.pi / 2, rng.uniform(0.3, 1.2)])),
            d=float(rng.choice([0.0, 1.0]) * rng.uniform(0.1, 0.5)),
            theta=float(rng.uniform(-1, 1)), offset=float(rng.uniform(-0.3, 0.3)),
            mass=float(rng.uniform(0.5, 3)), com=tuple(rng.uniform(-0.2, 0.2, 3)),
            inertia=(*rng.uniform(0.01, 0.1, 3), *rng.uniform(-0.005, 0.005, 3)),
        ))
    gravity = tuple(rng.normal(size=3) * 5) if seed % 2 else (0.0, 0.0, -9.81)
    return ChainDescription(f"random{seed}", tuple(links), convention=("standard", "modified")[seed % 2],
                            gravity=gravity)


def check_reproduces_dynamics(arm, bp, seed=0) -> None:
    q, qd, qdd = random_states(np.random.default_rng(seed), arm.n, 100)
    Wb = np.asarray(bp.W_base.map(100)(q.T, qd.T, qdd.T)).reshape(arm.n, 100, bp.count).transpose(1, 0, 2)
    assert scaled_error(Wb @ bp.beta, arm.inverse_dynamics(q, qd, qdd)) < TOL_EXACT


def check_full_column_rank(arm, bp, seed=1) -> None:
    q, qd, qdd = random_states(np.random.default_rng(seed), arm.n, 200)
    Wb = np.vstack([np.asarray(bp.W_base(q[k], qd[k], qdd[k])) for k in range(200)])
    s = np.linalg.svd(Wb / np.linalg.norm(Wb, axis=0), compute_uv=False)
    assert s[-1] > 1e-6 * s[0]
    assert np.linalg.matrix_rank(Wb) == bp.count


# ------------------------------------------------------------------------------- planar 2R


def test_planar2r_count_and_names():
    arm = robot("planar2r")
    bp = base_parameters(arm)
    assert bp.count == 6 == svd_rank(arm)
    assert bp.names == ("mcx1R", "mcy1", "Izz1R", "mcx2R", "mcy2", "Izz2R")
    check_reproduces_dynamics(arm, bp)
    check_full_column_rank(arm, bp)


def test_planar2r_regrouping_is_exact():
    """Standard DH, frames at the link tips: Izz2R = Izz2 - d2^2 m2 and Izz1R = Izz1 - d1^2 (m1 + m2)."""
    arm = robot("planar2r", d1=0.7, d2=0.3)
    bp = base_parameters(arm)
    K = dict(zip(bp.names, bp.K, strict=True))
    col = {name: j for j, name in enumerate(bp.parameter_names)}
    assert K["Izz2R"][col["m2"]] == pytest.approx(-0.3**2, abs=1e-14)
    assert K["mcx2R"][col["m2"]] == pytest.approx(0.3, abs=1e-14)
    assert K["Izz1R"][col["m1"]] == pytest.approx(-0.7**2, abs=1e-14)
    assert K["Izz1R"][col["m2"]] == pytest.approx(-0.7**2, abs=1e-14)
    assert K["mcx1R"][col["m2"]] == pytest.approx(0.7, abs=1e-14)
    assert "Izz2R = Izz2 - 0.09*m2" in bp.regrouping


def test_planar2r_friction_adds_two_per_joint():
    arm = robot("planar2r", friction=True)
    bp = base_parameters(arm)
    assert bp.count == 10 == svd_rank(arm)
    assert {"fv1", "fc1", "fv2", "fc2"} <= set(bp.names)
    check_reproduces_dynamics(arm, bp)


# ------------------------------------------------------------------------------- PUMA 560


def test_puma_count(puma):
    arm, bp = puma
    assert bp.count == 36 == svd_rank(arm)
    assert len(bp.zero_columns) == 9  # link 1: everything but Iyy1 (its rotation axis), m1 and mc1
    assert bp.certificate.gap > 1e10
    assert bp.certificate.relation_residual < 1e-12


def test_puma_reproduces_dynamics(puma):
    check_reproduces_dynamics(*puma)
    check_full_column_rank(*puma)


def test_puma_regrouping_coefficients_are_dh_constants(puma):
    """Coefficients are closed forms of the DH lengths (a2 = 0.4318, a3 = 0.0203) to rounding."""
    arm, bp = puma
    a2, a3 = 0.4318, 0.0203
    K = dict(zip(bp.names, bp.K, strict=True))
    col = {name: j for j, name in enumerate(bp.parameter_names)}
    for m in ("m3", "m4", "m5", "m6"):
        assert K["mcx2R"][col[m]] == pytest.approx(a2, abs=1e-13)
        assert K["Ixx2R"][col[m]] == pytest.approx(a2**2, abs=1e-13)
        assert K["mcx3R"][col[m]] == pytest.approx(a3, abs=1e-13)
    assert K["Ixx2R"][col["Iyy2"]] == -1.0
    np.testing.assert_allclose(bp.K @ arm.parameters, bp.beta, rtol=0, atol=1e-15)


def test_puma_with_rotors_and_friction(puma_rotors):
    arm, bp = puma_rotors
    assert bp.count == 36 + 12 + 4 == svd_rank(arm)
    assert "Ia1" not in bp.names and "Ia2" not in bp.names
    assert any(line.startswith("Iyy1R = ") and line.endswith("+ Ia1") for line in bp.regrouping)
    check_reproduces_dynamics(*puma_rotors)


# ------------------------------------------------------------------------------- other chains


@pytest.mark.parametrize("name", ["onelink", "scara"])
def test_zoo(name):
    arm = robot(name, friction=True, motor_inertia=True)
    bp = base_parameters(arm)
    assert bp.count == svd_rank(arm)
    check_reproduces_dynamics(arm, bp)
    check_full_column_rank(arm, bp)


@pytest.mark.parametrize("seed", range(6))
def test_random_chains(seed):
    arm = robot_from_dh(random_chain(seed), friction=seed % 3 == 0, motor_inertia=seed % 2 == 0)
    bp = base_parameters(arm)
    assert bp.count == svd_rank(arm)
    check_reproduces_dynamics(arm, bp, seed)
    check_full_column_rank(arm, bp, seed)


def test_result_is_a_named_function_and_frozen(puma):
    _, bp = puma
    f = bp.W_base
    assert (f.name(), f.name_in(), f.name_out()) == ("regressor_base", ["q", "qd", "qdd"], ["Wb"])
    assert f.size_out(0) == (6, 36)
    assert bp.E is bp.K
    with pytest.raises(AttributeError):
        bp.beta = None  # type: ignore[misc]


def test_symbolic_robot_is_refused():
    arm = robot("planar2r", symbolic=("m1",))
    with pytest.raises(ModelError, match="symbolic"):
        base_parameters(arm)


# ------------------------------------------------------------------------------- discovery and its fallback


@pytest.mark.parametrize("name", ["planar2r", "scara"])
def test_verification_rejects_spurious_relations(name, monkeypatch):
    """Discovery on 2 states finds spurious relations; the unisolvent set rejects them and the
    fallback (discovery on the whole evaluation set) recovers the true count."""
    import designkit.models.base_parameters as module

    arm = robot(name, friction=True)
    true = base_parameters(arm)
    assert true.certificate.discovery_states == 500
    original = module._sample_states
    monkeypatch.setattr(module, "_sample_states", lambda n, count: original(n, 2))
    fallback = base_parameters(arm)
    assert fallback.certificate.discovery_states == fallback.certificate.n_states
    assert fallback.count == true.count == svd_rank(arm)
    np.testing.assert_allclose(fallback.K, true.K, atol=1e-12)
