"""Certificates: strict-JSON round trip, and the NumPy re-check deciding on its own (a corrupted
certificate fails, whoever produced it)."""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest
import scipy.linalg

from designkit.verification.certificate import Certificate, Recheck, array_from_json, load, to_json
from designkit.verification.lmi import KypCertificate, LyapunovCertificate
from designkit.verification.lp import Polytope
from designkit.verification.lp_certificates import FarkasCertificate, FeasiblePointCertificate, LowerBoundCertificate
from designkit.verification.lyapunov import lyapunov_equation, lyapunov_lmi

A3 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-40.0, -30.0, -8.0]])  # poles well in the left half plane
B3 = np.array([[0.0, 1.0], [0.0, 0.0], [1.0, 1.0]])
Q3 = np.diag([1.0, 2.0, 3.0])
P_KYP = scipy.linalg.solve_continuous_lyapunov(A3.T, -Q3)  # A'P + PA = -Q, built without any solver
BOX = Polytope.box(["a", "b"], [0.0, -1.0], [2.0, 1.0])
C_LP = np.array([-1.0, 2.0])  # 5 - a + 2 b >= 5 - 2 - 2 = 1 on the box
# exact multipliers for the box rows [I; -I]: lam_upper = max(-c, 0), lam_lower = max(c, 0)
LAM = np.concatenate([np.maximum(-C_LP, 0.0), np.maximum(C_LP, 0.0)])
G2 = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])


def _lyapunov() -> LyapunovCertificate:
    return LyapunovCertificate((A3,), lyapunov_equation(A3))


def _kyp() -> KypCertificate:
    return KypCertificate(A3, B3, B3.T @ P_KYP, P_KYP)


def _bound() -> LowerBoundCertificate:
    lo, hi = BOX.bounding_box()
    return LowerBoundCertificate(5.0, C_LP, BOX.A, BOX.b, LAM, lo, hi)


def _point() -> FeasiblePointCertificate:
    return FeasiblePointCertificate(G2, np.array([1.0, 1.0, 1.0]), np.array([0.2, 0.3]))


def _farkas() -> FarkasCertificate:
    # x1 <= 1, x2 <= 1, x1 + x2 >= 3: the sum of the three rows reads 0 <= -1
    return FarkasCertificate(G2, np.array([1.0, 1.0, -3.0]), np.array([1.0, 1.0, 1.0]))


VALID: dict[str, Callable[[], Certificate]] = {
    "lyapunov": _lyapunov,
    "kyp": _kyp,
    "lp_lower_bound": _bound,
    "feasible_point": _point,
    "farkas": _farkas,
}


@pytest.mark.parametrize("kind", sorted(VALID))
def test_round_trip_through_strict_json_keeps_the_verdict(kind):
    cert = VALID[kind]()
    assert isinstance(cert, Certificate)
    assert cert.kind == kind
    rc = cert.recheck()
    assert rc.ok, rc.detail
    text = json.dumps(cert.to_dict(), allow_nan=False)
    again = load(json.loads(text))
    assert type(again) is type(cert)
    rc2 = again.recheck()
    assert rc2.ok and rc2.margin == pytest.approx(rc.margin, rel=1e-12, abs=1e-300)
    json.dumps(rc.to_dict(), allow_nan=False)  # the re-check's numbers are JSON too


def _replace(cert, **changes):
    data = cert.to_dict()
    data.update({k: to_json(v) for k, v in changes.items()})
    return load(data)


CORRUPT: dict[str, tuple[Callable[[], Certificate], str]] = {
    "lyapunov: -P": (lambda: _replace(_lyapunov(), P=-lyapunov_equation(A3)), "no positive eigenvalue"),
    "lyapunov: P = I is no Lyapunov matrix here": (lambda: _replace(_lyapunov(), P=np.eye(3)), "fail by"),
    "lyapunov: P not finite": (lambda: _replace(_lyapunov(), P=np.full((3, 3), np.nan)), "not finite"),
    "kyp: 2 P breaks P B = C'": (lambda: _replace(_kyp(), P=2.0 * P_KYP), "'equality'"),
    "kyp: B without full rank": (
        lambda: KypCertificate(A3, np.c_[B3[:, :1], B3[:, :1]], np.c_[B3[:, :1], B3[:, :1]].T @ P_KYP, P_KYP),
        "'rank_B'",
    ),
    "kyp: unstable A": (lambda: KypCertificate(-A3, B3, B3.T @ P_KYP, P_KYP), "'lyapunov'"),
    "lp: negative multiplier": (lambda: _replace(_bound(), lam=LAM - 0.1), ">= 0"),
    "lp: multipliers of the wrong rows": (lambda: _replace(_bound(), lam=LAM[::-1]), "< required"),
    "lp: condition not positive": (lambda: _replace(_bound(), constant=0.5), "< required"),
    "point: outside": (lambda: _replace(_point(), x=np.array([0.2, 1.3])), "violates constraint 1"),
    "farkas: -y": (lambda: _replace(_farkas(), y=-np.ones(3)), ">= 0"),
    "farkas: feasible system": (lambda: _replace(_farkas(), h=np.array([1.0, 1.0, 0.0])), "h . y = 2"),
    # h . y = -0.5 < 0 but G'y = (0, 0.5): only the residual is wrong, 0.5 / (1 + 1.5 + sqrt 2) = 0.13
    "farkas: y not in null(G')": (lambda: _replace(_farkas(), y=np.array([1.0, 1.5, 1.0])), "= 0.13"),
}


@pytest.mark.parametrize("name", sorted(CORRUPT))
def test_corrupted_certificates_fail_their_recheck(name):
    factory, reason = CORRUPT[name]
    rc = factory().recheck()
    assert rc.ok is False
    assert not rc.margin >= 0
    assert reason in rc.detail, rc.detail


def test_lmi_certificates_agree_with_an_independent_numpy_judgement():
    """What the KYP re-check accepts, a direct NumPy look at the same matrices accepts too."""
    rc = _kyp().recheck()
    assert rc.values["equality_residual"] < 1e-12
    assert np.min(np.linalg.eigvalsh(P_KYP)) > 0
    assert np.max(np.linalg.eigvalsh(A3.T @ P_KYP + P_KYP @ A3)) < 0
    check = lyapunov_lmi(A3)
    assert LyapunovCertificate((A3,), np.array(check.certificate["P"])).recheck().ok


def test_recheck_is_consistent_by_construction():
    with pytest.raises(ValueError):
        Recheck(True, -1.0)
    with pytest.raises(ValueError):
        Recheck(False, 0.5)
    assert Recheck(False, float("nan")).to_dict()["margin"] is None


def test_json_helpers():
    assert to_json({"z": np.array([1 + 2j]), "x": np.float64(np.inf), "b": np.bool_(True)}) == {
        "z": [[1.0, 2.0]], "x": None, "b": True,
    }
    back = array_from_json([[1.0, None]])
    assert back.shape == (1, 2) and np.isnan(back[0, 1])
    with pytest.raises(ValueError):
        load({"kind": "no_such_kind"})
