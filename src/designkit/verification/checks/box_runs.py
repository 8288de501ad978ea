"""Check ``box_runs``: the family's own run (its simulation or trials and every check it offers) repeated on the
true plant at the corners of ``plant.uncertainty`` and at seeded samples of the box.

A family whose law copes with unknown parameters by itself -- an adaptive, identifying or self-tuning law, whose
design has no fixed linear loop to sweep over a lattice -- offers it: its verdict over the box is what its own
run says at each plant.  At most :data:`MAX_CORNERS` corners are run (beyond, a seeded choice of that many,
said in the detail) and at most :data:`MAX_SAMPLES` of the ``samples`` interior points (the first ones drawn,
said in the detail).  A plant where a required check fails makes the check fail, naming the plant and the checks;
an undecided one makes it undecided; a run that cannot complete at a plant (an exception other than bad input)
fails that plant with the error.  Sampling, not proof: the detail counts the runs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from designkit.verification.suite import CheckRule, Context

MAX_CORNERS = 16
"""Most corners of the box run (2^k for k uncertain parameters; beyond, a seeded choice of this many)."""
MAX_SAMPLES = 16
"""Most interior samples of the box run (the first ones of ``plant.uncertainty.samples``)."""


def box_points(box: Any) -> tuple[np.ndarray, int, int, int]:
    """``(points, corners run, corners of the box, samples run)``: the corners (all, or a seeded choice of
    :data:`MAX_CORNERS`) then the first :data:`MAX_SAMPLES` seeded samples."""
    corners = box.vertices
    total = len(corners)
    if total > MAX_CORNERS:
        pick = np.sort(np.random.default_rng(box.seed).choice(total, MAX_CORNERS, replace=False))
        corners = corners[pick]
    samples = box.random[:MAX_SAMPLES] if box.samples else np.zeros((0, len(box.names)))
    return np.vstack([corners, samples]), len(corners), total, len(samples)


def _run(design: Any, ctx: Context) -> tuple:
    from designkit.errors import DesignkitError
    from designkit.verification.check import Check
    from designkit.verification.robustness import box_from_uncertainty

    box = box_from_uncertainty(ctx.true_plant(design), ctx.uncertainty())
    points, n_corners, total, n_samples = box_points(box)
    rows, failing, undecided = [], [], []
    for theta in points:
        values = dict(zip(box.names, map(float, theta), strict=True))
        try:
            checks = ctx.rerun(values)
        except DesignkitError:
            raise
        except Exception as exc:  # noqa: BLE001 -- a run that cannot complete is that plant's failure, with its reason
            checks = (Check(name=f"run raised {type(exc).__name__}: {exc}", passed=False, target="a completed run",
                            achieved=None, margin=None, unit="", detail=str(exc)),)
        failed = [c.name for c in checks if c.required and c.passed is False]
        open_ = [c.name for c in checks if c.required and c.passed is None]
        rows.append({**values, "verified": not failed and not open_, "failed": failed, "undecided": open_})
        where = ", ".join(f"{n}={v:.4g}" for n, v in values.items())
        if failed:
            failing.append(f"({where}) {', '.join(failed)}")
        elif open_:
            undecided.append(f"({where}) undecided: {', '.join(open_)}")
    runs = len(points)
    which = (f"{n_corners} corners" if n_corners == total else f"{n_corners} of the {total} corners (seeded choice, "
             f"seed {box.seed}; at most {MAX_CORNERS} are run)")
    if n_samples:
        which += f" and {n_samples} seeded samples (seed {box.seed}" + (
            f"; the first {MAX_SAMPLES} of {box.samples})" if box.samples > MAX_SAMPLES else ")")
    passed = False if failing else (None if undecided else True)
    if passed:
        detail = f"the family's own run verified at all {runs} plants of the box ({which}); sampled, not a proof"
    else:
        bad = failing or undecided
        detail = (f"{len(failing)} of {runs} plants of the box fail and {len(undecided)} are undecided ({which}): "
                  + "; ".join(bad[:4]) + ("; ..." if len(bad) > 4 else ""))
    cert = {"box": box.describe(), "runs": runs, "corners_run": n_corners, "corners": total,
            "samples_run": n_samples, "seed": box.seed, "plants": rows}
    return (Check(name="box_runs", passed=passed, target=f"every required check passes at each of {runs} plants "
                  "of the box (corners and samples; sampled, not a proof)",
                  achieved=float(runs - len(failing) - len(undecided)), margin=None, unit="plants verified",
                  detail=detail, certificate=cert),)


RULE = CheckRule(name="box_runs", order=150,
                 applies=lambda d, c: c.uncertainty() is not None and c.rerun is not None and c.simulation is not None,
                 run=_run, label="The family's own run over the parameter box")
