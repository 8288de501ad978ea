"""The learning family's figures, drawn from a run: the error norm per trial against the certificate, the first
and last trials' tracking errors, and the learned acceleration of the last trial.

Each function takes the pipeline's result and returns a standalone :class:`~designkit.display.figure.Figure`
(None without trials); the captions are written from the tagged artists actually drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from designkit.display.figure import JOINT_COLORS, LIMIT_STYLE, REFERENCE_STYLE, Figure, plain_ticks
from designkit.display.numbers import sci
from designkit.display.svg import GREY, RED, new_figure, plot_decimated, render_tagged, tag
from designkit.families.ilc.checks import near_one, trial_analysis

__all__ = ["error_norm_figure", "learned_figure", "tracking_error_figure"]


def _sentence(parts: Sequence[str]) -> str:
    parts = list(parts)
    return parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + " and " + parts[-1]


def _evidence(result: Any, names: Sequence[str]) -> tuple[str, ...]:
    have = {c.name for c in result.checks}
    return tuple(n for n in names if n in have)


# ----------------------------------------------------------------------------- error norm per trial


def _unit(result: Any, which: int) -> str:
    """The learned signal's (0) or the error's (1) unit (empty when dimensionless)."""
    unit = str(result.design.data.units[which])
    return "" if unit == "1" else unit


def _label(text: str, unit: str) -> str:
    return f"{text} ({unit})" if unit else text


def _draw_norms(result: Any, a: Any) -> tuple[Any, dict[str, Any]]:
    fig, (ax,) = new_figure(6.8, 3.6)
    k = np.arange(a.norms.size)
    c = a.contraction
    positive = a.norms[np.isfinite(a.norms) & (a.norms > 0)]
    floor = float(np.min(positive)) * 1e-3 if positive.size else 1e-300
    tag(fig, "measured", *ax.plot(k, np.where(a.norms > 0, a.norms, np.nan), "o-", color=JOINT_COLORS[0], ms=3.5,
                                  label="measured ‖e_k‖"))
    info: dict[str, Any] = {"rho": near_one(c.rho, c.margin if c.margin > 0 else -c.excess), "trials": a.norms.size}
    with np.errstate(over="ignore", under="ignore"):
        bound = a.norms[0] * np.power(c.rho, k.astype(float))
    shown = np.where((bound > floor) & (bound < 1e300), bound, np.nan)
    tag(fig, "rho-bound", *ax.plot(k, shown, color=RED, **LIMIT_STYLE, label=f"ρᵏ ‖e₀‖, ρ = {info['rho']}"))
    pred = np.where((a.predicted > floor) & (a.predicted < 1e300), a.predicted, np.nan)
    tag(fig, "lifted-prediction", *ax.plot(k, pred, color=GREY, **REFERENCE_STYLE,
                                           label="lifted model (I − HQ)ᵏ e₀"))
    ax.set_yscale("log")
    _log_labels(ax)
    ax.set_xlabel("trial k")
    ax.set_ylabel(_label("error norm ‖e_k‖", _unit(result, 1)))
    ax.set_xlim(-0.3, a.norms.size - 0.7)
    ax.legend(loc="best", framealpha=0.9)
    info.update(first=float(a.norms[0]), last=float(a.norms[-1]),
                ratio=float(a.norms[-1] / a.norms[0]) if a.norms[0] > 0 else float("nan"))
    info["monotone"] = c.monotone
    return fig, info


def _log_labels(ax: Any) -> None:
    """Plain tick labels on the log y axis; the minor ticks labelled too when it spans less than a decade."""
    from matplotlib.ticker import FuncFormatter, NullFormatter

    plain_ticks(ax.yaxis)
    lo, hi = ax.get_ylim()
    narrow = lo > 0 and hi / lo < 10.0
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _p: f"{v:.2g}") if narrow else NullFormatter())


def error_norm_figure(result: Any) -> Figure | None:
    """The error norm of every trial (log scale) against the certificate's bound ``rho^k ||e_0||`` and the lifted
    model's prediction."""
    a = trial_analysis(result)
    if a is None:
        return None
    svg, keys, info = render_tagged(_draw_norms, result, a)
    first = "computed torque alone" if result.design.data.sampled is None else "with no input"
    text = ("Euclidean norm of the sampled tracking error qD − q over every joint and instant, per trial "
            f"(log scale; trial 0 runs {first}, d₀ = 0; {info['trials']} trials)")
    if "measured" in keys:
        u = _unit(result, 1)
        text += (f": from {sci(info['first'])}{' ' + u if u else ''} in the first trial to {sci(info['last'])}"
                 f"{' ' + u if u else ''} in the last "
                 f"(×{sci(info['ratio'])})")
    text += "."
    if "rho-bound" in keys:
        if info["monotone"]:
            text += f" Dashed, red: the bound ρᵏ ‖e₀‖ the certificate proves, ρ = ‖I − Q H‖₂ = {info['rho']}"
            text += (", so close to 1 that the line is flat: the worst-case rate guarantees that the error does not "
                     "grow, nothing more." if info["rho"].startswith("1 −") else ".")
        elif info["monotone"] is False:
            text += (f" Dashed, red: ρᵏ ‖e₀‖ with ρ = ‖I − Q H‖₂ = {info['rho']}, above 1: no decrease is "
                     "certified, and the lifted model's largest singular direction grows at this rate.")
        else:
            text += (f" Dashed, red: ρᵏ ‖e₀‖ with ρ = ‖I − Q H‖₂ = {info['rho']}, not decided (its proved bracket "
                     "reaches 1, or lies within the boundary tolerance of it)"
                     + (", so close to 1 that the line is flat: no rate is proved." if info["rho"].startswith("1 ")
                        else "."))
    if "lifted-prediction" in keys:
        text += (" Dash-dot, grey: the lifted model's prediction (I − H Q)ᵏ e₀ from the first trial's error, exact "
                 "for the controller's error system; its distance to the measured points is what the model mismatch "
                 "and the coupling between joints change.")
    return Figure("Tracking error norm per trial", text, svg, "fig-ilc-error-norm.svg",
                  _evidence(result, ("ilc_error_decrease", "ilc_convergence", "ilc_lifted_model")))


# ----------------------------------------------------------------------------- first and last trials


def _draw_errors(result: Any) -> tuple[Any, dict[str, Any]]:
    trials = result.trials.results
    first, last = trials[0], trials[-1]
    n = first.n_joints
    fig, axes = new_figure(6.8, 2.2 + 1.6 * n, rows=n)
    t = np.asarray(first.time)
    for j, ax in enumerate(axes):
        color = JOINT_COLORS[j % len(JOINT_COLORS)]
        tag(fig, "first-trial", *plot_decimated(ax, t, first.tracking_errors[:, j], color=color, lw=1.0, alpha=0.55,
                                                ls="--", label=f"trial 0, joint {j + 1}"))
        tag(fig, "last-trial", *plot_decimated(ax, t, last.tracking_errors[:, j], color=color,
                                               label=f"trial {len(trials) - 1}, joint {j + 1}"))
        ax.axhline(0.0, color=GREY, lw=0.8)
        ax.set_ylabel(_label("q − qD", _unit(result, 1)))
        ax.legend(loc="best", framealpha=0.9)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(t[0], t[-1])
    peaks = [float(np.max(np.abs(r.tracking_errors))) for r in (first, last)]
    return fig, {"first": peaks[0], "last": peaks[1], "k": len(trials) - 1, "n": n}


def tracking_error_figure(result: Any) -> Figure | None:
    """The tracking error of every joint over the first and the last trial."""
    if result.trials is None:
        return None
    svg, keys, info = render_tagged(_draw_errors, result)
    parts = []
    u = " " + _unit(result, 1) if _unit(result, 1) else ""
    robot = result.design.data.sampled is None
    if "first-trial" in keys:
        parts.append(f"the first trial (dashed, {'computed torque alone' if robot else 'no input learned yet'}: "
                     f"largest |q − qD| = {sci(info['first'])}{u})")
    if "last-trial" in keys:
        parts.append(f"the last, trial {info['k']} (solid, with the learned "
                     f"{'acceleration' if robot else 'input'}: {sci(info['last'])}{u})")
    text = ("Tracking error q − qD " + ("of each joint (one panel per joint) " if info["n"] > 1 else "")
            + "against time in " + _sentence(parts) + ".")
    return Figure("Tracking error: first and last trials", text, svg, "fig-ilc-first-last.svg",
                  _evidence(result, ("tracking_error",)))


# ----------------------------------------------------------------------------- the learned signal


def _draw_learned(result: Any) -> tuple[Any, dict[str, Any]]:
    trials = result.trials
    d = np.asarray(trials.feedforward[-1], dtype=float)
    t = np.asarray(trials.results[-1].time)
    fig, (ax,) = new_figure(6.8, 3.4)
    for j in range(d.shape[1]):
        tag(fig, "learned", *plot_decimated(ax, t, d[:, j], color=JOINT_COLORS[j % len(JOINT_COLORS)],
                                            label=f"d (joint {j + 1})"))
    ax.axhline(0.0, color=GREY, lw=0.8)
    ax.set_xlabel("time (s)")
    robot = result.design.data.sampled is None
    ax.set_ylabel("learned acceleration (rad/s²)" if robot else _label("learned input", _unit(result, 0)))
    ax.set_xlim(t[0], t[-1])
    ax.legend(loc="best", framealpha=0.9)
    return fig, {"k": len(trials.results) - 1, "peak": float(np.max(np.abs(d))) if d.size else 0.0,
                 "n": d.shape[1]}


def learned_figure(result: Any) -> Figure | None:
    """The learned acceleration ``d_k`` the last trial ran with, per joint."""
    if result.trials is None:
        return None
    svg, keys, info = render_tagged(_draw_learned, result)
    if "learned" not in keys:
        return None
    joints = " of each joint" if info["n"] > 1 else ""
    if result.design.data.sampled is None:
        text = (f"The learned acceleration d_k{joints} the last trial (k = {info['k']}) ran with (largest |d| = "
                f"{sci(info['peak'])} rad/s²); the model's inertia maps it into the command, u = M̂(q)(q̈D + K1 e + "
                "K2 ė + d_k) + ĥ.")
    else:
        text = (f"The learned input u_k the last trial (k = {info['k']}) played to the plant, held over each sample "
                f"(largest |u| = {sci(info['peak'])}{' ' + _unit(result, 0) if _unit(result, 0) else ''}).")
    a = trial_analysis(result)
    if a is not None and a.norms[-1] < a.norms[0]:
        text += (" It is the acceleration the controller's model misses along this motion, as learned so far"
                 if result.design.data.sampled is None else " It is the input that makes the plant follow the "
                 "reference, as learned so far")
        text += ("; it falls to zero at the end of the trial, where the error's last samples depend on it least "
                 "(the adjoint update learns there slowest)." if a.contraction.kind == "adjoint" else ".")
    elif a is not None:
        text += " The learning diverged: it is not what the model misses but the growing part of the update."
    title = "Learned acceleration of the last trial" if result.design.data.sampled is None else \
        "Learned input of the last trial"
    return Figure(title, text, svg, "fig-ilc-learned.svg",
                  _evidence(result, ("ilc_error_decrease",)))
