"""Numbers, complex numbers, units and quantities as every report sentence and table writes them.

One way to write a number for the whole toolkit: :func:`fmt_number` (significant digits, ``∞``,
``nan``, ``—`` for a missing value), :func:`fmt_complex` (a real number when the imaginary part is
zero, ``-3 + j4`` otherwise), :func:`fmt_poles` (conjugate pairs as ``-3 ± j4``), :func:`quantity`
(a number with its unit, ``N·m`` never ``N*m``), :func:`sci` (``1.34 × 10⁴`` on figures).
:func:`plain_complex` rewrites the complex numbers Python writes into text (``-20+0j``,
``(-3+4j)``) the same way, for sentences that arrive already written.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = [
    "TARGET",
    "at_time",
    "fmt_complex",
    "fmt_number",
    "fmt_percent",
    "fmt_poles",
    "fmt_signed",
    "is_real",
    "plain_complex",
    "quantity",
    "relative_gap",
    "sci",
    "sentence_units",
    "unit",
]

TARGET = re.compile(r"^\s*(<=|>=|<|>|≤|≥)\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)$")
"""A requirement written as a comparison with a number (``"<= 5 %"``): operator, number, rest."""

_UNIT_STAR = re.compile(r"(?<=[A-Za-z)])\*(?=[A-Za-z(])")  # N*m -> N·m inside sentences
_UNIT_POWER = re.compile(r"(?<![A-Za-z_])(m|s|rad|kg·m|N·m)\^(2|3)(?![0-9.])")  # kg·m^2 -> kg·m², m/s^2 -> m/s²
_UNIT_EXPONENT = {"2": "²", "3": "³"}


def _powers(text: str) -> str:
    return _UNIT_POWER.sub(lambda m: m.group(1) + _UNIT_EXPONENT[m.group(2)], text)


def unit(text: str) -> str:
    """A unit as the report writes it (``N*m`` -> ``N·m``, ``kg*m^2`` -> ``kg·m²``).

    >>> unit("kg*m^2"), unit("m/s^2"), unit("N*m*s/rad")
    ('kg·m²', 'm/s²', 'N·m·s/rad')
    """
    return _powers(text.replace("*", "·"))


def sentence_units(text: str) -> str:
    """The units inside a sentence written one way (``5 N*m`` -> ``5 N·m``, ``kg*m^2`` -> ``kg·m²``; ``a * b`` and
    a symbol's power such as ``wn^2`` are left alone).

    >>> sentence_units("D_ii = 1.93 kg*m^2, f = 2 N*m*s/rad, a = 9.81 m/s^2, 1/wn^2")
    'D_ii = 1.93 kg·m², f = 2 N·m·s/rad, a = 9.81 m/s², 1/wn^2'
    """
    return _powers(_UNIT_STAR.sub("·", text))


def is_real(x: Any) -> bool:
    """True for a finite real number (not a bool)."""
    return isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool) and math.isfinite(x)


def fmt_number(value: Any, digits: int = 4) -> str:
    """A number with ``digits`` significant digits (``"∞"``, ``"nan"``, ``"—"`` for None; complex as
    :func:`fmt_complex`)."""
    if value is None:
        return "—"
    if isinstance(value, bool | np.bool_):
        return str(bool(value)).lower()
    if isinstance(value, complex | np.complexfloating):
        return fmt_complex(value, digits)
    if isinstance(value, int | float | np.integer | np.floating):
        x = float(value)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "∞" if x > 0 else "-∞"
        if x == 0:
            return "0"
        return f"{x:.{digits}g}"
    return str(value)


def fmt_complex(value: Any, digits: int = 4) -> str:
    """A complex number as an engineer writes it: real when the imaginary part is zero (to 1e-12 relative),
    ``a + jb`` / ``a - jb`` otherwise, ``jb`` when the real part is zero; each part as :func:`fmt_number`.

    Examples
    --------
    >>> fmt_complex(-20 + 0j), fmt_complex(-3 + 4j), fmt_complex(-3 - 4j), fmt_complex(-2j), fmt_complex(5)
    ('-20', '-3 + j4', '-3 - j4', '-j2', '5')
    """
    z = complex(value)
    if abs(z.imag) <= 1e-12 * max(1.0, abs(z)):
        return fmt_number(z.real, digits)
    imag = "j" + fmt_number(abs(z.imag), digits)
    if abs(z.real) <= 1e-12 * abs(z):
        return ("-" if z.imag < 0 else "") + imag
    return f"{fmt_number(z.real, digits)} {'-' if z.imag < 0 else '+'} {imag}"


def fmt_poles(poles: Iterable[complex], digits: int = 3) -> str:
    """A set of poles closed under conjugation, by increasing real part: a real pole as a number, a
    conjugate pair once as ``a ± jb`` (imaginary parts below 1e-9 relative are zero).

    Examples
    --------
    >>> fmt_poles([-3 - 4j, -20, -3 + 4j])
    '-20, -3 ± j4'
    """
    out = []
    for p in sorted((complex(p) for p in poles), key=lambda z: (z.real, z.imag)):
        if abs(p.imag) <= 1e-9 * max(1.0, abs(p)):
            out.append(fmt_number(p.real, digits))
        elif p.imag > 0:
            out.append(f"{fmt_number(p.real, digits)} ± j{fmt_number(p.imag, digits)}")
    return ", ".join(out)


_NUM = r"(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf|nan)"
_PY_COMPLEX = re.compile(
    rf"(?<![\w.])(?:\((?P<paren>[-+]?{_NUM}[-+]{_NUM}j)\)|(?P<bare>[-+]?{_NUM}[-+]{_NUM}j))(?![\w.])")


def plain_complex(text: str, digits: int = 4) -> str:
    """``text`` with every complex number written as Python or NumPy write them (``-20+0j``, ``(-3+4j)``,
    ``-3.+4.j``) rewritten by :func:`fmt_complex`; other text, and a bare imaginary such as ``2j``, is left as is.

    Examples
    --------
    >>> plain_complex("moves the poles (-20+0j -> -162+0j 1/s); poles [(-3+4j), (-3-4j)], 2j")
    'moves the poles (-20 -> -162 1/s); poles [-3 + j4, -3 - j4], 2j'
    """
    if "j" not in text:
        return text

    def rewrite(m: re.Match[str]) -> str:
        literal = m.group("paren") or m.group("bare")
        try:
            z = complex(literal)
        except ValueError:
            return m.group(0)
        return fmt_complex(z, digits)

    return _PY_COMPLEX.sub(rewrite, text)


def fmt_signed(value: Any, digits: int = 4) -> str:
    """Like :func:`fmt_number` with an explicit sign for finite non-zero reals."""
    if isinstance(value, int | float | np.integer | np.floating) and not isinstance(value, bool):
        x = float(value)
        if math.isfinite(x) and x != 0:
            return f"{x:+.{digits}g}"
    return fmt_number(value, digits)


def quantity(value: float | None, unit_text: str = "", digits: int = 4) -> str:
    """``value`` as :func:`fmt_number` with its unit (``""`` for None); a dimensionless ``1`` or
    ``1 (scaled)`` is left out, ``°`` follows the number without a space.

    Examples
    --------
    >>> quantity(5.0, "N*m"), quantity(12.5, "°"), quantity(0.25, "1 (scaled)"), quantity(None, "s")
    ('5 N·m', '12.5°', '0.25 (scaled)', '')
    """
    if value is None:
        return ""
    text = fmt_number(value, digits)
    u = unit(unit_text)
    if u == "1" or u.startswith("1 ("):  # dimensionless ("1", "1 (scaled)")
        u = u[2:]
    if not u:
        return text
    return f"{text}{u}" if u in ("°",) else f"{text} {u}"


def fmt_percent(ratio: float) -> str:
    """A ratio as a percentage with 3 significant digits (``0.125`` -> ``12.5 %``; ``∞`` when not finite); a ratio
    below 1 never reads as 100 % (``0.9997`` -> ``99.97 %``), nor one above 0 as 0 %.

    Examples
    --------
    >>> fmt_percent(0.125), fmt_percent(0.9997), fmt_percent(1.0), fmt_percent(0.0000123)
    ('12.5 %', '99.97 %', '100 %', '0.00123 %')
    """
    if not math.isfinite(ratio):
        return "∞"
    for digits in range(3, 10):
        text = f"{100 * ratio:.{digits}g}"
        if (ratio >= 1 or float(text) < 100) and (ratio <= 0 or float(text) > 0):
            return f"{text} %"
    return f"{100 * ratio:.10g} %"


def at_time(value: float) -> str:
    """``t = 1.23 s`` (3 significant digits)."""
    return f"t = {fmt_number(value, 3)} s"


def relative_gap(predicted: float, measured: float) -> str:
    """``predicted`` against ``measured`` as a signed percentage with a true minus (``−12 %``; ``—`` when
    ``measured`` is zero)."""
    return f"{fmt_signed(100 * (predicted - measured) / measured, 2)} %".replace("-", "−") if measured else "—"


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def sci(x: float, digits: int = 3) -> str:
    """``x`` to ``digits`` significant figures, large or small magnitudes as ``m × 10ⁿ`` (never ``1e+04``).

    Examples
    --------
    >>> sci(13390.2), sci(0.5), sci(2.5e-7), sci(-1e300)
    ('1.34 × 10⁴', '0.5', '2.5 × 10⁻⁷', '−1 × 10³⁰⁰')
    """
    text = f"{x:.{digits}g}"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa} × 10{str(int(exponent)).translate(_SUPERSCRIPT)}"
    return text.replace("-", "−", 1) if text.startswith("-") else text
