"""What the ``vsc`` family adds to ``--json`` and its report section (theorems 1, 3 and 4 on this run)."""

from __future__ import annotations

from typing import Any

from designkit.display.numbers import fmt_number
from designkit.display.section import Question, ReportSection, Table
from designkit.families.vsc.data import VscData
from designkit.families.vsc.measure import measure
from designkit.families.vsc.spec import KIND

__all__ = ["json_summary", "section"]


def json_summary(result: Any) -> dict[str, Any]:
    """Top-level ``alpha``, ``beta``, ``delta``, ``c`` (and ``c1`` ... ``c4`` on the elastic joint: ``sigma = c1 x1
    + c2 x2 + c3 x3 + c4 x4``, ``c2 = 1``), and a ``vsc`` object with the box's ``l_i`` ranges and the run's
    measurements."""
    info: VscData = result.design.data
    out: dict[str, Any] = {"alpha": list(info.alpha), "beta": list(info.beta), "delta": info.delta,
                           "c": list(info.c)}
    if info.plant_kind == "elastic_joint":
        out.update({f"c{i + 1}": v for i, v in enumerate(info.c)})
    vsc: dict[str, Any] = {
        "sigma": " + ".join(f"c{i + 1} x{i + 1}" for i in range(len(info.c))),
        "sign_convention": "psi_i = alpha_i where x_i sigma > 0, beta_i where x_i sigma < 0; alpha_i < l_i < beta_i",
        "sliding_poles": [[p.real, p.imag] for p in result.design.poles], "margin": info.margin,
        "box": {k: list(v) for k, v in info.box.items()},
        "l_ranges": {k: [v.lower, v.upper] for k, v in info.bounds.items() if k.startswith("l_")},
        "l_methods": {k: v.method for k, v in info.bounds.items() if k.startswith("l_")},
        "cD_over_cB": [info.bounds["cD/cB"].lower, info.bounds["cD/cB"].upper],
        "perturbation_bound": info.d_bar, "band": info.band, "max_step": info.max_step,
        "boundary_layer": info.boundary_layer,
        "sliding_poles_at_box_vertices": [v.to_json() for v in info.vertex_poles],
    }
    sim = result.simulation
    if sim is not None:
        run = measure(result.design, sim)
        vsc.update({
            "dt": float(sim.settings["dt"]), "reaching_time": run.reaching_time,
            "max_sigma_over_band_after_reaching": run.worst_ratio,
            "measured_sliding_poles": None if run.poles is None else [[z.real, z.imag] for z in run.poles],
            "switching_frequency": run.switching_frequency, "total_variation_u": run.total_variation,
            "u_eq_inside_fraction": run.ueq_fraction, "matched": run.matched,
            "predicted_offset": run.predicted_offset, "final_offset": run.final_offset,
            "sigma_to_position_gain": run.sigma_gain,
            "boundary_layer_precision": (None if info.boundary_layer is None else
                                         abs(run.sigma_gain) * info.boundary_layer),
        })
    out[KIND] = vsc
    return out


def _num(v: float) -> str:
    return fmt_number(v, 4)


def section(result: Any) -> ReportSection | None:
    """Theorems 1, 3 and 4 on this design and run, in words and numbers."""
    info = result.design.data
    if not isinstance(info, VscData):
        return None
    n = len(info.c)
    rows = tuple((f"x{i + 1}", _num(info.c[i]), _num(info.bounds[f"l_{i + 1}"].lower),
                  _num(info.bounds[f"l_{i + 1}"].upper), _num(info.alpha[i]), _num(info.beta[i]),
                  "exact at the box's corners" if info.bounds[f"l_{i + 1}"].method == "vertices"
                  else "proven enclosure") for i in range(n))
    table = Table("The switching surface and theorem 3's gains, per state", ("state", "c_i", "min l_i", "max l_i",
                                                                             "α_i", "β_i", "range"), rows)
    q3 = Question("Theorem 3: do the switching gains bracket the equivalent-control gains on the whole box?", (
        f"The equivalent-control gains l_i = −(cA)_i/(cB) were computed over the box of {len(info.box)} "
        f"uncertain parameters; the gains clear them by {fmt_number(100 * info.margin, 3)} % of each gain's "
        f"size, and the relay amplitude is δ = {_num(info.delta)}.",), (table,))
    re_ = [p.real for v in info.vertex_poles for p in v.poles]
    im_ = [abs(p.imag) for v in info.vertex_poles for p in v.poles]
    moved = max(abs(a - b) for v in info.vertex_poles for a, b in zip(
        sorted(p.real for p in v.poles), sorted(p.real for p in result.design.poles), strict=True))
    q3 = Question(q3.question, (*q3.sentences, (
        "c is placed at the nominal plant. The motion on σ = 0 does not depend on the parameters that enter only "
        "the driven state's equation, but it does on the others: at the box's corners its poles have real parts from "
        f"{_num(min(re_))} to {_num(max(re_))} 1/s" + (f" and imaginary parts up to {_num(max(im_))} 1/s" if
                                                       max(im_) > 0 else "") +
        (", the requested ones at every corner." if moved <= 1e-9 * max(1.0, max(abs(x) for x in re_)) else
         ", not only the requested ones: the sliding motion is invariant to matched uncertainty only.")),),
        q3.tables)
    questions = [q3]
    sim = result.simulation
    if sim is not None:
        run = measure(result.design, sim)
        s1 = ("No sliding phase was reached." if run.ueq_fraction is None else
              f"While sliding the equivalent control of the run's plant lies between the two switched controls on "
              f"{fmt_number(100 * run.ueq_fraction, 4)} % of the samples, as theorem 1 requires.")
        questions.append(Question("Theorem 1: does the equivalent control lie between the two switched controls?",
                                  (s1,)))
        s4 = (("The disturbance enters with the input (matched): the sliding motion is invariant to it" if run.matched
               else "The disturbance does not enter where the input does (unmatched): the relay keeps σ at 0, but "
                    "the motion on σ = 0 is driven by it and is not invariant") +
              f"; the sliding motion predicts a final error of {_num(run.predicted_offset)} rad of the controlled "
              f"position under the final disturbance, and the run ends at {_num(run.final_offset)} rad.")
        questions.append(Question("Theorem 4: is the sliding motion invariant to the disturbance?", (s4,)))
    return ReportSection("vsc-theorems", "Variable structure control: theorems 1, 3 and 4 on this design",
                         "Computed from the design's parameter box and the simulated run.", tuple(questions))
