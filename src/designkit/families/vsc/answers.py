"""What the ``vsc`` family says of one of its runs when a study asks (:attr:`designkit.synthesis.family.Family.answers`)
and what it predicts in closed form (:attr:`~designkit.synthesis.family.Family.predictions`).

* ``how``: why the loop's motion does not depend on the parameters where it matters (theorem 3 on the box, its
  certificate's status), how far the sliding motion's poles move at the box's corners, and how the run reached
  and held the surface (reaching time, the measured sliding poles, the equivalent control, the offset);
* ``strategy``: what the law measures and what its design needs, and, on the elastic joint, figure 5.3's printed
  ``c4`` against the surface designed (:func:`printed_c4`);
* ``load_offset``: the static offset ``|x - xD|`` (the controlled position's unit) a constant load of the spec's
  ``simulation.perturbation`` leaves at rest on ``sigma = 0`` at the nominal plant
  (:func:`~designkit.families.vsc.measure.static_offset`); on the elastic joint ``c1 w/(KR R2 (c1 + c3))``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from designkit.display.numbers import fmt_number, fmt_poles
from designkit.families.vsc.data import VscData
from designkit.families.vsc.spec import perturbation_level
from designkit.synthesis.knobs import Metric

__all__ = ["ANSWERS", "PREDICTIONS", "how", "load_offset", "printed_c4", "strategy", "surface_sentence"]


def _check(run: Any, name: str) -> Any:
    return next((c for c in run.checks if c.name == name), None)


def _poles(pairs: Any) -> str:
    return fmt_poles(complex(a, b) for a, b in pairs)


def how(result: Any) -> tuple[str, ...]:
    """Theorem 3 on the box, the sliding motion at the corners, and the run's reaching and sliding (module
    docstring)."""
    d = result.design
    info = d.data
    if not isinstance(info, VscData) or result.simulation is None:
        return ()
    unit = d.plant.states[int(info.position_index)].unit
    gains = _check(result, "vsc_gains")
    out = [f"Once the state is on the surface σ = c x̃ = 0 the motion has the poles chosen for it "
           f"({fmt_poles(d.poles)} 1/s) whatever the parameters that enter only the driven state's "
           f"equation, and the switching gains keep it there for every plant of the box (theorem 3, certified: "
           f"{gains.status if gains is not None else 'not run'})."]
    vertex = [min(-z.real for z in v.poles) for v in info.vertex_poles]
    if vertex and max(vertex) - min(vertex) > 1e-9 * max(vertex):
        requested = min(-z.real for z in d.poles)
        out.append(f"The sliding motion does depend on the other parameters (those of the reduced system): at the "
                   f"corners of the box its slowest decay rate is {fmt_number(min(vertex), 3)} 1/s to "
                   f"{fmt_number(max(vertex), 3)} 1/s, against {fmt_number(requested, 3)} 1/s requested at the nominal "
                   "plant; theorem 3 keeps the state on σ = 0 there, not the poles.")
    reach, poles, eq, off = (_check(result, n) for n in ("vsc_reaching_time", "vsc_sliding_poles",
                                                          "vsc_equivalent_control", "vsc_offset"))
    measured = (_poles(poles.certificate.get("poles") or []) if poles is not None and poles.certificate else "—")
    share = eq.achieved if eq is not None and eq.achieved is not None else None
    out.append(f"In the run it reached the surface in {fmt_number(reach.achieved if reach else None, 3)} s, then slid "
               f"with the measured poles {measured} 1/s; the equivalent control stayed between the two switched "
               f"controls on {fmt_number(None if share is None else 100 * share, 4)} % of the sliding samples "
               f"(theorem 1); the load left {fmt_number(off.achieved if off else None, 4)} {unit} against the "
               f"{fmt_number(off.certificate.get('predicted') if off else None, 4)} {unit} the sliding motion "
               "predicts.")
    return tuple(out)


def printed_c4(c: Any, tau2: float, k2: float) -> float:
    """Figure 5.3's ``c4`` as printed: its last term ``c1 J2/(c2 KR R2^2) = c1/(c2 k2)`` where the derivation gives
    ``c1/(tau2 k2)`` (docs/families/vsc.md); ``c`` the designed surface (``c2 = 1``), ``tau2`` (s), ``k2 = KR
    R2^2/J2`` (1/s^2)."""
    return float(c[3] + c[0] / (tau2 * k2) - c[0] / (c[1] * k2))


def surface_sentence(result: Any) -> str:
    """The designed surface against figure 5.3's closed form as printed (elastic joint; ``""`` otherwise)."""
    from designkit.families.vsc.surface import reduced_poles

    d = result.design
    info = d.data
    if not isinstance(info, VscData) or info.plant_kind != "elastic_joint":
        return ""
    c = np.asarray(info.c, float)
    A, B, _ = (np.asarray(m, float) for m in info.nominal_model)
    p = d.plant.params
    wrong = c.copy()
    wrong[3] = printed_c4(c, p.tau2, p.KR * p.R2**2 / p.J2)
    moved = fmt_poles(reduced_poles(A, B, wrong), 4)
    return ("The surface c = (" + ", ".join(fmt_number(v, 5) for v in c) + ") is computed from the sliding poles by "
            f"Ackermann's formula for surfaces, which equals figure 5.3's closed form once its c4 is read with τ2 "
            f"where c2 is printed; the printed c4 = {fmt_number(wrong[3], 5)} would put the sliding motion at {moved} "
            "1/s instead.")


def strategy(result: Any) -> tuple[str, ...]:
    """What its design needs, and the surface against figure 5.3 as printed."""
    d = result.design
    info = d.data
    if not isinstance(info, VscData):
        return ()
    out = [f"σ = c x̃ with c from the sliding poles {fmt_poles(d.poles)} 1/s (Ackermann's formula for "
           "surfaces); u = Σ ψᵢ x̃ᵢ − δ sign(σ) with ψᵢ switching between αᵢ and βᵢ on the sign of x̃ᵢ σ. Its design "
           "needs c, the ranges of the equivalent-control gains lᵢ over the parameter box and the certificate that "
           f"αᵢ < lᵢ < βᵢ there (relay δ = {fmt_number(info.delta, 4)} {d.plant.inputs[0].unit})."]
    words = surface_sentence(result)
    return (*out, words) if words else tuple(out)


def load_offset(result: Any) -> float | None:
    """``|x - xD|`` at rest under the spec's constant load (module docstring); None without a perturbation."""
    from designkit.families.vsc.measure import static_offset

    info = result.design.data
    w = perturbation_level(result.loaded.spec.simulation)
    if not isinstance(info, VscData) or w is None:
        return None
    A, B, D = (np.asarray(m, float) for m in info.nominal_model)
    if not D.size:
        return None
    value = static_offset(A, B, D, np.asarray(info.c, float), w)[int(info.position_index)]
    return abs(float(value)) if math.isfinite(value) else None


ANSWERS = (("how", how), ("strategy", strategy))
"""The topics the family answers (:data:`designkit.synthesis.family.ANSWER_TOPICS`)."""

PREDICTIONS = (Metric("load_offset", "static offset a constant load leaves (closed form)", "rad", load_offset,
                      "|x − xD| at rest on σ = 0 at the nominal plant under the spec's constant perturbation"),)
"""What the family predicts in closed form for a run."""
