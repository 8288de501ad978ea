"""The family's judgements as the theorems state them: the tracking error's decreasing windowed bound, a full
adaptation gain in the update and in ``V``, and the warnings on starting estimates no arm has."""

from __future__ import annotations

import numpy as np
import pytest

from designkit.families.adaptive_computed_torque.checks import decreasing, window_maxima
from designkit.families.adaptive_computed_torque.consistency import violations
from designkit.families.adaptive_computed_torque.laws import Adaptation, adaptive_law
from designkit.models.robot_plant import zoo_plant

T = np.linspace(0.0, 10.0, 10_001)


def _maxima_by_hand(t, e, window):
    """Window maxima ending at the run's end, counted with a plain loop."""
    out, end = [], t[-1]
    while end - window >= t[0] - 1e-9:
        out.append(max(abs(x) for x, s in zip(e, t, strict=True) if end - window < s <= end
                       or (end - window <= t[0] + 1e-9 and s == t[0])))
        end -= window
    return np.array(out[::-1])


def test_window_maxima_against_a_plain_loop():
    e = np.exp(-0.3 * T) * np.sin(2 * np.pi * T)
    ends, m = window_maxima(T, e[:, None], 1.0)
    np.testing.assert_allclose(ends, np.arange(1.0, 10.5, 1.0))
    np.testing.assert_allclose(m[:, 0], _maxima_by_hand(T, e, 1.0), rtol=0, atol=0)


@pytest.mark.parametrize(("name", "e", "expected"), [
    ("decaying", np.exp(-0.3 * T) * np.sin(2 * np.pi * T), True),
    ("rising then decaying", T * np.exp(-T) * np.sin(2 * np.pi * T), True),
    ("constant amplitude", 0.01 * np.sin(2 * np.pi * T), False),
    ("growing", 1e-3 * np.exp(0.1 * T) * np.sin(2 * np.pi * T), False),
    ("decaying to a floor", np.maximum(np.exp(-3 * T), 1e-9) * np.cos(2 * np.pi * T), True),
    ("a late bump", np.exp(-0.3 * T) * np.sin(2 * np.pi * T) + 0.5 * np.exp(-((T - 7.5) / 0.2) ** 2), False),
])
def test_decreasing_bound(name, e, expected):
    _, m = window_maxima(T, e[:, None], 1.0)
    ok, why = decreasing(m[:, 0], 0.0, 1e-6)
    assert ok is expected, why


def test_tolerance_admits_a_small_rise_only():
    m = np.array([1.0, 0.5, 0.52, 0.3])
    assert decreasing(m, 0.0, 1e-6)[0] is False
    assert decreasing(m, 0.05, 1e-6)[0] is True
    assert decreasing(m, 0.03, 1e-6)[0] is False


def test_the_old_five_percent_rule_is_not_the_judgement():
    """A run whose error falls period by period to 14 % of its peak passes: the theorem promises e -> 0 as t -> oo,
    not a size at a finite time."""
    e = np.exp(-0.2 * T) * np.sin(2 * np.pi * T)
    _, m = window_maxima(T, e[:, None], 1.0)
    assert m[-1, 0] / m.max() > 0.05
    assert decreasing(m[:, 0], 0.0, 1e-6)[0]


@pytest.mark.parametrize("scheme", ["slotine_li", "craig"])
def test_full_gain_matrix_in_the_update_and_in_v(scheme):
    """``p^' = K W_a' x`` with a full ``K``: the update at random states against ``K`` times the update with
    ``K = I`` (the columns ``W_a`` of the command found by central differences in ``p^`` for Slotine-Li)."""
    plant = zoo_plant("planar2r")
    K = np.array([[2.0, 0.7], [0.7, 1.5]])
    kw = ({"K1": (), "K2": (), "psi": (), "Lambda": (10.0, 8.0), "KD": (5.0, 1.0)} if scheme == "slotine_li"
          else {"K1": (100.0, 100.0), "K2": (20.0, 20.0), "psi": (0.1, 0.1)})
    full = adaptive_law(plant, Adaptation(names=("m1", "m2"), initial=(7.0, 4.5), gain=tuple(np.diag(K)),
                                          gain_matrix=tuple(map(tuple, K)), scheme=scheme, **kw))
    unit = adaptive_law(plant, Adaptation(names=("m1", "m2"), initial=(7.0, 4.5), gain=(1.0, 1.0), scheme=scheme,
                                          **kw))
    rng = np.random.default_rng(1)
    for _ in range(3):
        y, xc, r = rng.uniform(-1, 1, 4), rng.uniform([4.5, 2.7], [8.0, 5.0]), rng.uniform(-1, 1, 6)
        got = np.asarray(full.derivative(y, xc, [], r, np.ones(2))).ravel()
        base = np.asarray(unit.derivative(y, xc, [], r, np.ones(2))).ravel()
        np.testing.assert_allclose(got, K @ base, rtol=1e-10)
        if scheme == "slotine_li":
            h = 1e-4
            Wa = np.column_stack([(np.asarray(full.command(y, xc + h * d, [], r)).ravel()
                                   - np.asarray(full.command(y, xc - h * d, [], r)).ravel()) / (2 * h)
                                  for d in np.eye(2)])
            e, ed = r[0:2] - y[0:2], r[2:4] - y[2:4]
            s = ed + np.array([10.0, 8.0]) * e
            np.testing.assert_allclose(got, K @ Wa.T @ s, rtol=1e-7)
        # V's parameter term is phi' K^-1 phi (scaled 1/2 in Slotine-Li): compare with the unit-gain law's V
        v_full = float(np.asarray(full.signals(y, xc, [], r)).ravel()[0])
        v_unit = float(np.asarray(unit.signals(y, xc, [], r)).ravel()[0])
        phi = np.array([5.0, 3.0]) - xc
        half = 0.5 if scheme == "slotine_li" else 1.0
        assert v_full - v_unit == pytest.approx(half * (phi @ np.linalg.solve(K, phi) - phi @ phi), rel=1e-9)


NAMES = ["m1", "mcx1", "mcy1", "mcz1", "Ixx1", "Ixy1", "Ixz1", "Iyy1", "Iyz1", "Izz1", "fv1"]
TRUE = [1.0, 0.5, 0.0, 0.0, 0.06, 0.0, 0.0, 0.31, 0.0, 0.37, 0.2]


def _with(**values):
    est = list(TRUE)
    for k, v in values.items():
        est[NAMES.index(k)] = v
    return est


@pytest.mark.parametrize(("change", "words"), [
    ({"m1": -1.0}, "a negative mass"),
    ({"Izz1": -2.0}, "not positive semidefinite"),
    ({"Izz1": 0.5}, "triangle inequality"),  # 0.5 > Ixx + Iyy = 0.37
    ({"mcx1": 2.0}, "pseudo-inertia"),  # |h|^2/m = 4 above the second moment about x
    ({"fv1": -0.1}, "negative viscous friction of joint 1"),
])
def test_impossible_starts_are_named(change, words):
    found = violations(NAMES, TRUE, _with(**change))
    assert len(found) == 1 and words in found[0][1]
    assert found[0][0] == next(iter(change))


def test_possible_starts_and_inconsistent_arms_are_not_warned():
    assert violations(NAMES, TRUE, _with(m1=3.0, Izz1=0.36)) == []
    bad = _with(Izz1=0.5)  # the arm itself breaks the triangle inequality: the generic warning says so
    assert violations(NAMES, bad, [*bad[:9], 0.6, bad[10]]) == []


def test_gain_keys_through_the_spec():
    """``gain_matrix`` reaches the design as given; ``combination`` with ``gain`` as ``T^-1 G T^-T`` (NumPy)."""
    from designkit.pipeline import design as design_of
    from designkit.schema.loader import parse_spec

    head = ("name: g\nplant: {kind: robot, robot: planar2r}\nsimulation: {duration: 2, trajectory: {kind: sine}}\n"
            "controller: {kind: adaptive_computed_torque, scheme: slotine_li, Lambda: 10, KD: [5, 1], "
            "adapt: [m1, m2], initial: {m1: 7.0, m2: 4.5}, ")
    K = [[2.0, 0.7], [0.7, 1.5]]
    d = design_of(parse_spec(head + f"gain_matrix: {K}}}\n"))
    np.testing.assert_array_equal(d.data.adaptation.K(), K)
    assert [d.gains["K_m1"], d.gains["K_m2"]] == [2.0, 1.5]
    T, G = np.array([[1.0, 1.0], [0.0, 2.0]]), np.diag([0.3, 0.4])
    d = design_of(parse_spec(head + f"combination: {T.tolist()}, gain: [0.3, 0.4]}}\n"))
    Tinv = np.linalg.inv(T)
    np.testing.assert_allclose(d.data.adaptation.K(), Tinv @ G @ Tinv.T, rtol=1e-14)
    assert any("T⁻¹ G T⁻ᵀ" in n for n in d.notes)
