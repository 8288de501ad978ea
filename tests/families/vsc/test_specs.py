"""The example specs through the CLI: the JSON contract, bad input (exit 2), the schema round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest

from designkit.cli import main
from designkit.models.elastic import elastic_state_space
from designkit.models.robots.elastic_link import DEFAULTS
from tests.cli_input import assert_bad_input
from tests.families.vsc.common import ELASTIC_SPEC, LINK_SPEC, NARROW_SPEC


def _synth(path, tmp_path, capsys) -> tuple[int, dict]:
    code = main(["synth", str(path), "--json", "--no-studies", "--out", str(tmp_path / "out")])
    return code, json.loads(capsys.readouterr().out)


def test_elastic_joint_json_contract(tmp_path, capsys):
    code, data = _synth(ELASTIC_SPEC, tmp_path, capsys)
    assert code == 0 and data["verified"] is True
    c = [data["c1"], data["c2"], data["c3"], data["c4"]]
    assert data["c2"] == 1.0 and data["c"] == c
    # sigma = c1 x1 + ... + c4 x4 with the order [theta_m, theta_m', theta_l, theta_l']: the reduced system on
    # sigma = 0 (x2 eliminated) has the requested poles, computed here by hand from the model's state space
    A, _ = elastic_state_space(DEFAULTS)
    keep = [0, 2, 3]
    Ar = A[np.ix_(keep, keep)] + np.outer(A[keep, 1], -np.array(c)[keep])
    assert np.sort(np.linalg.eigvals(Ar).real) == pytest.approx([-12, -10, -8], rel=1e-9)
    assert len(data["alpha"]) == len(data["beta"]) == 4 and data["delta"] > 0
    lr = data["vsc"]["l_ranges"]
    for i in range(4):
        lo, hi = lr[f"l_{i + 1}"]
        assert data["alpha"][i] < lo <= hi < data["beta"][i]
    statuses = {ch["name"]: ch["status"] for ch in data["checks"]}
    assert all(statuses[n] == "PASS" for n in ("vsc_gains", "vsc_relay", "vsc_orientation", "vsc_band",
                                                 "vsc_sliding_poles", "vsc_equivalent_control", "vsc_offset"))


def test_link_json_contract(tmp_path, capsys):
    code, data = _synth(LINK_SPEC, tmp_path, capsys)
    assert code == 0 and data["c"] == [5.0, 1.0] and "c1" not in data
    assert data["delta"] == pytest.approx(1.2)  # (1 + 0.2) x 1 N*m, cD/cB = 1 (matched)


def test_narrow_gains_exit_1_and_say_what_would_do(tmp_path, capsys):
    code, data = _synth(NARROW_SPEC, tmp_path, capsys)
    assert code == 1
    gains = next(ch for ch in data["checks"] if ch["name"] == "vsc_gains")
    assert gains["status"] == "FAIL"
    assert "beta_1 = 45 is not above max l_1 = 48.11 (at Km = 1.8, J2 = 0.45) by 3.11" in gains["detail"]
    assert "beta_1 >= 57.73 with the 20 % margin" in gains["detail"]


BAD = {
    "pole_rhp": (("[-8, -10, -12]", "[-8, -10, 0.5]"), "controller.sliding_poles[2]: must have negative real part"),
    "pole_zero": (("[-8, -10, -12]", "[-8, -10, 0]"), "controller.sliding_poles[2]"),
    "delta_zero": (("  margin: 0.2\n", "  margin: 0.2\n  relay_amplitude: 0\n"),
                   "controller.relay_amplitude: must be"),
    "delta_negative": (("  margin: 0.2\n", "  margin: 0.2\n  relay_amplitude: -1\n"),
                       "controller.relay_amplitude: must be"),
    "poles_count": (("[-8, -10, -12]", "[-8, -10]"), "controller.sliding_poles: the elastic_joint plant has 4 "
                    "states"),
    "uncontrollable": (("  kind: elastic_joint\n", "  kind: elastic_joint\n  KR: 1.0e-6\n"),
                       "plant.KR: makes the plant uncontrollable"),
    "alpha_above_beta": (("  margin: 0.2\n", "  margin: 0.2\n  alpha: [45, -0.3, -45, 0.6]\n"
                          "  beta: [40, -0.2, -40, 0.8]\n"), "controller.alpha[0]: alpha_1 = 45 must be below"),
    "alpha_count": (("  margin: 0.2\n", "  margin: 0.2\n  alpha: [1, 2]\n"), "controller.alpha: one gain per "
                    "state"),
    "gravity": (("  kind: elastic_joint\n", "  kind: elastic_joint\n  mgl: 1.0\n"), "plant.mgl"),
    "band_and_layer": (("  margin: 0.2\n", "  margin: 0.2\n  chattering_band: 0.01\n  boundary_layer: 0.01\n"),
                       "controller.boundary_layer"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_input_exits_2_with_the_key_path(case, tmp_path, capsys):
    (old, new), message = BAD[case]
    text = ELASTIC_SPEC.read_text()
    assert old in text
    assert_bad_input(tmp_path, capsys, text.replace(old, new, 1), message)


def test_no_relay_and_no_perturbation_is_refused(tmp_path, capsys):
    text = ELASTIC_SPEC.read_text().replace("  perturbation: {value: 0.2, time: 1.0}\n", "")
    assert_bad_input(tmp_path, capsys, text, "controller.relay_amplitude: give the relay amplitude")


@pytest.mark.parametrize("path", [ELASTIC_SPEC, LINK_SPEC, NARROW_SPEC], ids=["elastic", "link", "narrow"])
def test_example_specs_round_trip_through_the_json_schema(path):
    import jsonschema

    from designkit.schema.loader import load_spec
    from designkit.schema.spec import Spec

    loaded = load_spec(path)
    data = json.loads(loaded.spec.model_dump_json())
    jsonschema.validate(data, Spec.model_json_schema())
    assert Spec.model_validate(data) == loaded.spec


def test_no_linear_check_is_offered(elastic_result):
    d = elastic_result.design
    assert d.linearization.kind == "none" and d.closed_loop is None
    names = {c.name for c in elastic_result.checks}
    assert not names & {"pole_placement", "routh_hurwitz", "lyapunov", "loop_margins", "robustness", "designed_loop"}


def test_uncertain_ratio_is_judged_on_the_proven_enclosure(tmp_path, capsys):
    """R1 uncertain: l_1 and l_3 are certified on their enclosures (vsc_gains_enclosed), the others at vertices;
    an alpha_1 above a value of l_1 attained inside the box fails."""
    text = ELASTIC_SPEC.read_text().replace("Km: [1.8, 2.2]}", "R1: [0.019, 0.021]}")
    path = tmp_path / "r1.yaml"
    path.write_text(text)
    code, data = _synth(path, tmp_path, capsys)
    checks = {ch["name"]: ch for ch in data["checks"]}
    assert code == 0 and checks["vsc_gains_enclosed"]["status"] == "PASS"
    assert data["vsc"]["l_methods"] == {"l_1": "enclosure", "l_2": "vertices", "l_3": "enclosure", "l_4": "vertices"}
    lo, hi = data["vsc"]["l_ranges"]["l_1"]
    # independent: l_1 = (tau1/Km) KR (R1^2/J1 - c4 R2^2/J2) is largest at R1 = 0.021, J2 = 0.45 and smallest at
    # R1 = 0.019, J2 = 0.55 (c4 < 0: both terms grow with R1 and fall with J2)
    c4, p = data["c4"], DEFAULTS

    def l1(R1, J2):
        return p.tau1 / p.Km * p.KR * (R1**2 / p.J1 - c4 * p.R2**2 / J2)
    assert lo <= l1(0.019, 0.55) <= lo + 1e-5 * abs(lo) and hi - 1e-5 * abs(hi) <= l1(0.021, 0.45) <= hi
    gains = "  alpha: [40, -0.3, -57, 0.4]\n  beta: [57, -0.15, -29, 0.9]\n"
    bad = text.replace("  margin: 0.2\n", "  margin: 0.2\n" + gains)
    path.write_text(bad)
    code, data = _synth(path, tmp_path, capsys)
    enc = next(ch for ch in data["checks"] if ch["name"] == "vsc_gains_enclosed")
    assert code == 1 and enc["status"] == "FAIL" and "alpha_1 = 40 >= 38.7989" in enc["detail"]


def test_narrow_gains_diagnosis_names_the_fix(narrow_result):
    from designkit.families.vsc.diagnoses import diagnose

    gains = next(c for c in narrow_result.checks if c.name == "vsc_gains")
    cause, fix = diagnose(narrow_result, gains)
    assert "alpha_1 = 40 is not below min l_1 = 38.82" in cause
    assert "alpha_1 <= 29.2 (any value below 38.82 meets the condition)" in fix
    assert "beta_1 >= 57.73 (any value above 48.11 meets the condition)" in fix


def test_the_box_holds_the_nominal_plant_and_the_plant_change():
    from designkit.pipeline import run
    from designkit.schema.loader import parse_spec

    text = LINK_SPEC.read_text().replace("  perturbation: {value: 1.0, time: 1.0}\n", "  perturbation: {value: 1.0, "
                                         "time: 1.0}\n  plant_change: {time: 2.0, values: {Km: 3.0}}\n")
    result = run(parse_spec(text))
    assert {k: list(v) for k, v in result.design.data.box.items()} == {"Km": [1.4, 3.0], "tau": [0.35, 0.65]}
    lo, hi = result.design.data.bounds["l_2"].lower, result.design.data.bounds["l_2"].upper
    # l_2 = (1 - c1 tau)/Km with c1 = 5: negative on the box, so smallest at Km = 1.4, tau = 0.65, largest at
    # Km = 3.0, tau = 0.35
    assert lo == pytest.approx((1 - 5 * 0.65) / 1.4) and hi == pytest.approx((1 - 5 * 0.35) / 3.0)
    assert result.verified
