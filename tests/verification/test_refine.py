"""The lattice refined between neighbours: planted margins, and a robot's parameter box judged by ``robust_grid``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from designkit.verification.refine import MIN_WIDTH_FRACTION, RESOLVED_FRACTION, lattice_pairs, refine, resolved

ROOT = Path(__file__).resolve().parents[2]


def _run(f, lo, hi, grid, cap=2000):
    """Refine a 1-D lattice of ``grid`` points of the planted margin ``f``; every point evaluated, in order."""
    x = np.linspace(lo, hi, grid)[:, None]
    seen = []

    def evaluate(points):
        seen.append(points.copy())
        return f(points[:, 0])

    r = refine(x, f(x[:, 0]), (grid,), np.array([hi - lo]), evaluate, cap=cap)
    return x, r, seen


def test_resolved_needs_a_small_change_of_one_sign():
    m_a = np.array([2.0, 2.0, 0.1, -3.0, 1.0, 0.0])
    m_b = np.array([2.9, 3.1, -0.1, -2.0, np.nan, 0.0])
    # |2 - 2.9| = 0.9 <= 0.5 * 2; |2 - 3.1| = 1.1 > 1; a sign change; |-3 + 2| = 1 <= 1; undecided; zero
    assert resolved(m_a, m_b).tolist() == [True, False, False, True, False, False]


def test_lattice_pairs_are_the_neighbours_along_each_axis():
    shape = (3, 2, 2)
    pts = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), axis=-1).reshape(-1, 3)
    pairs = lattice_pairs(shape)
    assert [j for j, _, _ in pairs] == [0, 1, 2]
    # own count: along axis j, (n_j - 1) * prod(other n) pairs, each differing by 1 along j only
    for j, a, b in pairs:
        assert a.size == (shape[j] - 1) * int(np.prod(shape)) // shape[j]
        diff = pts[b] - pts[a]
        assert np.all(diff[:, j] == 1) and np.all(np.delete(diff, j, axis=1) == 0)


def test_a_dip_between_two_equal_corners_is_found():
    """Corners alike, an unstable band in the middle third: a two-point lattice misses it, the refinement finds it."""
    def f(x):
        return np.where(np.abs(x - 0.5) < 1 / 6, -1.0, 1.0)

    x, r, seen = _run(f, 0.0, 1.0, 2)
    assert np.all(f(x[:, 0]) > 0)  # the lattice alone says stable
    assert np.any(f(r.theta[:, 0]) < 0)  # the refinement does not
    assert r.plants == sum(len(s) for s in seen) and r.unresolved == 0
    # every added point is a dyadic midpoint of the box, and no point is evaluated twice
    k = r.theta[:, 0] * 2**12
    assert np.allclose(k, np.round(k)) and len(np.unique(r.theta[:, 0])) == r.plants
    # the boundaries x = 1/3 and x = 2/3 are bracketed to the finest width
    pts = np.sort(np.concatenate([x[:, 0], r.theta[:, 0]]))
    for edge in (1 / 3, 2 / 3):
        right = pts[pts > edge].min()
        left = pts[pts < edge].max()
        assert right - left <= 2 * MIN_WIDTH_FRACTION


def test_refinement_stops_where_the_margin_is_resolved():
    """A smooth margin far from zero: one bisection of each pair, then every neighbour pair resolved."""
    def f(x):
        return 10.0 + x

    x, r, _ = _run(f, 0.0, 1.0, 5)
    assert r.plants == 4 and r.rounds == 1  # one midpoint per pair of the 5-point lattice
    pts = np.sort(np.concatenate([x[:, 0], r.theta[:, 0]]))
    m = f(pts)
    assert np.all(np.abs(np.diff(m)) <= RESOLVED_FRACTION * np.minimum(m[:-1], m[1:]))


def test_a_margin_approaching_zero_is_refined_more_densely_near_zero():
    def f(x):
        return x  # stable margin shrinking to 1e-3 at the low end of [1e-3, 1]

    _, r, _ = _run(f, 1e-3, 1.0, 2)
    added = r.theta[:, 0]
    assert np.count_nonzero(added < 0.1) > np.count_nonzero(added > 0.5)


def test_the_cap_is_kept_and_what_is_left_is_counted():
    def f(x):
        return np.sin(200 * x)  # changes sign everywhere: never resolved

    _, r, _ = _run(f, 0.0, 1.0, 2, cap=5)
    assert r.plants == 5 and r.unresolved > 0


# ------------------------------------------------------------------------------------------ a robot's box

def _ilc_spec(tmp_path: Path, interval: str, grid: int = 2) -> Path:
    text = (ROOT / "specs" / "ilc-simnog.yaml").read_text()
    plant = "plant: {kind: robot, robot: planar2r}"
    assert plant in text
    path = tmp_path / "ilc-box.yaml"
    path.write_text(text.replace(plant, f"plant: {{kind: robot, robot: planar2r, uncertainty: {{m2: {interval}, "
                                        f"grid: {grid}}}}}"))
    return path


def _grid(tmp_path, interval):
    from designkit import pipeline
    from designkit.schema.loader import load_spec
    from designkit.verification.robustness import Sweeper, box_from_uncertainty, grid_check

    loaded = load_spec(_ilc_spec(tmp_path, interval))
    plant = pipeline.plant(loaded)
    design = pipeline.design(loaded, plant)
    box = box_from_uncertainty(plant, loaded.spec.plant.uncertainty)
    sweeper = Sweeper(design, box.names, plant)
    return design, plant, grid_check(design, box, sweeper), sweeper


def _independent_jacobian(design, plant, m2, z):
    """The closed loop's right-hand side at ``z`` on the arm with link mass ``m2``, evaluated point by point from
    the plant's ODE and the law's command (no batched Newton, no CasADi Jacobian), and its Jacobian by central
    differences."""
    import casadi as ca

    true = plant.with_params(m2=m2)
    ode, law, r0 = true.ode(), design.linear_law, ca.DM(design.operating_point["r"])
    p, d = true.parameter_vector, np.zeros(len(true.disturbances))

    def f(x):
        u = law.command(ca.DM(x), ca.DM.zeros(0, 1), ca.DM.zeros(0, 1), r0)
        return np.asarray(ode(ca.DM(x), u, d, p), dtype=float).ravel()

    h = 1e-6 * max(1.0, float(np.max(np.abs(z))))
    J = np.column_stack([(f(z + h * e) - f(z - h * e)) / (2 * h) for e in np.eye(z.size)])
    return f(z), J


def test_a_two_point_lattice_of_a_wide_mass_box_finds_the_unstable_region(tmp_path):
    from designkit.synthesis.closed_loop import equilibria

    design, plant, check, sweeper = _grid(tmp_path, "[1.0e-3, 1.0e4]")
    cert = check.certificate
    assert check.passed is False
    assert cert["lattice_plants"] == 2 and cert["refined_plants"] > 0 and cert["unstable"] > 0
    assert cert["plants"] == 2 + cert["refined_plants"] and f"of {cert['plants']} sampled plants" in check.detail
    bad = [p for p in cert["failing_points"] if p["status"] == "unstable"]
    m2 = bad[0]["m2"]
    assert 1e-3 < m2 < 1e4  # inside the box, not a corner
    # the equilibrium the check linearized at, re-checked independently: it is one, and it is unstable
    eq = equilibria(sweeper._functions, sweeper._z0, sweeper._r0, sweeper.parameters(np.array([[m2]])))
    z = eq.z[0]
    f, J = _independent_jacobian(design, plant, m2, z)
    assert np.max(np.abs(f)) < 1e-6 * (1 + np.max(np.abs(z)))
    assert np.max(np.linalg.eigvals(J).real) > 1.0  # 1/s: clearly in the right half plane


def test_a_benign_mass_box_passes_with_its_count(tmp_path):
    _, _, check, _ = _grid(tmp_path, "[2.5, 3.5]")
    cert = check.certificate
    assert check.passed is True
    assert cert["lattice_plants"] == 2 and cert["refined_plants"] >= 1 and cert["unresolved_pairs"] == 0
    assert f"{cert['plants']} sampled plants stable" in check.detail
    assert "not proven for the continuum" in check.detail and "sampled" in check.target


def test_the_cli_fails_the_wide_box(tmp_path, capsys):
    from designkit.cli import main

    code = main(["verify", str(_ilc_spec(tmp_path, "[1.0e-3, 1.0e4]")), "--jobs", "1"])
    out = capsys.readouterr().out
    assert code == 1 and "NOT VERIFIED" in out and "robust_grid" in out.split("NOT VERIFIED")[-1]


@pytest.mark.parametrize("grid", [2, 3])
def test_the_verdict_does_not_hang_on_the_lattice_size(tmp_path, grid):
    from designkit import pipeline
    from designkit.schema.loader import load_spec
    from designkit.verification.robustness import Sweeper, box_from_uncertainty, grid_check

    loaded = load_spec(_ilc_spec(tmp_path, "[1.0e-3, 1.0e4]", grid))
    plant = pipeline.plant(loaded)
    design = pipeline.design(loaded, plant)
    box = box_from_uncertainty(plant, loaded.spec.plant.uncertainty)
    assert grid_check(design, box, Sweeper(design, box.names, plant)).passed is False
