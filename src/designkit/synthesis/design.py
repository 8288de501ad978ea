"""The outcome of a synthesis: named gains with units, the closed loop they give, how they were obtained.

A :class:`Design` is deeply frozen: gains are a read-only :class:`Gains` mapping whose arrays
cannot be written, every other mapping is a ``MappingProxyType`` over a private copy, and every
sequence a tuple.  What a design *exposes* decides which checks apply to it
(:mod:`designkit.verification.suite`): requested ``poles`` -> pole placement; a ``closed_loop``
-> Lyapunov; a ``characteristic`` -> Routh-Hurwitz (and, with linear stability conditions in
the plant parameters, the LP certificate over an uncertainty box); ``loops`` -> the checks of
each per-joint loop; ``input_loop`` -> loop margins.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from designkit.models.linear_system import LinearSystem
from designkit.synthesis.linearization import EXACT, Linearization

__all__ = ["Characteristic", "Design", "FamilyData", "FrozenDict", "Gain", "Gains", "LinearCondition", "freeze",
           "loop_matrices", "thaw"]


class FrozenDict(dict):
    """A ``dict`` that refuses every change (still JSON-serialisable, as a ``dict``)."""

    def _refuse(self, *args: Any, **kwargs: Any) -> None:
        raise TypeError("this mapping is frozen")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = _refuse  # type: ignore[assignment]
    __ior__ = _refuse  # type: ignore[assignment]

    def __hash__(self) -> int:  # type: ignore[override]
        return hash(tuple(sorted((str(k), repr(v)) for k, v in self.items())))


def freeze(value: Any) -> Any:
    """A deeply immutable copy: mappings -> :class:`FrozenDict`, lists -> tuples, arrays read-only."""
    if isinstance(value, Mapping):
        return FrozenDict({k: freeze(v) for k, v in value.items()})
    if isinstance(value, list | tuple):
        return tuple(freeze(v) for v in value)
    if isinstance(value, np.ndarray):
        out = np.array(value, copy=True)
        out.setflags(write=False)
        return out
    return value


@dataclass(frozen=True)
class FamilyData:
    """Base of a family's design data (:attr:`Design.data`): a frozen dataclass whose fields are deeply frozen on
    construction (:func:`freeze`: mappings -> :class:`FrozenDict`, lists -> tuples, arrays read-only), so a design
    stays immutable whatever its family stores."""

    def __post_init__(self) -> None:
        for f in fields(self):
            object.__setattr__(self, f.name, freeze(getattr(self, f.name)))

    def to_json(self) -> dict[str, Any]:
        """The fields in JSON types (:func:`thaw`), by name."""
        return {f.name: thaw(getattr(self, f.name)) for f in fields(self)}


def thaw(value: Any) -> Any:
    """JSON-serialisable form of a frozen value (mappings -> dict, tuples and arrays -> lists)."""
    if isinstance(value, Mapping):
        return {str(k): thaw(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [thaw(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, complex):
        return [value.real, value.imag]
    return value


@dataclass(frozen=True)
class Gain:
    """One named gain.

    Parameters
    ----------
    name : str
        As in the control law (``"K1"``).
    value : float or numpy.ndarray
        A scalar, a vector with one entry per joint, or a matrix (read-only).
    unit : str
        SI unit of the value (``"N*m/rad"``).
    meaning : str
        Its role in a few words (``"proportional"``).
    """

    name: str
    value: float | np.ndarray
    unit: str = ""
    meaning: str = ""

    def __post_init__(self) -> None:
        if isinstance(self.value, np.ndarray | list | tuple):
            arr = np.array(self.value, dtype=float)
            arr.setflags(write=False)
            object.__setattr__(self, "value", arr)
        else:
            object.__setattr__(self, "value", float(self.value))

    @property
    def per_joint(self) -> bool:
        """True for a vector with one entry per joint."""
        return isinstance(self.value, np.ndarray) and self.value.ndim == 1


@dataclass(frozen=True, eq=False)
class Gains(Mapping[str, Any]):
    """Read-only, ordered mapping gain name -> value (float or read-only array), with units.

    Examples
    --------
    >>> g = Gains.of([Gain("K1", 50.0, "N*m/rad"), Gain("K2", [1.0, 2.0], "N*m*s/rad")])
    >>> g["K1"], g.unit("K2"), g["K2"].tolist()
    (50.0, 'N*m*s/rad', [1.0, 2.0])
    """

    entries: tuple[Gain, ...] = ()

    @classmethod
    def of(cls, entries: Iterable[Gain]) -> Gains:
        """Gains from ``entries`` (names must be unique)."""
        items = tuple(entries)
        names = [g.name for g in items]
        if len(set(names)) != len(names):
            raise ValueError(f"duplicate gain names in {names}")
        return cls(items)

    def _find(self, name: str) -> Gain:
        for g in self.entries:
            if g.name == name:
                return g
        from designkit.errors import NameNotFoundError

        raise NameNotFoundError(f"gains[{name!r}]", f"no such gain; the design has {[g.name for g in self.entries]}")

    def __getitem__(self, name: str) -> Any:
        return self._find(name).value

    def __iter__(self) -> Iterator[str]:
        return iter(g.name for g in self.entries)

    def __len__(self) -> int:
        return len(self.entries)

    def unit(self, name: str) -> str:
        """Unit of gain ``name``."""
        return self._find(name).unit

    def meaning(self, name: str) -> str:
        """Role of gain ``name``."""
        return self._find(name).meaning

    def replace(self, **values: Any) -> Gains:
        """The same gains with some values replaced (units kept)."""
        return Gains(tuple(Gain(g.name, values.get(g.name, g.value), g.unit, g.meaning) for g in self.entries))

    def to_json(self) -> dict[str, float | list[float]]:
        """``{name: number or list}``."""
        return {g.name: thaw(g.value) for g in self.entries}


@dataclass(frozen=True)
class LinearCondition:
    """A stability condition affine in plant parameters: ``constant + sum coefficients[k] theta_k > 0``.

    Parameters
    ----------
    label : str
        The condition in words (``"K1 (1 + Km K2) - tau K3 > 0"``).
    constant : float
    coefficients : Mapping[str, float]
        Coefficient of each named plant parameter (missing parameters: 0).
    unit : str
        Unit of the left-hand side.
    """

    label: str
    constant: float
    coefficients: Mapping[str, float] = field(default_factory=dict)
    unit: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "coefficients", freeze({k: float(v) for k, v in self.coefficients.items()}))

    def value(self, **theta: Any) -> Any:
        """The left-hand side at parameters ``theta`` given by name (arrays broadcast)."""
        out = self.constant
        for name, c in self.coefficients.items():
            out = out + c * np.asarray(theta[name], dtype=float)
        return out

    def vector(self, names: Any) -> np.ndarray:
        """The coefficients aligned with ``names`` (``ValueError`` for a coefficient on another parameter)."""
        names = list(names)
        unknown = set(self.coefficients) - set(names)
        if unknown:
            raise ValueError(f"condition {self.label!r}: unknown parameters {sorted(unknown)}")
        return np.array([float(self.coefficients.get(n, 0.0)) for n in names])

    def at(self, theta: Any, names: Any) -> float:
        """The left-hand side at the vector ``theta`` whose entries are the parameters ``names``."""
        return float(self.constant + self.vector(names) @ np.asarray(theta, dtype=float))


@dataclass(frozen=True)
class Characteristic:
    """A design's closed-loop characteristic polynomial as a vectorised function of plant parameters.

    Parameters
    ----------
    parameters : tuple of str
        Plant parameter names the coefficients depend on (``("Km", "tau")``).
    coefficients : callable
        ``(gains, **theta) -> tuple of arrays``, highest power first; ``theta`` arrays broadcast.
    labels : tuple of str
        The coefficients in words (``"tau"``, ``"1 + Km K2"``, ...).
    gain_labels : Mapping[str, tuple[str, str]]
        For a cubic ``a0 s^3 + a1 s^2 + a2 s + a3``: the gain each of ``a1``, ``a2``, ``a3`` is
        affine in and the condition in the notes' gain form (``{"a1": ("K2", "K2 > -1/Km")}``).
    linear_conditions : callable or None
        ``gains -> tuple of LinearCondition``: the Hurwitz conditions, affine in the plant
        parameters for fixed gains (enables the LP certificate over a parameter box).
    """

    parameters: tuple[str, ...]
    coefficients: Callable[..., tuple[np.ndarray, ...]]
    labels: tuple[str, ...] = ()
    gain_labels: Mapping[str, tuple[str, str]] = field(default_factory=dict)
    linear_conditions: Callable[[Mapping[str, Any]], tuple[LinearCondition, ...]] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "gain_labels", freeze(dict(self.gain_labels)))

    def at(self, gains: Mapping[str, Any], plant: Any) -> tuple[float, ...]:
        """Coefficients on ``plant`` (its parameter values), as floats."""
        theta = {name: plant.parameter(name).value for name in self.parameters}
        return tuple(float(np.asarray(c)) for c in self.coefficients(gains, **theta))


def loop_matrices(design: Any, channel: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(A_i, b_i, c_i)`` of the loop broken at plant input ``channel`` of ``design.input_loop``, or ``None``.

    With ``input_loop`` = ``(A, B, C)`` (``A`` the closed loop, ``B`` where the plant inputs enter,
    ``C = -du/dz``): ``b_i = B[:, i]``, ``c_i = C[i, :]`` and ``A_i = A + b_i c_i`` (the loop opened at
    input ``i``, the others closed), so ``L_i(s) = c_i (sI - A_i)^-1 b_i``.
    """
    lp = design.input_loop
    if lp is None or channel >= lp.B.shape[1]:
        return None
    b = lp.B[:, [channel]]
    c = lp.C[[channel], :]
    return lp.A + b @ c, b, c


@dataclass(frozen=True, eq=False)
class Design:
    """A synthesised controller.

    Parameters
    ----------
    kind : str
        Controller family (``design.kind`` selects the family in the registry).
    plant : Plant
        The nominal plant the gains were computed for.
    gains : Gains
        Named gains with units.
    poles : tuple of complex
        Requested poles (1/s): those the synthesis places exactly on ``closed_loop`` when the design
        has one (the ``pole_placement`` check compares them); for a design without a linear loop,
        the poles it asks of the run (a sliding-mode law's sliding pole ``-c``), which its own checks
        measure.  Empty when the design does not claim exact placement (e.g. a decentralized design
        on a coupled arm, whose per-joint loops carry the placed poles).  They also set the time
        scales of the simulation step.
    zeros : tuple of complex
        Requested zeros (1/s) of the reference-to-position transfer.
    reference : str
        ``"step"`` (servo: driven by a position step) or ``"trajectory"`` (tracker: by position,
        velocity and acceleration).
    closed_loop : LinearSystem or None
        The plant with the control law, linearized at the design's operating point: inputs the
        reference signals (``xD, xDd, xDdd`` per joint) and the plant disturbances, outputs the
        joint positions and the plant inputs.
    input_loop : LinearSystem or None
        The same closed loop seen from the plant input: ``A`` the closed loop, ``B`` where the
        control enters, ``C = -du/dz``; the loop broken at input ``i`` is
        ``L_i(s) = C_i (sI - A + B_i (-C_i))^-1 B_i`` (loop margins).
    operating_point : Mapping
        ``x`` (plant state), ``xc`` (controller state), ``r`` (reference) of the linearization.
    characteristic : Characteristic or None
        Closed-form characteristic polynomial in the plant parameters.
    loops : tuple of Design
        Per-joint designs of a decentralized controller (each checked on its own).
    loop_names : tuple of str
        Names of ``loops`` (``"joint1"``).
    formulas, notes : tuple of str
        Design equations and the choices made on the user's behalf.
    extra : Mapping
        Data keyed by strings (deeply frozen): only what the generic layers read of a design by name, whatever its
        family: ``codegen_terms`` (:mod:`designkit.synthesis.codegen`) and the requirements' ``zeta`` and ``wn``
        (:func:`designkit.synthesis.requirements.poles_from_spec`, read by the pole-zero figure).  A family's own
        numbers are in :attr:`data`.
    law : Law or None
        The control law as designed (no anti-windup; the simulation adds the spec's), set with the
        closed loop (:func:`~designkit.synthesis.closed_loop.with_closed_loop`) or alone
        (:func:`~designkit.synthesis.closed_loop.with_law`).  Checks and analyses read it instead of
        rebuilding the law.
    linearization : Linearization
        What ``closed_loop`` means (:mod:`designkit.synthesis.linearization`): ``exact``, ``frozen``
        (the adaptation held at ``linearization.initial``) or ``none`` (then there is no closed loop,
        input loop or characteristic, and no linear check is offered).
    motion : TaskMotion or None
        What a task-space design tracks (:class:`designkit.simulation.motion.TaskMotion`), computed
        at synthesis, with how it resolves task accelerations to the joints (``damping``) and the conditioning
        it accepts (``max_condition``); ``None`` for a joint-space design.
    learning : Learning or None
        Repeated trials with a learning update between them (:class:`designkit.simulation.trials.Learning`);
        ``None`` for a design run once.
    label : str
        The family in words (``"PID position servo"``), for views of the design alone.
    data : Any
        The family's own design data: a frozen dataclass the family declares (its modules read typed attributes
        of it, with units in its docstring), or ``None``.
    """

    kind: str
    plant: Any
    gains: Gains
    poles: tuple[complex, ...] = ()
    zeros: tuple[complex, ...] = ()
    reference: str = "step"
    closed_loop: LinearSystem | None = None
    input_loop: LinearSystem | None = None
    operating_point: Mapping[str, Any] = field(default_factory=dict)
    characteristic: Characteristic | None = None
    loops: tuple[Design, ...] = ()
    loop_names: tuple[str, ...] = ()
    formulas: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)
    law: Any = None
    linearization: Linearization = EXACT
    motion: Any = None
    learning: Any = None
    label: str = ""
    data: Any = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "poles", tuple(complex(p) for p in self.poles))
        object.__setattr__(self, "zeros", tuple(complex(z) for z in self.zeros))
        for name in ("formulas", "notes", "loops", "loop_names"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        for name in ("operating_point", "extra"):
            object.__setattr__(self, name, freeze(dict(getattr(self, name))))
        if self.reference not in ("step", "trajectory"):
            raise ValueError(f"reference must be 'step' or 'trajectory', got {self.reference!r}")
        if not self.linearization.linear:
            present = [n for n in ("closed_loop", "input_loop", "characteristic") if getattr(self, n) is not None]
            if present:
                raise ValueError(f"a design without a linearization has no {', '.join(present)}")

    @property
    def linear_law(self) -> Any:
        """The law whose linearization ``closed_loop`` is: the law itself (``exact``), the law with its
        adaptation frozen at the initial values (``frozen``), or ``None`` (``none``)."""
        lin = self.linearization
        if lin.kind == "exact":
            return self.law
        if lin.kind == "frozen":
            return lin.freeze(lin.initial)
        return None

    # ------------------------------------------------------------------ python-control interop

    def _require_closed_loop(self) -> LinearSystem:
        if self.closed_loop is None:
            raise ValueError(f"this {self.kind} design has no nominal closed loop")
        return self.closed_loop

    def to_control(self, form: str = "ss"):
        """The nominal closed loop as a python-control system (imports python-control lazily).

        Parameters
        ----------
        form : {"ss", "tf"}
            ``"ss"``: :class:`control.StateSpace` with ``closed_loop``'s matrices and its state,
            input and output names (inputs the references ``xD, xDd, xDdd`` per joint, in rad,
            rad/s, rad/s^2, then the disturbances in N*m; outputs the joint positions in rad and the
            plant inputs in N*m); its poles are the closed-loop poles (1/s).  ``"tf"``:
            :class:`control.TransferFunction` of the same system, one entry per output/input pair
            (:meth:`LinearSystem.to_transfer`).  Both are deviations about
            ``operating_point``.

        Returns
        -------
        control.StateSpace or control.TransferFunction
            Named ``"<kind>_closed_loop"``.

        Raises
        ------
        ValueError
            When the design has no closed loop, or ``form`` is unknown.

        Examples
        --------
        >>> from designkit.synthesis.servo_loop import servo_design
        >>> from designkit.models.link import LinkPlant
        >>> sys = servo_design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0, kind="servo").to_control()
        >>> sys.input_labels[:1], sys.output_labels
        (['xD'], ['x1', 'u'])
        """
        cl = self._require_closed_loop()
        name = f"{self.kind}_closed_loop"
        if form == "ss":
            return cl.to_control(name=name)
        if form == "tf":
            return cl.to_transfer(name=name)
        raise ValueError(f"form must be 'ss' or 'tf', got {form!r}")

    def loop_system(self, channel: int | str = 0) -> LinearSystem:
        """The loop broken at plant input ``channel``, the other inputs' loops closed.

        The convention is the ``loop_margins`` check's (:mod:`designkit.verification.loop`):
        with ``input_loop`` (``A`` the closed loop, ``B`` where the plant inputs enter,
        ``C = -du/dz``), ``A_i = A + B_i C_i`` and ``L_i(s) = C_i (sI - A_i)^-1 B_i``.  Its input is
        the signal injected at the broken plant input (named as the plant input, ``"u"``), its
        output the *negated* controller output (``"-u"``), so the loop is closed by **negative**
        feedback, ``v = -L v``: the closed-loop poles are the roots of ``1 + L_i(s) = 0``, the
        input sensitivity is ``S = 1/(1 + L_i)``, and ``control.stability_margins(L_i)`` gives the
        check's gain and phase margins.  For the PID servo on the link,
        ``L(s) = Km (K2 s^2 + K1 s + K3) / (s^2 (tau s + 1))``.

        Parameters
        ----------
        channel : int or str
            Index or name of the plant input (``0`` or ``"u"``).

        Returns
        -------
        LinearSystem
            ``(A_i, B_i, C_i, 0)`` with the closed loop's state names.

        Raises
        ------
        ValueError
            When the design has no ``input_loop`` or no such input.
        """
        lp = self.input_loop
        if lp is None:
            raise ValueError(f"this {self.kind} design has no loop at the plant input")
        i = channel
        if isinstance(channel, str):
            if channel not in lp.inputs:
                raise ValueError(f"no plant input {channel!r}; the inputs are {list(lp.inputs)}")
            i = lp.inputs.index(channel)
        if not 0 <= i < len(lp.inputs):
            raise ValueError(f"channel must be in 0..{len(lp.inputs) - 1}, got {channel}")
        A, b, c = loop_matrices(self, i)
        return LinearSystem(A=A, B=b, C=c, D=np.zeros((1, 1)), states=lp.states, inputs=(lp.inputs[i],),
                            outputs=(lp.outputs[i],))

    def loop_transfer(self, channel: int | str = 0, form: str = "tf"):
        """The loop transfer ``L_i(s)`` at plant input ``channel`` as a python-control system.

        See :meth:`loop_system` for the sign convention (negative feedback: ``1 + L_i = 0``).

        Parameters
        ----------
        channel : int or str
            Index or name of the plant input.
        form : {"tf", "ss"}
            :class:`control.TransferFunction` (numerator and denominator from
            :meth:`LinearSystem.transfer_coefficients`, no cancellation) or
            :class:`control.StateSpace`.

        Returns
        -------
        control.TransferFunction or control.StateSpace
            Dimensionless (input and output in the plant input's unit), named ``"<kind>_L_<input>"``.

        Examples
        --------
        >>> from designkit.synthesis.servo_loop import servo_design
        >>> from designkit.models.link import LinkPlant
        >>> L = servo_design(LinkPlant(Km=2.0, tau=0.5), [-4, -5, -20], -3.0, kind="servo").loop_transfer()
        >>> [round(float(c), 9) for c in L.num_array[0][0]], [round(float(c), 9) for c in L.den_array[0][0]]
        ([27.0, 200.0, 400.0], [1.0, 2.0, 0.0, 0.0])
        """
        loop = self.loop_system(channel)
        name = f"{self.kind}_L_{loop.inputs[0]}"
        if form == "tf":
            return loop.to_transfer(name=name)
        if form == "ss":
            return loop.to_control(name=name)
        raise ValueError(f"form must be 'tf' or 'ss', got {form!r}")

    def _repr_html_(self) -> str:
        """Jupyter view: gains with units, poles and the closed-loop summary (no check is run)."""
        from designkit.display.design_view import design_html

        return design_html(self)
