"""The sliding-mode servo's own checks on a linear plant (:mod:`~designkit.families.sliding_mode.linear`).

Run by the family's ``sliding_conditions`` rule (order 55) on a linear design, each re-deriving its proven range
from the plant's own linear model over the box (:func:`~designkit.families.sliding_mode.linear.proven_range`):

* ``sliding_linear_orientation``: ``c B > 0`` on the whole box;
* ``sliding_linear_switching``: ``k_i >= sup |g_i / cB|`` for every state (the state-proportional gains dominate
  the model error in ``s'``);
* ``sliding_linear_reaching``: ``k0 > xi_bar + sup |w X / cB|``, so ``s s' <= -eta |s|`` with
  ``eta = min cB (k0 - xi_bar - sup|w X/cB|) > 0``: the sliding mode exists on ``s = 0`` and every trajectory
  reaches it within ``|s(0)| / eta``.

Run by its ``sliding_run`` rule (order 127): ``sliding_linear_reaching_time`` (informational: the first time
``|s| <= h S(x~)``) and ``sliding_linear_band`` (required: after reaching, ``|s| <= h max S(x~)`` over the rest of
the run, the band a held step can leave; with a boundary layer ``|s| <= max(epsilon, h max S)``).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from designkit.families.sliding_mode.linear import LinearSlidingData, proven_range
from designkit.synthesis.state_space import linear_model
from designkit.verification.check import Check
from designkit.verification.suite import Context

__all__ = ["CERTIFICATE_GLOSSARY", "CERTIFICATE_LABELS", "RUN_GLOSSARY", "RUN_LABELS", "conditions", "run_checks"]

TOLERANCE = 1e-9
"""Relative slack the run's band is judged with (rounding of the recorded ``s``)."""


def conditions(design: Any, ctx: Context) -> tuple[Check, ...]:
    """The certificate on a linear plant (module docstring)."""
    info: LinearSlidingData = design.data
    model = linear_model(design.plant)
    box = {k: tuple(v) for k, v in info.box.items()}
    c = np.asarray(info.c, float)
    cv = ca.DM(c).T
    cA, cB = cv @ model.A, (cv @ model.B)[0, 0]
    cA0 = np.asarray(info.cA0, float)
    where = ", ".join(f"{k} in [{v[0]:.4g}, {v[1]:.4g}]" for k, v in box.items()) or "the nominal plant"
    lo, hi = proven_range(cB, model, box)
    out = [Check("sliding_linear_orientation", lo > 0, "c B > 0 on the whole box", lo, lo, "",
                 f"c B in [{lo:.6g}, {hi:.6g}] over {where} (proven range)", {"cB": [lo, hi], "box": box})]
    rows, ok = [], True
    sups = []
    for i, ki in enumerate(info.k):
        g = (cA[0, i] - cB * float(cA0[i])) / cB
        sup = max(abs(v) for v in proven_range(g, model, box))
        sups.append(sup)
        ok = ok and ki >= sup
        rows.append(f"k{i + 1} = {ki:.6g} {'>=' if ki >= sup else '<'} sup|g{i + 1}/cB| = {sup:.6g}")
    out.append(Check("sliding_linear_switching", ok, "k_i >= sup |g_i/cB| on the whole box", min(
        (ki - s for ki, s in zip(info.k, sups, strict=True)), default=None), None, "",
        "the state-proportional switching gains dominate the model error in s' (g = cA − (cB/cB0) cA0, proven): "
        + "; ".join(rows), {"k": list(info.k), "sup_g_over_cB": sups}))
    w = (cv @ (model.A @ ca.DM(np.asarray(info.x_rest)) + model.B * info.u_rest))[0, 0] * info.reference_max
    w_sup = max(abs(v) for v in proven_range(w / cB, model, box))
    need = info.xi_bar + w_sup
    eta = lo * (info.k0 - need)
    out.append(Check(
        "sliding_linear_reaching", info.k0 > need, "k0 > sup|ξ| + sup |w X/cB| on the whole box", info.k0,
        info.k0 - need, "",
        f"k0 = {info.k0:.6g} against sup|ξ| = {info.xi_bar:.6g} plus the rest mismatch sup|w X/cB| = {w_sup:.6g} "
        f"(X = {info.reference_max:g}): s s' <= −η |s| with η = {eta:.6g} > 0, so s = 0 is reached within |s(0)|/η "
        "and kept (the sliding mode exists)" if info.k0 > need else
        f"k0 = {info.k0:.6g} is not above sup|ξ| + sup|w X/cB| = {need:.6g}: raise controller.M above it",
        {"k0": info.k0, "xi_bar": info.xi_bar, "sup_w_over_cB": w_sup, "eta": eta,
         "corner_poles": [{"at": dict(at), "poles": [[z.real, z.imag] for z in poles]}
                          for at, poles in info.corner_poles]}))
    return tuple(out)


CERTIFICATE_LABELS = {"sliding_linear_orientation": "The input moves s the same way on the whole box (c B > 0)",
                      "sliding_linear_switching": "Switching gains dominate the model error (whole box)",
                      "sliding_linear_reaching": "Every trajectory reaches s = 0 and slides (whole box)"}
CERTIFICATE_GLOSSARY = (("linear plant's s", "c (x − x* xD), c from the sliding poles"),
                        ("linear plant's reaching", "s s' ≤ −η |s|: s = 0 is met in finite time and kept"))


def run_checks(design: Any, ctx: Context) -> tuple[Check, ...]:
    """What the run on a linear plant shows (module docstring)."""
    info: LinearSlidingData = design.data
    sim = ctx.simulation
    t = np.asarray(sim.time, float)
    x = np.asarray(sim.state, float)
    xd = np.asarray(sim.reference, float)[:, 0, 0]
    err = x - np.outer(xd, np.asarray(info.x_rest, float))
    s = err @ np.asarray(info.c, float)
    S = info.rate_bound(err)
    h = float(info.max_step)
    inside = np.abs(s) <= h * S * (1.0 + TOLERANCE)
    if info.boundary_layer is not None:
        inside |= np.abs(s) <= float(info.boundary_layer) * (1.0 + TOLERANCE)
    k = int(np.argmax(inside)) if inside.any() else None
    if k is None:
        reach = Check("sliding_linear_reaching_time", False, "reported: first |s| <= h S(x~)", None, None, "s",
                      f"|s| never came within the band h S(x~) (h = {h:.4g} s) in {t[-1]:g} s", {}, required=False)
        band = Check("sliding_linear_band", False, "|s| <= h max S(x~) after reaching", None, None, "",
                     "the run never reached the band", {})
        return reach, band
    later_S = np.maximum.accumulate(S[::-1])[::-1]  # max of S over [t_j, end]
    bound = h * later_S[k]
    if info.boundary_layer is not None:
        bound = max(bound, float(info.boundary_layer))
    worst = float(np.max(np.abs(s[k:])))
    reach = Check("sliding_linear_reaching_time", True, "reported: first |s| <= h S(x~)", float(t[k]), None, "s",
                  f"s reaches the band at {t[k]:.4g} s (|s(0)| = {abs(s[0]):.4g}) [informational]",
                  {"sliding_linear_reaching_time": float(t[k])}, required=False)
    ok = bool(worst <= bound * (1.0 + TOLERANCE))
    band = Check("sliding_linear_band", ok, "|s| <= h max S(x~) after reaching", worst / bound if bound > 0 else None,
                 1.0 - worst / bound if bound > 0 else None, "1",
                 f"after {t[k]:.4g} s the largest |s| is {worst:.4g} against {bound:.4g} "
                 f"({'the boundary layer or ' if info.boundary_layer is not None else ''}h = {h:.4g} s times the "
                 f"largest S(x~) = {later_S[k]:.4g} over the rest of the run)",
                 {"worst": worst, "bound": bound, "sliding_linear_reaching_time": float(t[k])})
    return reach, band


RUN_LABELS = {"sliding_linear_reaching_time": "Reaching time (measured)",
              "sliding_linear_band": "The run stays in the band h S(x̃)"}
RUN_GLOSSARY = (("h S(x̃)", "how far from s = 0 a command held over a step can leave s on a linear plant"),)
