"""Formulas typeset from their plain-text form: identifiers with subscripts, fractions, words apart.

:func:`equation` turns a plain-text formula (``x1/xD = Km(...) / (τ s³ + ...)``) into an
:class:`Equation` of :class:`MathToken` and :class:`MathFrac` nodes, which the HTML renderer writes
as MathML and the PDF renderer as Typst math.  Trailing words (a parenthesised remark, or prose after
the formula) become the equation's note.
"""

from __future__ import annotations

import dataclasses
import re
import unicodedata
from dataclasses import dataclass
from typing import Any

__all__ = ["Equation", "MathFrac", "MathToken", "equation", "line_pieces"]


@dataclass(frozen=True)
class MathToken:
    """A token of a typeset formula: ``kind`` is ``"mi"`` (identifier), ``"mn"`` (number),
    ``"mo"`` (operator), ``"sep"`` (a comma or semicolon between two formulas of one line, set
    with a wide space) or ``"mtext"`` (words); ``sub``/``sup`` are attached sub- and superscripts."""

    kind: str
    text: str
    sub: str = ""
    sup: str = ""


@dataclass(frozen=True)
class MathFrac:
    """A fraction of two token rows."""

    num: tuple[MathToken | MathFrac, ...]
    den: tuple[MathToken | MathFrac, ...]


@dataclass(frozen=True)
class Equation:
    """A formula to typeset: ``label`` (what it is), ``nodes`` (tokens and fractions), ``note``
    (words shown next to it) and ``text`` (the plain-text original, for alt text and search)."""

    label: str
    nodes: tuple[MathToken | MathFrac, ...]
    note: str = ""
    text: str = ""


_WORDS = {"tau": "τ", "xi": "ξ", "qd": "q̇", "qdd": "q̈", "Jdot": "J̇"}
_FUNCTIONS = frozenset({"sin", "cos", "tan", "sign", "exp", "diag", "max", "min", "sat", "dt", "d"})
_SUPERSCRIPTS = {"²": "2", "³": "3", "⁻": "−", "¹": "1", "⁴": "4", "ᵀ": "T"}
_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<num>\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)"
    r"|(?P<sup>[²³⁻¹⁴ᵀ]+)"
    r"|(?P<ident>[^\W\d_][\u0300-\u036f]*(?:[A-Za-z]*)(?:\d+)?(?:_[A-Za-z0-9]+)?[\u0300-\u036f]*)"
    r"|(?P<prime>'+)"
    r"|(?P<op>.)",
    re.S,
)
_PROSE = re.compile(r"\s(?=(?:(?!(?:sin|cos|sign|dt)\b)[a-z]{2,}'?s?\s+){1,}[a-z]{2,}\b)")


def _ident(word: str) -> list[MathToken]:
    """An identifier as tokens: ``K1`` -> K_1, ``xD`` -> x_D, ``Km_i`` -> K_{m,i}, ``mgl`` -> m g l."""
    word = _WORDS.get(word, word)
    sub_i = ""
    if "_" in word:
        word, sub_i = word.split("_", 1)
        word = _WORDS.get(word, word)
    if word in _FUNCTIONS:
        return [MathToken("mi", word, sub_i)]
    base, rest = word[0], word[1:]
    while rest and unicodedata.combining(rest[0]):
        base, rest = base + rest[0], rest[1:]
    if re.fullmatch(r"[A-Za-z]?\d*", rest):
        return [MathToken("mi", base, ",".join(x for x in (rest, sub_i) if x))]
    if word.isascii() and word.isalpha() and word.islower() and len(word) <= 3:  # a product: mgl
        return [*(MathToken("mi", c) for c in word[:-1]), MathToken("mi", word[-1], sub_i)]
    return [MathToken("mi", word, sub_i)]


def _lex(text: str) -> list[MathToken]:
    tokens: list[MathToken] = []
    text = unicodedata.normalize("NFD", text)
    depth = 0
    for m in _TOKEN.finditer(text):
        kind, value = m.lastgroup, m.group()
        if kind == "space":
            continue
        if kind == "num":
            tokens.append(MathToken("mn", value))
        elif kind == "ident" and value.startswith("Δ") and len(value) > 1:  # Δx1: the increment of x1
            tokens += [MathToken("mi", "Δ"), *_ident(value[1:])]
        elif kind == "ident":
            tokens += _ident(unicodedata.normalize("NFC", value) if not _needs_nfd(value) else value)
        elif kind == "op" and value in ",;" and depth == 0:  # between formulas of one line
            tokens.append(MathToken("sep", value))
        elif (kind == "op" and value == "*" and tokens and tokens[-1].kind == "mi" and m.start() > 0
              and not text[m.start() - 1].isspace()):  # a*, q*: a starred symbol
            tokens[-1] = dataclasses.replace(tokens[-1], sup=tokens[-1].sup + "∗")
        elif kind in ("prime", "sup") and tokens and tokens[-1].kind in ("mi", "mn", "mo"):
            add = "′" * len(value) if kind == "prime" else "".join(_SUPERSCRIPTS.get(c, c) for c in value)
            last = tokens[-1]
            tokens[-1] = dataclasses.replace(last, sup=last.sup + add)
        else:
            depth += (value == "(") - (value == ")")
            tokens.append(MathToken("mo", "−" if value == "-" else value))
    return tokens


def _needs_nfd(value: str) -> bool:
    return any(unicodedata.combining(c) for c in value)


def _strip_parens(nodes: list[Any]) -> list[Any]:
    if (len(nodes) >= 2 and isinstance(nodes[0], MathToken) and nodes[0].text == "("
            and isinstance(nodes[-1], MathToken) and nodes[-1].text == ")" and not nodes[-1].sup):
        depth = 0
        for k, n in enumerate(nodes):
            if isinstance(n, MathToken) and n.text == "(":
                depth += 1
            elif isinstance(n, MathToken) and n.text == ")":
                depth -= 1
                if depth == 0 and k < len(nodes) - 1:
                    return nodes
        return nodes[1:-1]
    return nodes


def _fractions(tokens: list[MathToken], text: str) -> tuple[Any, ...]:
    """Fractions: ``a / b`` at the top level of each side of ``=`` (written with spaces), and
    ``x1/xD`` between two identifiers."""
    out: list[Any] = []
    k = 0
    while k < len(tokens):  # identifier/identifier
        t = tokens[k]
        if (t.kind == "mo" and t.text == "/" and out and isinstance(out[-1], MathToken) and out[-1].kind in ("mi", "mn")
                and k + 1 < len(tokens) and tokens[k + 1].kind == "mi"
                and (k + 2 >= len(tokens) or tokens[k + 2].text != "(")):
            num = (out.pop(),)
            if out and isinstance(out[-1], MathToken) and out[-1].text == "Δ":  # Δx1/ξ: the increment over ξ
                num = (out.pop(), *num)
            out.append(MathFrac(num, (tokens[k + 1],)))
            k += 2
            continue
        out.append(t)
        k += 1
    if " / " not in text:
        return tuple(out)
    sides: list[list[Any]] = [[]]
    for n in out:
        if isinstance(n, MathToken) and (n.text == "=" or n.kind == "sep"):
            sides.append([n])
            sides.append([])
        else:
            sides[-1].append(n)
    result: list[Any] = []
    for side in sides:
        depth, split = 0, None
        for k, n in enumerate(side):
            if isinstance(n, MathToken) and n.text == "(":
                depth += 1
            elif isinstance(n, MathToken) and n.text == ")":
                depth -= 1
            elif isinstance(n, MathToken) and n.text == "/" and depth == 0 and split is None:
                split = k
        if split is None or split == 0 or split == len(side) - 1:
            result += side
        else:
            result.append(MathFrac(tuple(_strip_parens(side[:split])), tuple(_strip_parens(side[split + 1:]))))
    return tuple(result)


def _balanced(text: str) -> bool:
    depth = 0
    for ch in text:
        depth += (ch == "(") - (ch == ")")
        if depth < 0:
            return False
    return depth == 0


def equation(label: str, text: str, note: str = "") -> Equation:
    """A plain-text formula (``x1/xD = Km(...) / (τ s³ + ...)``) as an :class:`Equation`.

    Trailing words (a parenthesised remark, or prose after the formula) become the ``note``;
    identifiers get their subscripts (``K1`` -> K₁, ``xD`` -> x_D), superscripts and primes are
    attached, and ``a / b`` at the top level of a side of ``=`` becomes a fraction.
    """
    math_part, notes = text.strip(), [note] if note else []
    paren = re.search(r"\s+\(([^()]*[a-z]{3,}\s+[a-z]{2,}[^()]*)\)\s*$", math_part)
    if paren is not None:
        math_part, notes = math_part[: paren.start()], [paren.group(1), *notes]
    prose = _PROSE.search(math_part)
    if prose is not None and _balanced(math_part[: prose.start()]):
        notes = [math_part[prose.start():].strip(" ;,"), *notes]
        math_part = math_part[: prose.start()].rstrip(" ;,")
    if "=" not in math_part:  # no formula: words only
        return Equation(label, (), "; ".join([text.strip()]), text)
    return Equation(label, _fractions(_lex(math_part), math_part), "; ".join(n for n in notes if n), text)


def _is_op(n: Any, *texts: str) -> bool:
    return isinstance(n, MathToken) and n.kind == "mo" and (not texts or n.text in texts)


def line_pieces(nodes: tuple[MathToken | MathFrac, ...]) -> list[list[list[MathToken | MathFrac]]]:
    """The units a typeset equation may be broken between, as formulas of terms.

    The equation is cut after each separator (``sep``: the formulas of one line), and each formula before
    every binary ``+``/``−`` at parenthesis depth 0 (a sign right after ``=``, ``(``, an operator or a
    separator is unary and stays with its term, one after ``)`` is binary; the first term keeps the left
    side and ``=``).  A renderer keeps each term whole and lets a line break only between terms, the
    operator opening the next line, so that no formula is split inside a parenthesis or a fraction.

    Examples
    --------
    >>> eq = equation("law", "u = -K1 (x1 - xD) + K3 xD, K4 = 2")
    >>> [[" ".join(n.text for n in term) for term in f] for f in line_pieces(eq.nodes)]
    [['u = − K ( x − x )', '+ K x ,'], ['K = 2']]
    """
    formulas: list[list[list[MathToken | MathFrac]]] = [[[]]]
    depth = 0
    for n in nodes:
        terms = formulas[-1]
        if isinstance(n, MathToken) and n.kind == "sep":
            terms[-1].append(n)
            formulas.append([[]])
            continue
        if _is_op(n, "("):
            depth += 1
        elif _is_op(n, ")"):
            depth = max(depth - 1, 0)
        previous = terms[-1][-1] if terms[-1] else None
        binary = previous is not None and (not _is_op(previous) or _is_op(previous, ")"))
        if depth == 0 and _is_op(n, "+", "−", "-") and binary:
            terms.append([])
        terms[-1].append(n)
    return [[term for term in f if term] for f in formulas if any(f)]
