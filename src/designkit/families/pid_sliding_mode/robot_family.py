"""The PID/sliding-mode family extended to robots: dispatch on the plant kind, the JSON object, the report section.

``--json`` (``pid_sliding_mode``): per joint the PID gains, ``M`` and the proven ``bound`` it covers, with the
sampled lower bound and the configuration attaining it.  The report section "Hierarchy of control" has one row
per joint: the acceleration box it was bounded over, the bound and its parts, the attained value and where.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from designkit.display.numbers import fmt_percent
from designkit.display.section import Question, ReportSection, Table
from designkit.families.pid_sliding_mode.data import RobotSlidingData
from designkit.families.pid_sliding_mode.robot import law, synthesize
from designkit.families.pid_sliding_mode.robot_checks import (
    CERTIFICATE_RULE,
    RUN_RULE,
    box_words,
    parameter_values,
    run_perturbation,
)
from designkit.families.pid_sliding_mode.robot_figures import ROBOT_FIGURES
from designkit.families.pid_sliding_mode.spec import KIND
from designkit.synthesis.family import PlantField

__all__ = ["extend", "json_summary", "section"]


def _link_json(link: Any) -> dict[str, float]:
    """A joint's simplified link: ``Km`` ((rad/s)/(N*m)), ``tau`` (s), ``inertia`` (kg*m^2), ``damping``
    (N*m*s/rad)."""
    return {"Km": link.Km, "tau": link.tau, "inertia": link.inertia, "damping": link.damping}


def json_summary(result: Any) -> dict[str, Any]:
    """The family's ``--json`` object for a robot design (module docstring)."""
    info: RobotSlidingData = result.design.data
    joints = []
    for i, M in enumerate(info.M):
        at = {k: v for k, v in info.enclosure.argmax[i].items() if k != "p"}
        if "p" in info.enclosure.argmax[i]:
            at["parameters"] = parameter_values(info, info.enclosure.argmax[i]["p"])
        joints.append({
            "joint": i + 1, "gains": info.gains[i], "M": M, "bound": info.bound[i],
            "sampled_lower_bound": info.sampled[i], "attained_at": at, "terms": info.enclosure.terms[i],
            "converged": info.enclosure.converged[i], "acceleration_box": info.acceleration_rows[i],
            "sliding_acceleration": info.sliding_acceleration[i], "link": _link_json(info.links[i]),
            "inertia_range": info.inertia_range[i]})
    enc = info.enclosure
    out = {"form": info.form, "a1": info.a1, "a2": info.a2, "p3": info.p3, "zero": info.p3,
           "M": list(info.M), "M_given": info.M_given, "margin": info.margin,
           "bound": {"per_joint": list(info.bound), "sampled": list(info.sampled), "boxes": enc.boxes,
                     "seconds": enc.seconds, "tolerance": enc.rel_tol, "work_limit": enc.max_boxes,
                     "workspace": info.workspace, "gravity_feedforward": info.gravity_feedforward,
                     "parameter_box": {r["name"]: {"low": r["low"], "high": r["high"], "nominal": r["nominal"],
                                                   "unit": r["unit"]} for r in info.parameter_box}},
           "joints": joints, "epsilon": info.epsilon, "layer": info.layer if info.epsilon is not None
           else None, "max_step": info.max_step}
    sim = result.simulation
    if sim is not None and "slm1" in sim.signals:
        xi, inside, _ = run_perturbation(result.design, sim, getattr(result, "plant", None))
        out["run"] = {"peak_xi": [float(v) for v in abs(xi).max(axis=0)],
                      "inside_fraction": [float(v) for v in inside.mean(axis=0)]}
    return {KIND: out}


def _fmt(values: Any) -> str:
    return "(" + ", ".join(f"{float(v):.3g}" for v in values) + ")"


def section(result: Any) -> ReportSection | None:
    """"Hierarchy of control": per joint the box, the proven bound and its parts, the attained value and where."""
    info = result.design.data
    if not isinstance(info, RobotSlidingData):
        return None
    n = len(info.M)
    rows = []
    units = {r["name"]: r["unit"] for r in info.parameter_box}
    for i in range(n):
        t, at = info.enclosure.terms[i], info.enclosure.argmax[i]
        named = parameter_values(info, at["p"]) if "p" in at else {}
        rows.append((f"joint {i + 1}", _fmt(info.acceleration_rows[i]) + " rad/s²",
                     f"{info.bound[i]:.4g} N·m", f"{info.sampled[i]:.4g} N·m",
                     f"q = {_fmt(at['q'])} rad, q̇ = {_fmt(at['qd'])} rad/s, q̈ = {_fmt(at['qdd'])} rad/s²"
                     + "".join(f", {k} = {v:.4g} {units[k]}" for k, v in named.items()),
                     f"{t['own_inertia']:.3g} / {t['coupling']:.3g} / {t['coriolis']:.3g} / {t['gravity']:.3g} / "
                     f"{t['friction']:.3g} N·m", f"{info.M[i]:.4g} N·m"))
    parts = ("Coriolis and centrifugal / gravity, with the feed-forward its residual / friction: Coulomb and the "
             "viscous change over the parameter box" if units else "Coriolis and centrifugal / gravity / Coulomb "
             "friction")
    table = Table("Per joint, from the last to the first: the acceleration box the bound covers (the later joints at "
                  "their sliding motion's largest acceleration), the proven sup|ξ_i|, the largest |ξ_i| attained and "
                  "where, the proven parts on the box that sets the bound (own inertia variation / coupling / "
                  f"{parts}) and the relay amplitude.",
                  ("joint", "|q̈_j| ≤", "proven sup|ξ_i|", "attained", "attained at", "parts", "M_i"),
                  tuple(reversed(rows)))
    ws = info.workspace
    over = box_words(info)
    sentences = [
        f"The box: q from {_fmt(ws['low'])} to {_fmt(ws['high'])} rad, |q̇| ≤ {_fmt(ws['velocity'])} rad/s, "
        f"|q̈| ≤ {_fmt(ws['acceleration'])} rad/s² (the plant's limits)" + (f"; {over}" if over else "")
        + f"; the sliding motions' largest accelerations are {_fmt(info.sliding_acceleration)} rad/s².",
        "The bound is proven by ball arithmetic on the inertia matrix, the Christoffel symbols and the gravity "
        + ("torque (with the feed-forward, its residual: the true arm's gravity minus the nominal model's), "
           "the parameters bounded inputs of the enclosure like the joints, "
           f"over {info.enclosure.boxes} boxes of configurations and parameters " if over else
           f"torque over {info.enclosure.boxes} configuration boxes ")
        + f"({info.enclosure.seconds:.3g} s), combined with the velocity and "
        "acceleration boxes by interval arithmetic; the attained value is the model's inverse dynamics at a point "
        "of the box, so sup|ξ_i| lies between the two.",
    ]
    if over:
        sentences.append("Each joint's simplified link (its D̂_i, f_i and the gravity feed-forward) is the nominal "
                         "model's: the parameter change is part of ξ_i, in every part of the table.")
    sim = result.simulation
    if sim is not None and "slm1" in sim.signals:
        xi, inside, _ = run_perturbation(result.design, sim, getattr(result, "plant", None))
        sentences.append("Along the run the largest |ξ_i| were " + _fmt(abs(xi).max(axis=0)) + " N·m, the run "
                         "inside each joint's box for " + ", ".join(fmt_percent(v) for v in inside.mean(axis=0))
                         + " of its samples.")
    q = Question("How large must each joint's relay be (the hierarchy of control, notes section 5.4)?",
                 tuple(sentences), (table,))
    intro = ("Each joint's relay M_i must exceed sup|ξ_i|, the torque its simplified link leaves out. Designing "
             "from the last link to the first, the later links are assumed in sliding mode, so their accelerations "
             "are those of their sliding motion.")
    return ReportSection("pid-sm-hierarchy", "Hierarchy of control: the relay amplitudes per joint", intro, (q,))


ROBOT_FIELDS = (
    PlantField("workspace", ("robot",), "the box of configurations the hierarchy of control bounds xi over"),
    PlantField("gravity_feedforward", ("robot",), "the arm's gravity torque fed forward"),
    PlantField("work_limit", ("robot",), "the configuration boxes the proven bound of sup|xi_i| may bisect"),
)
"""The controller fields only the robot's hierarchy of control reads; given on a link or an elastic joint, they
are refused when the spec is read."""


def extend(family: Any) -> Any:
    """``family`` also designing for robots (dispatched on the plant kind; a robot design's data is a
    :class:`~designkit.families.pid_sliding_mode.data.RobotSlidingData`)."""
    base_synth, base_law, base_json = family.synthesize, family.law, family.json

    def synth(spec: Any, plant: Any) -> Any:
        if plant.kind == "robot":
            from designkit.families.pid_sliding_mode.spec import refuse_chatter_limit

            refuse_chatter_limit(spec, plant.kind)
            return synthesize(spec, plant)
        return base_synth(spec, plant)

    def law_of(design: Any, anti_windup: Any = None) -> Any:
        return law(design, anti_windup) if isinstance(design.data, RobotSlidingData) else base_law(design, anti_windup)

    def json_of(result: Any) -> Any:
        if isinstance(result.design.data, RobotSlidingData):
            return json_summary(result)
        return base_json(result) if base_json is not None else {}

    return dataclasses.replace(family, plants=(*family.plants, "robot"), synthesize=synth, law=law_of,
                               checks=(*family.checks, CERTIFICATE_RULE, RUN_RULE), json=json_of,
                               sections=(*family.sections, section), figures=(*family.figures, *ROBOT_FIGURES),
                               plant_fields=ROBOT_FIELDS)
