"""The self-tuning regulator's report section (lab experiment 2's questions, answered from re-simulations) and its
top-level JSON fields ``theta_hat``, ``theta_true`` and ``self_tuning``."""

from __future__ import annotations

import math
from typing import Any

from designkit.families.self_tuning.laws import KIND
from designkit.families.self_tuning.runs import excitation, samples, sylvester_condition, true_theta

__all__ = ["json", "section"]


def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def json(result: Any) -> dict[str, Any]:
    """``theta_hat`` (final estimates), ``theta_true`` (the exactly discretized true link at the end of the run,
    same order) and the family's own object under its kind (form, parameter names and units, initial estimates,
    sampling period, design; the ARX form's orders, ``Am``, ``Ao``, zeros and, after a run, the final controller
    polynomials ``R``, ``S``, ``T``; after a run the samples taken, the samples where the controller was held and where
    the covariance bound fired, the final excitation indicator and the final Sylvester condition number)."""
    d, sim = result.design, result.simulation
    x = d.data
    st = x.settings
    info = {"form": st.form, "parameters": list(x.parameters), "units": list(x.units),
            "initial": list(st.theta0), "sampling_period": st.Ts, "design": st.design}
    if st.form == "arx":
        info.update({"orders": dict(zip(("na", "nb", "d"), st.orders, strict=True)), "Am": list(st.am),
                     "Ao": list(st.ao), "zeros": "cancel" if st.cancel else "keep"})
    if sim is None:
        return {"theta_hat": list(st.theta0), KIND: info}
    s = samples(sim, d)
    if st.form == "arx":
        from designkit.families.self_tuning.arx_runs import controller_polynomials

        info["controller"] = controller_polynomials(s.coefs[-1], d)
    plant = result.plant if result.plant is not None else d.plant
    true = true_theta(result.loaded.spec, plant, d, s.t[-1:])[0]
    window = max(1, int(round(x.excitation_window / x.settings.Ts)))
    norm = excitation(s, window)[1]
    cond = sylvester_condition(s, d)
    return {"theta_hat": [_num(v) for v in s.theta[-1]], "theta_true": [float(v) for v in true],
            KIND: {**info, "samples": len(s.t), "held": int(s.held.sum()), "bounded": int(s.bounded.sum()),
                   "excitation": _num(norm[-1]) if norm.size else None,
                   "sylvester_condition": _num(cond[-1]) if cond.size else None}}


def section(result: Any) -> Any:
    """The lab section (see :mod:`designkit.families.self_tuning.study`)."""
    from designkit.families.self_tuning.study import section as build

    return build(result)

