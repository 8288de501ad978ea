"""Any linear plant: a transfer function or a state-space model, continuous- or discrete-time, as a :class:`Plant`.

**The model.**  ``x' = A(p) x + B(p) (u + xi)``, ``y = C(p) x + D(p) u``: each entry a number or an expression over
named parameters ``p`` (:mod:`designkit.models.expression`), so a robustness box or a plant change moves the entries
that name them.  The disturbance ``xi`` is input-equivalent (one per input, entering where the input does), as the
simplified link's.

**The tracked position is the first output** ``y1 = C1 x``, and the pipeline reads a position as a state: the
realisation makes ``y1`` a state.

* ``transfer_function`` ``G(s) = (b_0 s^m + ... + b_m) / (a_0 s^n + ... + a_n)`` (strictly proper, ``m < n``) is
  realised in the **observability canonical form** (Kailath, *Linear Systems*, 2.1): with ``a_k`` and ``b_k``
  divided by ``a_0`` and the numerator padded to ``n`` coefficients ``b_1 .. b_n``, the states are the output and
  its derivatives less the input's share, ``x_(k+1) = x_k' - beta_k (u + xi)``::

      x_k' = x_(k+1) + beta_k (u + xi)   (k < n),   x_n' = -a_n x1 - ... - a_1 x_n + beta_n (u + xi),   y = x1

  with the Markov parameters ``beta_k = b_k - sum_(j<k) a_j beta_(k-j)``.  At relative degree ``r`` the first
  ``r - 1`` of them vanish, so ``x1 = y``, ``x2 = y'``, ..., ``x_r = y^(r-1)`` *whatever the parameters*: at
  relative degree 2 or more the plant's velocity is the state ``x2`` (``velocities = (1,)``), and a rate feedback
  reads the true rate even when the plant's parameters change.  ``x_k`` has the output's unit per ``s^(k-1)``.
* ``state_space`` keeps the states as written when ``C1`` selects one state (``[0, 1, 0]``).  Otherwise the state
  ``x_k`` with the largest ``|C1_k|`` (at the nominal parameters) is replaced by ``y1`` itself:
  ``z = T x`` with ``T`` the identity whose row ``k`` is ``C1``, so ``A_z = T A T^-1``, ``B_z = T B``,
  ``C_z = C T^-1`` -- the same input-output behaviour, the position a state.  The first output may have no direct
  feedthrough (``D1 = 0``).

Elsewhere no state is the position's rate (``velocities = ()``): a family reads the output's rate as ``C1 A x``.

**Discrete-time** (``dt``, the sample period in s): the same realisations with the shift in place of the
derivative, ``x[k+1] = A x[k] + B (u[k] + xi[k])``, ``y[k] = C x[k]`` (a transfer function in ``z``, highest power
first).  Such a plant has no ODE (:meth:`LinearPlant.ode` refuses, naming ``dt``) and no state is a rate; only a
family that runs sampled plants uses it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import ModelError
from designkit.models.expression import parse_entry
from designkit.models.plant import Parameter, PlantBase, Signal, ode_function

__all__ = ["LinearPlant", "LinearRealisation", "state_space_plant", "transfer_function_plant"]

Entry = float | int | str
_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*$")
_SIMPLE = re.compile(r"^-?[\w.]+$")
MAX_ORDER = 20
"""Most states of a linear plant (a transfer function's denominator degree, a state-space ``A``'s size)."""


@dataclass(frozen=True, eq=False)
class LinearRealisation:
    """The symbolic realisation a :class:`LinearPlant` simulates, shared by every parameter value.

    Attributes
    ----------
    kind : str
        ``"transfer_function"`` or ``"state_space"``.
    names : tuple of str
        Parameter names, in the order of ``p``.
    p : casadi.SX
        Their symbols (a column).
    A, B, C, D : casadi.SX
        The realised matrices in ``p`` (``n x n``, ``n x m``, ``q x n``, ``q x m``).
    entries : casadi.SX
        Every entry as written in the spec, in the order of ``paths`` (checked finite at each parameter value).
    paths : tuple of str
        The key path of each entry under ``plant`` (``"den[0]"``, ``"A[1][2]"``).
    leading : int or None
        Index in ``entries`` of the transfer function's leading denominator coefficient (must not vanish).
    states, inputs, outputs : tuple of Signal
        The realised signals; ``states[position]`` is the first output.
    position : int
        The state that is the first output.
    velocity : int or None
        The state that is its rate for every parameter value (None: none is).
    form : str
        The realisation in words.
    equations : tuple of str
        The model as written, then the realisation, in plain text.
    dt : float or None
        The sample period (s) of a discrete-time model (``A``, ``B`` then map ``x[k]``, ``u[k]`` to ``x[k+1]``);
        None: continuous-time.
    """

    kind: str
    names: tuple[str, ...]
    p: ca.SX
    A: ca.SX
    B: ca.SX
    C: ca.SX
    D: ca.SX
    entries: ca.SX
    paths: tuple[str, ...]
    leading: int | None
    states: tuple[Signal, ...]
    inputs: tuple[Signal, ...]
    outputs: tuple[Signal, ...]
    position: int
    velocity: int | None
    form: str
    equations: tuple[str, ...]
    dt: float | None = None

    def __post_init__(self) -> None:
        n, m = self.A.size1(), self.B.size2()
        x, u, d = ca.SX.sym("x", n), ca.SX.sym("u", m), ca.SX.sym("d", m)
        object.__setattr__(self, "_ode", ode_function(f"{self.kind}_ode", x, u, d, self.p,
                                                      ca.mtimes(self.A, x) + ca.mtimes(self.B, u + d)))
        object.__setattr__(self, "_matrices", ca.Function("abcd", [self.p], [self.A, self.B, self.C, self.D]))
        object.__setattr__(self, "_entries", ca.Function("entries", [self.p], [self.entries]))

    def ode(self) -> ca.Function:
        """``(x, u, d, p) -> A x + B (u + d)``."""
        return self._ode  # type: ignore[attr-defined]

    def matrices(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(A, B, C, D)`` as arrays at the parameter vector ``values``."""
        return tuple(np.array(M, dtype=float) for M in self._matrices(values))  # type: ignore[attr-defined, return-value]

    def check(self, values: np.ndarray, blame: str | None = None) -> None:
        """Every entry finite and the leading denominator coefficient nonzero at ``values`` (:class:`ModelError` at
        the entry, or at ``blame`` -- a parameter name -- naming the entry)."""
        raw = np.array(self._entries(values), dtype=float).reshape(-1)  # type: ignore[attr-defined]
        for k, v in enumerate(raw):
            if not math.isfinite(v):
                where = self.paths[k]
                if blame is None:
                    raise ModelError(where, f"is not finite at the nominal parameters (got {v})")
                raise ModelError(blame, f"makes plant.{where} not finite (got {v})")
        if self.leading is not None and raw[self.leading] == 0.0:
            where = self.paths[self.leading]
            why = "the leading coefficient of the denominator is 0: the order drops; write den from its first nonzero "
            if blame is None:
                raise ModelError(where, why + "coefficient")
            raise ModelError(blame, f"makes plant.{where} = 0: {why}coefficient")
        for M in self.matrices(values):
            if not np.all(np.isfinite(M)):
                raise ModelError(blame or self.paths[0], "gives a realisation that is not finite")


@dataclass(frozen=True, eq=False)
class LinearPlant(PlantBase):
    """A linear plant ``x' = A x + B (u + xi)``, ``y = C x + D u`` (a :class:`Plant`; module docstring).

    Parameters
    ----------
    realisation : LinearRealisation
        The symbolic model (built by :func:`transfer_function_plant` or :func:`state_space_plant`).
    params : tuple of Parameter
        The parameters' values (any finite sign).

    Examples
    --------
    >>> plant = transfer_function_plant(["Km"], ["tau", 1, 0], {"Km": 2.0, "tau": 0.5})
    >>> [s.name for s in plant.states], plant.positions, plant.velocities
    (['x1', 'x2'], (0,), (1,))
    >>> A, B, C, D = plant.matrices()
    >>> A.tolist(), B.ravel().tolist()
    ([[0.0, 1.0], [0.0, -2.0]], [0.0, 4.0])
    """

    realisation: LinearRealisation
    params: tuple[Parameter, ...]

    @property
    def kind(self) -> str:  # type: ignore[override]
        """``"transfer_function"`` or ``"state_space"``."""
        return self.realisation.kind

    @property
    def states(self) -> tuple[Signal, ...]:
        """The realised states (the first output among them)."""
        return self.realisation.states

    @property
    def inputs(self) -> tuple[Signal, ...]:
        """The inputs."""
        return self.realisation.inputs

    @property
    def outputs(self) -> tuple[Signal, ...]:
        """The outputs; the first is the tracked position."""
        return self.realisation.outputs

    @property
    def disturbances(self) -> tuple[Signal, ...]:
        """One input-equivalent disturbance per input (same unit, entering through ``B``)."""
        ins = self.realisation.inputs
        return tuple(Signal("xi" if len(ins) == 1 else f"xi{k + 1}", s.unit,
                            f"input-equivalent disturbance on {s.name}") for k, s in enumerate(ins))

    @property
    def parameters(self) -> tuple[Parameter, ...]:
        """The named parameters of the entries."""
        return self.params

    @property
    def positions(self) -> tuple[int, ...]:
        """The state that is the first output."""
        return (self.realisation.position,)

    @property
    def velocities(self) -> tuple[int, ...]:
        """The state that is the first output's rate (``x2`` of a transfer function of relative degree 2 or more),
        else none (the rate is ``C1 A x + C1 B u``)."""
        return () if self.realisation.velocity is None else (self.realisation.velocity,)

    @property
    def dt(self) -> float | None:
        """The sample period (s) of a discrete-time plant, None for a continuous-time one."""
        return self.realisation.dt

    def ode(self) -> ca.Function:
        """``(x, u, d = xi, p) -> A(p) x + B(p) (u + xi)`` (:class:`ModelError` at ``dt`` for a discrete-time plant,
        which is a difference equation and has no ODE)."""
        if self.realisation.dt is not None:
            raise ModelError("dt", "a discrete-time plant is a difference equation x[k+1] = A x[k] + B u[k]; it has no "
                                   "ODE to integrate")
        return self.realisation.ode()

    def equations(self) -> tuple[str, ...]:
        """The model as written and its realisation, in plain text."""
        return self.realisation.equations

    def matrices(self, p: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The realised ``(A, B, C, D)`` at the plant's parameters (or the vector ``p``)."""
        return self.realisation.matrices(self.parameter_vector if p is None else np.asarray(p, dtype=float))

    def rate_row(self) -> np.ndarray:
        """``C1 A``: the first output's rate ``y1' = C1 A x`` (plus ``C1 B u``, zero at relative degree >= 2)."""
        A, _, C, _ = self.matrices()
        return C[0] @ A

    def describe(self) -> str:
        """The plant in one sentence."""
        r = self.realisation
        what = "transfer function" if r.kind == "transfer_function" else "state-space model"
        if r.dt is not None:
            what = f"discrete-time {what} (sample period {r.dt:g} s)"
        return (f"a linear {what} of order {len(r.states)} with {len(r.inputs)} input(s), realised in {r.form}; "
                f"the tracked position is its first output {r.outputs[0].name} = state {r.states[r.position].name}")

    def with_params(self, **values: float) -> LinearPlant:
        """The same plant with other parameter values (any finite number; :class:`ModelError` naming the parameter
        for an unknown name, a non-number, or a value making an entry non-finite or the order drop)."""
        checked: dict[str, float] = {}
        for name, value in values.items():
            self.parameter(name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
                raise ModelError(name, f"must be a number, got {value!r}")
            if not math.isfinite(float(value)):
                raise ModelError(name, f"must be finite, got {value!r}")
            checked[name] = float(value)
        if not checked:
            return self
        new = self._replace(checked)
        blame = next(iter(checked)) if len(checked) == 1 else ", ".join(checked)
        self.realisation.check(new.parameter_vector, blame)
        return new

    def _replace(self, values: Mapping[str, float]) -> LinearPlant:
        params = tuple(Parameter(p.name, float(values.get(p.name, p.value)), p.unit, p.meaning, positive=False)
                       for p in self.params)
        return LinearPlant(self.realisation, params)


# ----------------------------------------------------------------------------- building


def _parameters(parameters: Mapping[str, float], units: Mapping[str, str]) -> tuple[tuple[Parameter, ...], ca.SX,
                                                                                     dict[str, ca.SX]]:
    params, syms = [], {}
    for name, value in parameters.items():
        if not isinstance(name, str) or not _NAME.match(name):
            raise ModelError(f"parameters.{name}", "a parameter name is a letter or _ followed by letters, digits, _")
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise ModelError(f"parameters.{name}", f"must be a finite number, got {value!r}")
        params.append(Parameter(name, float(value), units.get(name, "1"), "parameter of the linear plant",
                                positive=False))
        syms[name] = ca.SX.sym(name)
    p = ca.vertcat(*syms.values()) if syms else ca.SX.sym("p", 0)
    return tuple(params), p, syms


def _matrix(rows: Any, name: str, syms: Mapping[str, ca.SX], shape: tuple[int | None, int | None],
            why: str) -> tuple[ca.SX, list[ca.SX], list[str]]:
    """Rows of entries -> SX matrix, its entries and their paths; shapes checked (``None``: free)."""
    if not isinstance(rows, Sequence) or isinstance(rows, str) or not rows:
        raise ModelError(name, "must be a non-empty list of rows (a list of lists of entries)")
    n_rows, n_cols = shape
    if n_rows is not None and len(rows) != n_rows:
        raise ModelError(name, f"needs {n_rows} rows ({why}), got {len(rows)}")
    width = n_cols if n_cols is not None else (len(rows[0]) if isinstance(rows[0], Sequence) else None)
    out, entries, paths = [], [], []
    for i, row in enumerate(rows):
        if not isinstance(row, Sequence) or isinstance(row, str):
            raise ModelError(f"{name}[{i}]", f"must be a list of entries, got {row!r}")
        if len(row) != width:
            raise ModelError(f"{name}[{i}]", f"needs {width} entries ({why}), got {len(row)}")
        cells = []
        for j, entry in enumerate(row):
            where = f"{name}[{i}][{j}]"
            value = parse_entry(entry, syms, where)
            cells.append(value)
            entries.append(value)
            paths.append(where)
        out.append(ca.horzcat(*cells) if cells else ca.SX(1, 0))
    return ca.vertcat(*out), entries, paths


def _signals(names: Sequence[str] | None, default: Sequence[str], key: str, units: Mapping[str, str],
             default_unit: Sequence[str], meaning: str) -> tuple[Signal, ...]:
    if names is None:
        names = list(default)
    if len(names) != len(default):
        raise ModelError(key, f"needs {len(default)} names, got {len(names)}")
    if len(set(names)) != len(names):
        raise ModelError(key, f"names must differ, got {list(names)}")
    for k, nm in enumerate(names):
        if not isinstance(nm, str) or not _NAME.match(nm):
            raise ModelError(f"{key}[{k}]", f"a signal name is a letter or _ followed by letters, digits, _; "
                                            f"got {nm!r}")
    return tuple(Signal(nm, units.get(nm, default_unit[k]), f"{meaning} {k + 1}" if len(names) > 1 else meaning)
                 for k, nm in enumerate(names))


def _text(entry: Entry) -> str:
    if isinstance(entry, str):
        return entry.strip()
    return f"{float(entry):g}"


def _polynomial(coefficients: Sequence[Entry]) -> str:
    n = len(coefficients) - 1
    terms = []
    for k, c in enumerate(coefficients):
        text = _text(c)
        if text in ("0", "-0"):
            continue
        power = n - k
        s = "" if power == 0 else ("s" if power == 1 else f"s^{power}")
        coef = text if not s or text not in ("1",) else ""
        if coef and s and not _SIMPLE.match(coef):
            coef = f"({coef})"
        terms.append(f"{coef} {s}".strip() if coef else s)
    return " + ".join(terms).replace("+ -", "- ") or "0"


def _combination(row: Sequence[Entry], names: Sequence[str]) -> str:
    terms = []
    for c, nm in zip(row, names, strict=True):
        text = _text(c)
        if text in ("0", "-0"):
            continue
        if text == "1":
            terms.append(nm)
        elif text == "-1":
            terms.append(f"-{nm}")
        else:
            terms.append(f"{text if _SIMPLE.match(text) else f'({text})'} {nm}")
    return " + ".join(terms).replace("+ -", "- ") or "0"


def transfer_function_plant(num: Sequence[Entry], den: Sequence[Entry], parameters: Mapping[str, float] | None = None,
                            *, units: Mapping[str, str] | None = None, input: str = "u",
                            output: str = "y", dt: float | None = None) -> LinearPlant:
    """The SISO plant ``y(s)/u(s) = num(s)/den(s)`` in observability canonical form (module docstring).

    Parameters
    ----------
    num, den : sequence of float or str
        Coefficients, highest power of ``s`` first; entries may be expressions over the parameters.  Strictly
        proper: ``len(num) < len(den)``; no leading zero in either; ``den`` of degree 1 to :data:`MAX_ORDER`.
    parameters : Mapping[str, float], optional
        Name -> nominal value of the parameters the entries name.
    units : Mapping[str, str], optional
        Units of the input, the output and the parameters by name (defaults: the input ``"1"``, the output
        ``"rad"``, parameters ``"1"``).
    input, output : str
        The signals' names.
    dt : float, optional
        The sample period (s) of a discrete-time plant: ``num(z)/den(z)``, realised in the same canonical form
        with the shift in place of the derivative (``x1[k] = y[k]``).

    Raises
    ------
    ModelError
        At ``num``, ``den``, ``num[k]``, ``den[k]``, ``parameters.<name>``: improper or biproper, a leading zero,
        a non-finite entry, an unknown parameter.
    """
    units = dict(units or {})
    params, p, syms = _parameters(dict(parameters or {}), units)
    if not isinstance(den, Sequence) or isinstance(den, str) or len(den) < 2:
        raise ModelError("den", "needs at least two coefficients (degree 1 or more: a plant with a state)")
    if len(den) - 1 > MAX_ORDER:
        raise ModelError("den", f"has degree {len(den) - 1}; at most {MAX_ORDER} states")
    if not isinstance(num, Sequence) or isinstance(num, str) or not num:
        raise ModelError("num", "needs at least one coefficient")
    n, m = len(den) - 1, len(num) - 1
    if m > n:
        raise ModelError("num", f"has degree {m} above the denominator's {n}: the transfer function is improper "
                                "(not realisable by a state-space model)")
    if m == n:
        raise ModelError("num", f"has the degree of the denominator ({n}): a direct feedthrough from u to the "
                                "tracked output, which must be a state; give a strictly proper transfer function")
    a = [parse_entry(c, syms, f"den[{k}]") for k, c in enumerate(den)]
    b = [parse_entry(c, syms, f"num[{k}]") for k, c in enumerate(num)]
    nominal = np.array([q.value for q in params], dtype=float)
    values = ca.Function("v", [p], [ca.vertcat(*a, *b)])
    av = np.array(values(nominal), dtype=float).reshape(-1)
    if av[0] == 0.0:
        raise ModelError("den[0]", "the leading coefficient is 0: write den from its first nonzero coefficient")
    if m > 0 and av[n + 1] == 0.0:
        raise ModelError("num[0]", "the leading coefficient is 0: write num from its first nonzero coefficient")
    if not np.any(av[n + 1:] != 0.0):
        raise ModelError("num", "the transfer function is zero: the input does not reach the output")
    bpad = [ca.SX(0.0)] * (n - 1 - m) + b
    ak = [a[k] / a[0] for k in range(1, n + 1)]
    beta: list[ca.SX] = []
    for k in range(n):  # Markov parameters: beta_k = b_k - sum_(j<k) a_j beta_(k-j)
        value = bpad[k] / a[0]
        for j in range(k):
            value = value - ak[j] * beta[k - 1 - j]
        beta.append(0.0 if k < n - 1 - m else value)  # exactly 0 below the relative degree
    A = ca.SX.zeros(n, n)
    B = ca.SX.zeros(n, 1)
    for k in range(n):
        if k + 1 < n:
            A[k, k + 1] = 1.0
        A[n - 1, k] = -ak[n - 1 - k]
        B[k] = beta[k]
    C = ca.SX.zeros(1, n)
    C[0, 0] = 1.0
    ins = _signals([input], ["u"], "input", units, ["1"], "input")
    outs = _signals([output], ["y"], "output", units, ["rad"], "output")
    y_unit = outs[0].unit
    relative = n - m
    u, y = ins[0].name, outs[0].name

    def meaning(k: int) -> str:
        if k < relative:
            return f"{y}, the output" if k == 0 else f"{y}{chr(39) * k}, the output's derivative {k}"
        return "observability canonical state"

    states = tuple(Signal(f"x{k + 1}", y_unit if k == 0 else (f"{y_unit}/s" if k == 1 else f"{y_unit}/s^{k}"),
                          meaning(k)) for k in range(n))

    def wrap(text: str) -> str:
        return text if _SIMPLE.match(text) else f"({text})"

    exact = ", ".join(f"x{k + 1} = {y}{chr(39) * k}" for k in range(relative))
    lines = [f"{y}(s)/{u}(s) = {wrap(_polynomial(num))} / {wrap(_polynomial(den))}",
             f"observability canonical form: {exact}; x_k' = x_(k+1) + β_k ({u} + ξ), "
             f"x_n' = −Σ (a_j/a_0) x_(n+1−j) + β_n ({u} + ξ), β the Markov parameters"]
    if dt is not None:
        lines = [lines[0].replace("(s)", "(z)").replace("s^", "z^").replace(" s ", " z ").replace(" s)", " z)")
                 + f", sample period {dt:g} s",
                 f"observability canonical form: x1[k] = {y}[k]; x_k[k+1] = x_(k+1)[k] + β_k {u}[k], "
                 f"x_n[k+1] = −Σ (a_j/a_0) x_(n+1−j)[k] + β_n {u}[k], β the Markov parameters"]
    realisation = LinearRealisation(
        kind="transfer_function", names=tuple(q.name for q in params), p=p, A=A, B=B, C=C, D=ca.SX.zeros(1, 1),
        entries=ca.vertcat(*a, *b), paths=tuple([f"den[{k}]" for k in range(len(den))]
                                                + [f"num[{k}]" for k in range(len(num))]),
        leading=0, states=states, inputs=ins, outputs=outs, position=0,
        velocity=1 if relative >= 2 and dt is None else None,
        form=f"observability canonical form ({exact})" if dt is None else "observability canonical form (x1 = y)",
        equations=tuple(lines), dt=None if dt is None else float(dt))
    realisation.check(nominal)
    return LinearPlant(realisation, params)


def state_space_plant(A: Any, B: Any, C: Any, D: Any = None, parameters: Mapping[str, float] | None = None, *,
                      states: Sequence[str] | None = None, inputs: Sequence[str] | None = None,
                      outputs: Sequence[str] | None = None, units: Mapping[str, str] | None = None,
                      dt: float | None = None) -> LinearPlant:
    """The plant ``x' = A x + B (u + xi)``, ``y = C x + D u`` (module docstring for the realisation).

    Parameters
    ----------
    A, B, C, D : list of lists of float or str
        ``n x n``, ``n x m``, ``q x n``, ``q x m`` (``D`` default zero), entries numbers or expressions over the
        parameters; ``n`` at most :data:`MAX_ORDER`.
    parameters : Mapping[str, float], optional
        Name -> nominal value.
    states, inputs, outputs : sequence of str, optional
        Names (defaults ``x1..``, ``u1..`` (``u`` for one), ``y1..`` (``y`` for one)).
    units : Mapping[str, str], optional
        Units by signal or parameter name (defaults: states and inputs ``"1"``, the first output ``"rad"``, others
        ``"1"``; parameters ``"1"``).
    dt : float, optional
        The sample period (s) of a discrete-time plant ``x[k+1] = A x[k] + B u[k]``.

    Raises
    ------
    ModelError
        At ``A``, ``B[k]``, ``C[i][j]``, ``D``, ``states``, ...: a shape that does not fit, a non-finite entry, an
        unknown parameter, a first output that measures nothing or has a direct feedthrough.
    """
    units = dict(units or {})
    params, p, syms = _parameters(dict(parameters or {}), units)
    if not isinstance(A, Sequence) or isinstance(A, str) or not A:
        raise ModelError("A", "must be a non-empty square list of rows")
    n = len(A)
    if n > MAX_ORDER:
        raise ModelError("A", f"has {n} rows; at most {MAX_ORDER} states")
    Am, ea, pa = _matrix(A, "A", syms, (n, n), f"A is square, {n} x {n}")
    Bm, eb, pb = _matrix(B, "B", syms, (n, None), f"one row per state, {n}")
    m = Bm.size2()
    if m == 0:
        raise ModelError("B", "needs at least one input column")
    Cm, ec, pc = _matrix(C, "C", syms, (None, n), f"one column per state, {n}")
    q = Cm.size1()
    if D is None:
        Dm, ed, pd = ca.SX.zeros(q, m), [], []
    else:
        Dm, ed, pd = _matrix(D, "D", syms, (q, m), f"{q} outputs x {m} inputs")
    st = _signals(states, [f"x{k + 1}" for k in range(n)], "states", units, ["1"] * n, "state")
    ins = _signals(inputs, ["u"] if m == 1 else [f"u{k + 1}" for k in range(m)], "inputs", units, ["1"] * m, "input")
    outs = _signals(outputs, ["y"] if q == 1 else [f"y{k + 1}" for k in range(q)], "outputs", units,
                    ["rad"] + ["1"] * (q - 1), "output")
    nominal = np.array([par.value for par in params], dtype=float)
    entries = ca.vertcat(*ea, *eb, *ec, *ed)
    paths = tuple(pa + pb + pc + pd)
    for k in range(m):
        d0 = Dm[0, k]
        if not (d0.is_constant() and float(ca.DM(d0)) == 0.0):
            raise ModelError(f"D[0][{k}]", "the first output is the tracked position, read as a state: it may have no "
                                           "direct feedthrough (D[0] = 0)")
    c1 = np.array(ca.Function("c1", [p], [Cm[0, :]])(nominal), dtype=float).reshape(-1)
    if not np.all(np.isfinite(c1)) or not np.any(c1 != 0.0):
        raise ModelError("C[0]", "the first output is the tracked position; its row measures nothing (all zero or "
                                 "not finite)")
    unit_row = [j for j in range(n) if Cm[0, j].is_constant() and float(ca.DM(Cm[0, j])) == 1.0]
    others_zero = all(Cm[0, j].is_constant() and float(ca.DM(Cm[0, j])) == 0.0 for j in range(n)
                      if j not in unit_row[:1])
    names = [s.name for s in st]
    drive = [f"({s.name} + ξ)" if m == 1 else f"({s.name} + ξ{k + 1})" for k, s in enumerate(ins)]
    lines = []
    for i in range(n):
        parts = [t for t in (_combination(A[i], names), _combination(B[i], drive)) if t != "0"]
        lhs = f"{names[i]}[k+1]" if dt is not None else f"{names[i]}'"
        lines.append(f"{lhs} = " + (" + ".join(parts).replace("+ -", "- ") if parts else "0"))
    lines += [f"{outs[i].name} = {_combination(C[i], names)}" for i in range(q)]
    if len(unit_row) >= 1 and others_zero:
        k = unit_row[0]
        A_z, B_z, C_z, states_out = Am, Bm, Cm, st
        form = "the state-space form as given"
    else:
        k = int(np.argmax(np.abs(c1)))
        c = Cm[0, :]
        T = ca.SX.eye(n)
        Tinv = ca.SX.eye(n)
        for j in range(n):
            T[k, j] = c[j]
            Tinv[k, j] = (1.0 / c[k]) if j == k else -c[j] / c[k]
        A_z, B_z, C_z = ca.mtimes(ca.mtimes(T, Am), Tinv), ca.mtimes(T, Bm), ca.mtimes(Cm, Tinv)
        states_out = tuple(Signal(outs[0].name, outs[0].unit, "the first output, the tracked position") if j == k
                           else s for j, s in enumerate(st))
        if outs[0].name in names[:k] + names[k + 1:]:
            raise ModelError("outputs[0]", f"{outs[0].name!r} replaces state {names[k]} in the realisation and must "
                                           "differ from the other states' names")
        form = f"the given states with {names[k]} replaced by the first output {outs[0].name} = C1 x"
        lines.append(f"realised with the state {outs[0].name} = {_combination(C[0], names)} in place of {names[k]}")
    realisation = LinearRealisation(
        kind="state_space", names=tuple(par.name for par in params), p=p, A=A_z, B=B_z, C=C_z, D=Dm,
        entries=entries, paths=paths, leading=None, states=states_out, inputs=ins, outputs=outs, position=k,
        velocity=None, form=form, equations=tuple(lines), dt=None if dt is None else float(dt))
    realisation.check(nominal)
    return LinearPlant(realisation, params)
