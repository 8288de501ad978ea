"""Physical consistency of inertial parameters (designkit.models.physical) and the consistent-inertia option.

Independent routes: the published PUMA 560 numbers (Armstrong, Khatib & Burdick 1986, as shipped) checked by
hand; the projection against SciPy's SLSQP solving the same least-squares problem from scratch; the change in
M(q) against the bound a rank-one inertia change allows; Pinocchio (and MuJoCo or Drake when installed) loading
the exported URDF.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

import designkit as dk
from designkit.errors import ModelError
from designkit.models.physical import check_inertia, nearest_consistent
from designkit.models.robot_plant import zoo_plant
from designkit.models.robots.puma560 import description as puma_description
from designkit.models.summary import model_summary
from designkit.models.urdf import description_to_urdf


def test_the_published_puma_breaks_the_triangle_inequality_on_links_1_and_3():
    c = check_inertia(puma_description())
    assert not c.consistent
    by_link = {v.link: v for v in c.violations}
    assert sorted(by_link) == [1, 3]
    assert by_link[1].amount == pytest.approx(0.35)                    # moments (0, 0, 0.35): 0 + 0 < 0.35
    assert by_link[3].amount == pytest.approx(0.086 - (0.066 + 0.0125))  # 0.066 + 0.0125 < 0.086
    text = " ".join(c.sentences())
    assert "link 1 (joint1)" in text and "link 3 (joint3)" in text and "no mass" in text


@pytest.mark.parametrize("name", ["planar2r", "scara", "onelink"])
def test_the_other_zoo_robots_are_consistent(name):
    assert check_inertia(dk.robot(name).description).consistent


def _triangle_ok(moments):
    m = np.sort(moments)
    return m[0] >= -1e-12 and m[0] + m[1] >= m[2] - 1e-12


def test_raise_keeps_every_moment_as_a_lower_bound_and_changes_m_by_a_rank_one_term():
    published = dk.robot("puma560")
    fixed = dk.robot("puma560", consistent_inertia="raise")
    assert check_inertia(fixed.description).consistent
    _, changes = nearest_consistent(puma_description(), "raise")
    delta = {c.link: np.array(c.after) - np.array(c.before) for c in changes}
    for d in delta.values():
        assert np.all(d >= 0) and np.count_nonzero(d) == 1  # one moment raised, none lowered
    assert delta[3].sum() == pytest.approx(0.0075)
    q = np.random.default_rng(4).uniform(-3, 3, size=(500, 6))
    dM = fixed.mass_matrix(q) - published.mass_matrix(q)
    # a moment raised by delta about a unit axis e adds delta (J_w' e)(J_w' e)' with |J_w' e| entries <= 1
    bound = sum(d.sum() for d in delta.values())
    assert np.abs(dM).max() <= bound + 1e-12
    assert np.linalg.eigvalsh(dM).min() >= -1e-12
    # link 1 only ever turns about the axis carrying its 0.35 kg*m^2: raising another of its moments changes nothing
    from dataclasses import replace

    raised, _ = nearest_consistent(puma_description(), "raise")
    links = list(puma_description().links)
    links[0] = raised.links[0]
    only_link1 = dk.Robot(replace(puma_description(), links=tuple(links)))
    assert np.abs(only_link1.mass_matrix(q) - published.mass_matrix(q)).max() < 1e-12


def test_nearest_is_the_least_squares_projection_onto_the_consistent_cone():
    _, changes = nearest_consistent(puma_description(), "nearest")
    for c in changes:
        before = np.array(c.before)
        cons = [{"type": "ineq", "fun": lambda x, i=i: x[(i + 1) % 3] + x[(i + 2) % 3] - x[i]} for i in range(3)]
        cons += [{"type": "ineq", "fun": lambda x, i=i: x[i]} for i in range(3)]
        ref = minimize(lambda x, b=before: np.sum((x - b) ** 2), before, constraints=cons, method="SLSQP",
                       options={"ftol": 1e-15, "maxiter": 500}).x
        assert np.array(c.after) == pytest.approx(ref, abs=1e-7)
        assert _triangle_ok(np.array(c.after))


def test_the_plant_option_and_the_spec_field():
    plant = zoo_plant("puma560", consistent_inertia="raise")
    assert check_inertia(plant.robot.description).consistent
    assert not check_inertia(zoo_plant("puma560").robot.description).consistent
    with pytest.raises(ModelError) as err:
        nearest_consistent(puma_description(), "closest")
    assert err.value.path == "method"
    from designkit.schema.loader import parse_spec
    from designkit.spec.plant_builder import plant_from_spec

    loaded = parse_spec("name: c\nplant: {kind: robot, robot: puma560, consistent_inertia: raise}\n"
                        "controller: {kind: computed_torque, poles: [-20, -20]}\n")
    assert check_inertia(plant_from_spec(loaded.spec.plant).robot.description).consistent


def test_the_summary_and_the_urdf_header_state_it():
    assert "not physically consistent" in model_summary(dk.robot("puma560"), timing=False, base=False)
    assert "are physically consistent" in model_summary(dk.robot("planar2r"), timing=False, base=False)
    header = description_to_urdf(puma_description()).splitlines()[3]
    assert header.startswith("  <!--") and "link 3 (joint3)" in header and "--" not in header[6:-4]


def _exported(tmp_path, method):
    path = tmp_path / f"puma560-{method}.urdf"
    path.write_text(description_to_urdf(dk.robot("puma560", consistent_inertia=method).description))
    return path


def test_pinocchio_loads_the_consistent_export_with_the_same_inertia_matrix(tmp_path):
    pin = pytest.importorskip("pinocchio")
    path = _exported(tmp_path, "raise")
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    ours = dk.robot("puma560", consistent_inertia="raise")
    for q in np.random.default_rng(7).uniform(-2, 2, size=(20, 6)):
        config = np.concatenate([[math.cos(v), math.sin(v)] if j.nq == 2 else [v]
                                 for v, j in zip(q, model.joints[1:], strict=True)])
        M = pin.crba(model, data, config)
        M = np.triu(M) + np.triu(M, 1).T
        assert np.allclose(M, ours.mass_matrix(q), rtol=1e-10, atol=1e-12)


def test_mujoco_loads_the_consistent_export(tmp_path):
    mujoco = pytest.importorskip("mujoco", reason="MuJoCo is not installed (not a dependency)")
    model = mujoco.MjModel.from_xml_path(str(_exported(tmp_path, "raise")))
    assert model.nbody >= 7


def test_drake_loads_the_consistent_export(tmp_path):
    pytest.importorskip("pydrake", reason="Drake is not installed (not a dependency)")
    from pydrake.multibody.parsing import Parser
    from pydrake.multibody.plant import MultibodyPlant

    plant = MultibodyPlant(0.0)
    Parser(plant).AddModels(str(_exported(tmp_path, "raise")))
    plant.Finalize()
    assert plant.num_positions() == 6
