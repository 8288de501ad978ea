"""The one-state fast path of Robot.inverse_dynamics gives the batched call's numbers and Pinocchio's RNEA."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from designkit.models.robots import robot


def test_one_state_equals_the_batch_and_the_plain_list_call():
    r = robot("puma560")
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.normal(size=(3, 40, 6))
    batch = r.inverse_dynamics(q, qd, qdd)
    for k in range(40):
        np.testing.assert_array_equal(r.inverse_dynamics(q[k], qd[k], qdd[k]), batch[k])
    assert r.inverse_dynamics(list(q[0]), qd[0], qdd[0]).shape == (6,)  # a list takes the general path


def test_one_state_matches_pinocchio_rnea():
    pin = pytest.importorskip("pinocchio")
    from tests.models.support import pinocchio_model

    r = robot("puma560")
    model, _ = pinocchio_model(r.description)
    data = model.createData()
    rng = np.random.default_rng(4)
    for _ in range(20):
        q, qd, qdd = rng.normal(size=(3, 6))
        want = pin.rnea(model, data, q, qd, qdd)
        np.testing.assert_allclose(r.inverse_dynamics(q, qd, qdd), want, rtol=1e-10, atol=1e-10)


def test_one_state_calls_from_threads_do_not_share_buffers():
    r = robot("puma560")
    rng = np.random.default_rng(5)
    states = rng.normal(size=(8, 3, 6))
    want = [r.inverse_dynamics(s[0][None], s[1][None], s[2][None])[0] for s in states]
    got: dict[int, list] = {}

    def work(i: int) -> None:
        got[i] = [r.inverse_dynamics(*states[(i + k) % 8]) for k in range(200)]

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i, rows in got.items():
        for k, row in enumerate(rows):
            np.testing.assert_array_equal(row, want[(i + k) % 8])
