"""C code of a designed controller: the family's control law, and the model terms it uses, as self-contained C.

:func:`generate_law_code` writes ``<out_dir>/<spec name>/<name>.c`` and ``<name>.h`` with CasADi's
:class:`casadi.CodeGenerator`: every function of the :class:`~designkit.synthesis.law.Law`
(``command``, ``derivative``, ``gate``, ``project``, ``update``) and, when the family needs them,
the nominal robot-model terms (``D_hat``, ``h_hat``, ``g_hat``, ``J``, ``Jdot_qd``), each as a C
function ``<name>_<role>`` with CasADi's calling convention (``arg``/``res`` pointer arrays,
``iw``/``w`` work arrays sized by ``<name>_<role>_work``).  ``<name>`` is the spec name made a C
identifier (``posspeed-link`` -> ``posspeed_link``), so the code of several controllers links into
one program without clashes.  The C file includes only ``<math.h>`` and has no ``main``; the
header adds a comment block with every function's inputs and outputs (sizes, units), the gains,
the spec name and its sha256, and the sizes ``<name>_N_Y``, ``_N_XC``, ``_N_M``, ``_N_R``, ``_N_U``.

Which model terms a design exports is the family's word: its ``design`` step sets
``design.extra["codegen_terms"]`` to the names of :data:`MODEL_TERMS` its law uses (no entry:
none).  Keeping the choice in the family module keeps the controller kinds out of this module.

A law may also carry an attribute ``exports`` (a mapping ``role -> casadi.Function``) for
functions it builds itself; they are exported as ``<name>_<role>`` after the model terms.

Writing is atomic per file (temporary file in the destination folder, then :func:`os.replace`);
bad arguments raise :class:`~designkit.errors.SpecError` naming the argument before anything is
written.  See ``docs/codegen.md``.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import tempfile
import textwrap
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from designkit.errors import SpecError
from designkit.synthesis.design import Design, thaw
from designkit.synthesis.law import Law

__all__ = [
    "LAW_ROLES", "MODEL_TERMS", "GeneratedFunction", "LawCode", "ModelTerm", "Port",
    "c_identifier", "check_name", "generate_law_code", "law_source",
]

LAW_ROLES: tuple[str, ...] = ("command", "derivative", "gate", "project", "update")
"""The law's functions, exported in this order as ``<name>_<role>``."""

_IDENTIFIER = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_MAX_NAME = 64


@dataclass(frozen=True)
class ModelTerm:
    """A nominal robot-model term a control law may use, exported as ``<name>_<term>``.

    Parameters
    ----------
    robot_function : str
        Name of the function in ``plant.robot.functions`` it is computed with.
    inputs : tuple of str
        Its C inputs, among ``"q"`` (rad) and ``"qd"`` (rad/s); a ``qdd`` input of the robot
        function is set to zero and the parameters ``p`` to the nominal plant's.
    unit : str
        Unit of the output's entries.
    meaning : str
        What the output is, in a few words.
    """

    robot_function: str
    inputs: tuple[str, ...]
    unit: str
    meaning: str


MODEL_TERMS: Mapping[str, ModelTerm] = {
    "D_hat": ModelTerm("mass_matrix", ("q",), "kg*m^2 (kg for prismatic joints)",
                       "nominal joint-space inertia matrix D^(q), n x n, column-major"),
    "h_hat": ModelTerm("inverse_dynamics", ("q", "qd"), "N*m (N for prismatic joints)",
                       "nominal Coriolis, centrifugal, gravity and friction torques h^(q, qd) "
                       "(inverse dynamics at qdd = 0)"),
    "g_hat": ModelTerm("gravity_torque", ("q",), "N*m (N for prismatic joints)", "nominal gravity torques g^(q)"),
    "J": ModelTerm("jacobian", ("q",), "m/rad in rows 1-3, 1 in rows 4-6 (revolute joints)",
                   "end-effector geometric Jacobian J(q), 6 x n, column-major"),
    "Jdot_qd": ModelTerm("jacobian_dot_qd", ("q", "qd"), "m/s^2 in rows 1-3, rad/s^2 in rows 4-6",
                         "end-effector acceleration bias Jdot(q, qd) qd"),
}
"""The model terms by name (see :class:`ModelTerm`)."""

@dataclass(frozen=True)
class Port:
    """One input or output of a generated function.

    Parameters
    ----------
    name : str
        CasADi name (``"y"``, ``"u"``).
    rows, cols : int
        Shape; the C array holds ``rows * cols`` doubles, column-major.
    description : str
        Meaning of the entries with their units.
    """

    name: str
    rows: int
    cols: int
    description: str = ""

    @property
    def size(self) -> int:
        """Number of doubles."""
        return self.rows * self.cols

    @property
    def shape(self) -> str:
        """``"[3]"`` for a column, ``"[6x2]"`` for a matrix."""
        return f"[{self.rows}]" if self.cols == 1 else f"[{self.rows}x{self.cols}]"


@dataclass(frozen=True)
class GeneratedFunction:
    """A function of the generated C code.

    Parameters
    ----------
    role : str
        ``"command"``, ..., or a model term (``"g_hat"``).
    symbol : str
        Its C name, ``<name>_<role>``.
    inputs, outputs : tuple of Port
        ``arg[i]`` and ``res[i]`` of the C call, in order.
    """

    role: str
    symbol: str
    inputs: tuple[Port, ...]
    outputs: tuple[Port, ...]

    @property
    def signature(self) -> str:
        """``"posspeed_link_command(y[2], xc[1], m[0], r[3]) -> (u[1])"``."""
        ins = ", ".join(p.name + p.shape for p in self.inputs)
        outs = ", ".join(p.name + p.shape for p in self.outputs)
        return f"{self.symbol}({ins}) -> ({outs})"


@dataclass(frozen=True)
class LawCode:
    """What :func:`generate_law_code` wrote.

    Parameters
    ----------
    directory : pathlib.Path
        ``<out_dir>/<spec name>``.
    source, header : pathlib.Path
        ``<name>.c`` and ``<name>.h``.
    name : str
        The C prefix of every exported symbol.
    kind : str
        Controller kind.
    spec_name, spec_sha256 : str or None
        The spec the design came from (None when not given).
    functions : tuple of GeneratedFunction
        The exported functions, law first, then model terms, then the law's own exports.
    """

    directory: Path
    source: Path
    header: Path
    name: str
    kind: str
    spec_name: str | None
    spec_sha256: str | None
    functions: tuple[GeneratedFunction, ...]

    @property
    def files(self) -> tuple[Path, ...]:
        """The files written."""
        return (self.source, self.header)

    def function(self, role: str) -> GeneratedFunction:
        """The generated function of ``role`` (``KeyError`` when not exported)."""
        for f in self.functions:
            if f.role == role:
                return f
        raise KeyError(role)


def c_identifier(name: str) -> str:
    """A C identifier made from a spec name: characters other than letters, digits and ``_`` become ``_``.

    Examples
    --------
    >>> c_identifier("posspeed-link"), c_identifier("2r.arm")
    ('posspeed_link', 'spec_2r_arm')
    """
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not out or not out[0].isalpha():
        out = "spec_" + out
    return out[:_MAX_NAME]


def check_name(name: str) -> str:
    if not isinstance(name, str) or not _IDENTIFIER.match(name) or len(name) > _MAX_NAME:
        raise SpecError("name", f"must be a C identifier (a letter, then letters, digits or _; at most "
                        f"{_MAX_NAME} characters), got {name!r}")
    return name


def _check_folder(spec_name: str) -> str:
    if not spec_name or spec_name in (".", "..") or "/" in spec_name or "\\" in spec_name or os.sep in spec_name:
        raise SpecError("spec_name", f"cannot be used as a folder name, got {spec_name!r}")
    return spec_name


def _dense(f: ca.Function, symbol: str) -> ca.Function:
    """``f`` under the C name ``symbol``, with dense outputs (same expression graph for SX)."""
    args = f.sx_in() if f.is_a("SXFunction") else f.mx_in()
    outs = f.call(args)
    return ca.Function(symbol, args, [ca.densify(o) for o in outs], f.name_in(), f.name_out())


def _model_term(plant: Any, term: str, symbol: str) -> ca.Function | None:
    """The term as a Function of ``q`` (and ``qd``) with the nominal parameters, or None without a robot model."""
    spec = MODEL_TERMS[term]
    robot = getattr(plant, "robot", None)
    functions = getattr(robot, "functions", None)
    if functions is None or spec.robot_function not in functions:
        return None
    f = functions[spec.robot_function]
    n = len(plant.positions)
    p = plant.model_parameters()
    sym = {"q": ca.SX.sym("q", n), "qd": ca.SX.sym("qd", n)}
    args = []
    for name in f.name_in():
        if name in sym:
            args.append(sym[name])
        elif name == "qdd":
            args.append(ca.SX.zeros(n))
        elif name == "p" and p is not None:
            args.append(ca.SX(ca.DM(np.asarray(p, dtype=float))))
        else:
            raise ValueError(f"model term {term}: unexpected input {name!r} of {spec.robot_function}")
    out = f.call(args)[0]
    return ca.Function(symbol, [sym[k] for k in spec.inputs], [ca.densify(out)], list(spec.inputs), [term])


def _terms(design: Design) -> tuple[str, ...]:
    wanted = design.extra.get("codegen_terms", ())
    unknown = [t for t in wanted if t not in MODEL_TERMS]
    if unknown:
        raise ValueError(f"{design.kind}: unknown model terms {unknown}; known: {sorted(MODEL_TERMS)}")
    return tuple(wanted)


# ---------------------------------------------------------------------------------------------
# Documentation of the ports


def _listing(names: list[str], units: list[str]) -> str:
    if not names:
        return "none"
    return ", ".join(f"{n} ({u})" if u else n for n, u in zip(names, units, strict=True))


def _state_units(law: Law) -> list[str]:
    declared = getattr(law, "state_units", None)
    if declared is not None:
        return list(declared)
    # integral_law's states are integrals of a position error
    return ["rad*s" if re.fullmatch(r"x3(_\d+)?", s) else "" for s in law.state_names]


def _per_second(unit: str) -> str:
    if not unit:
        return ""
    return unit[:-2] if unit.endswith("*s") else f"{unit}/s"


def _reference(n: int) -> str:
    if n == 1:
        return "xD (rad), xD' (rad/s), xD'' (rad/s^2)"
    return (f"xD1..xD{n} (rad), then xD'1..xD'{n} (rad/s), then xD''1..xD''{n} (rad/s^2): "
            "desired joint positions, velocities, accelerations")


def _port_docs(design: Design, law: Law) -> dict[str, str]:
    plant = design.plant
    n = len(plant.positions)
    state_units = _state_units(law)
    memory_units = list(getattr(law, "memory_units", None) or [""] * law.n_memory)
    states = list(plant.states)
    y = _listing([s.name for s in states], [s.unit for s in states])
    xc = _listing(list(law.state_names), state_units)
    return {
        "y": f"measured plant state: {y}",
        "xc": f"controller state: {xc}",
        "m": f"discrete memory: {_listing(list(law.memory_names), memory_units)}",
        "r": f"reference: {_reference(n)}",
        "gate": "anti-windup switch per controller state, 0 or 1 (from *_gate)",
        "u": "commanded plant inputs: " + _listing([s.name for s in plant.inputs], [s.unit for s in plant.inputs]),
        "xc_dot": "controller state derivative: "
                  + _listing([f"d{s}/dt" for s in law.state_names], [_per_second(u) for u in state_units]),
        "xc_projected": f"controller state after projection (anti-windup clamp): {xc}",
        "m_next": f"memory at the next controller sample: {_listing(list(law.memory_names), memory_units)}",
        "q": "joint positions: " + _listing([states[i].name for i in plant.positions],
                                            [states[i].unit for i in plant.positions]),
        "qd": "joint velocities: " + _listing([states[i].name for i in plant.velocities],
                                              [states[i].unit for i in plant.velocities]),
        **{t: f"{m.meaning}; unit {m.unit}" for t, m in MODEL_TERMS.items()},
    }


def _ports(f: ca.Function, docs: Mapping[str, str]) -> tuple[tuple[Port, ...], tuple[Port, ...]]:
    ins = tuple(Port(f.name_in(i), *f.size_in(i), docs.get(f.name_in(i), "")) for i in range(f.n_in()))
    outs = tuple(Port(f.name_out(i), *f.size_out(i), docs.get(f.name_out(i), "")) for i in range(f.n_out()))
    return ins, outs


# ---------------------------------------------------------------------------------------------
# Header


def _comment(text: str) -> str:
    return text.replace("*/", "* /")


def _wrapped(prefix: str, text: str, indent: int) -> list[str]:
    lines = textwrap.wrap(text, width=100 - indent, break_long_words=False, break_on_hyphens=False) or [""]
    pad = " " * indent
    return [prefix + lines[0]] + [pad + line for line in lines[1:]]


def _number(value: Any) -> str:
    arr = np.asarray(value, dtype=float)
    return f"{float(arr):.17g}" if arr.ndim == 0 else "[" + ", ".join(f"{x:.17g}" for x in arr.ravel()) + "]"


def _header_comment(code: LawCode, design: Design, law: Law, law_lines: tuple[str, ...]) -> str:
    from importlib import metadata

    try:
        version = metadata.version("designkit")
    except metadata.PackageNotFoundError:  # a source tree that was never installed
        version = "(not installed)"
    lines = [f"designkit {version}: C code of the {design.kind} controller"
             + (f" of spec {code.spec_name!r}" if code.spec_name else "") + ".",
             f"spec sha256: {code.spec_sha256 or 'unknown (not generated from a spec file)'}",
             f"plant: {design.plant.kind}; CasADi {ca.__version__}; see docs/codegen.md for the calling convention."]
    if design.label:
        lines.append(f"family: {design.label}")
    lines += [f"  law: {line}" for line in law_lines]
    lines += ["", "Gains:"]
    for k in design.gains:
        unit, meaning = design.gains.unit(k), design.gains.meaning(k)
        lines += _wrapped(f"  {k} = ", f"{_number(design.gains[k])} {unit}".strip()
                          + (f": {meaning}" if meaning else ""), 6)
    settings = {k: v for k, v in thaw(law.settings).items() if k != "gains"}
    if settings:
        lines += ["", "Settings:"]
        for k, v in settings.items():
            lines += _wrapped(f"  {k}: ", json.dumps(v), 6)
    period = getattr(law, "sampling_period", None)
    if getattr(law, "command_after_update", False):
        lines += ["", "Order at each controller sample" + (f" (every {period:g} s)" if period else "") + ": measure y, "
                  "then m = update(y, xc, m, r), then u = command(y, xc, m, r) with the updated memory."]
    elif law.memory_names:
        lines += ["", "Order at each controller sample: u = command(y, xc, m, r) with the memory of the previous "
                  "sample, then m = update(y, xc, m, r)."]
    lines += ["", "Functions: int NAME(const casadi_real** arg, casadi_real** res, casadi_int* iw, "
                  "casadi_real* w, int mem);", "  arrays of doubles, matrices column-major; "
                  "work sizes from NAME_work() or the NAME_SZ_* macros."]
    for f in code.functions:
        lines += ["", f"{f.signature}"]
        for label, ports in (("arg", f.inputs), ("res", f.outputs)):
            for i, p in enumerate(ports):
                lines += _wrapped(f"  {label}[{i}] {p.name}{p.shape}: ", p.description or "(undocumented)", 6)
    body = "\n".join((" * " + _comment(line)).rstrip() for line in lines)
    return f"/*\n{body}\n */\n"


def _sizes(code: LawCode, law: Law) -> str:
    cmd = code.function("command")
    sizes = {"N_Y": cmd.inputs[0].size, "N_XC": law.n_state, "N_M": law.n_memory, "N_R": cmd.inputs[3].size,
             "N_U": cmd.outputs[0].size}
    meaning = {"N_Y": "plant state y", "N_XC": "controller state xc", "N_M": "memory m", "N_R": "reference r",
               "N_U": "command u"}
    body = "\n".join(f"#define {code.name}_{k} {v}  /* doubles in the {meaning[k]} */" for k, v in sizes.items())
    return f"/* Sizes of the law's vectors. */\n{body}\n"


# ---------------------------------------------------------------------------------------------
# Writing


def _stage(folder: Path, name: str, text: str) -> Path:
    fd, tmp = tempfile.mkstemp(prefix=f".{name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fchmod(fh.fileno(), 0o644)
            os.fsync(fh.fileno())
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    return Path(tmp)


def _write(folder: Path, files: Mapping[str, str]) -> None:
    """Write ``files`` (name -> text) into ``folder`` atomically; on failure remove what was created."""
    created: list[Path] = []
    staged: list[Path] = []
    try:
        missing, p = [], folder
        while not p.exists() and p != p.parent:
            missing.append(p)
            p = p.parent
        for d in reversed(missing):
            d.mkdir()
            created.append(d)
        for name, text in files.items():
            staged.append(_stage(folder, name, text))
        for tmp, name in zip(staged, files, strict=True):
            os.replace(tmp, folder / name)
    except BaseException:
        for tmp in staged:
            with contextlib.suppress(OSError):
                tmp.unlink()
        for d in reversed(created):
            with contextlib.suppress(OSError):
                d.rmdir()
        raise


def _generate(functions: list[ca.Function], name: str) -> tuple[str, str]:
    """CasADi's C source and header for ``functions`` in a file ``<name>.c``."""
    gen = ca.CodeGenerator(f"{name}.c", {"with_header": True, "verbose": False, "main": False})
    for f in functions:
        gen.add(f)
    with tempfile.TemporaryDirectory(prefix="designkit-codegen-") as tmp:
        gen.generate(tmp + os.sep)
        source = (Path(tmp) / f"{name}.c").read_text(encoding="utf-8")
        header = (Path(tmp) / f"{name}.h").read_text(encoding="utf-8")
    return source, header


def _functions(design: Design, law: Law, name: str) -> tuple[list[ca.Function], list[str]]:
    """The exported functions (law, model terms, the law's own exports) under their C names, and their roles."""
    functions: list[ca.Function] = [_dense(getattr(law, role), f"{name}_{role}") for role in LAW_ROLES]
    roles = list(LAW_ROLES)
    for term in _terms(design):
        f = _model_term(design.plant, term, f"{name}_{term}")
        if f is not None:
            functions.append(f)
            roles.append(term)
    for role, f in dict(getattr(law, "exports", None) or {}).items():
        if role in roles or not _IDENTIFIER.match(role):
            raise ValueError(f"{design.kind}: law export {role!r} is not a new C identifier")
        functions.append(_dense(f, f"{name}_{role}"))
        roles.append(role)
    return functions, roles


def _source_text(kind: str, spec_name: str | None, name: str, source: str) -> str:
    of_spec = f" of spec {_comment(spec_name)!r}" if spec_name else ""
    return f"/* designkit: C code of the {kind} controller{of_spec}; the functions are documented in {name}.h. */\n" \
        + source


def law_source(design: Design, law: Law, *, name: str, spec_name: str | None = None) -> str:
    """The text of ``<name>.c`` that :func:`generate_law_code` writes for these arguments, without writing anything.

    Parameters
    ----------
    design, law
        As for :func:`generate_law_code`.
    name : str
        The C prefix (a C identifier).
    spec_name : str, optional
        The spec named in the file's first line.

    Raises
    ------
    SpecError
        ``name`` not a C identifier.
    """
    name = check_name(name)
    functions, _ = _functions(design, law, name)
    source, _ = _generate(functions, name)
    return _source_text(design.kind, spec_name, name, source)


def generate_law_code(
    design: Design,
    law: Law,
    out_dir: str | os.PathLike[str],
    *,
    name: str | None = None,
    spec_name: str | None = None,
    spec_sha256: str | None = None,
    law_lines: tuple[str, ...] = (),
) -> LawCode:
    """Write the C code of ``law`` (and the model terms its family uses) to ``out_dir/<spec name>/``.

    Parameters
    ----------
    design : Design
        The design (gains, plant, kind) the law was built from.
    law : Law
        Its control law (``design.law``, which carries the spec's anti-windup).
    out_dir : path-like
        Root folder; created when missing.
    name : str, optional
        C prefix of every symbol and base name of the files; default ``c_identifier(spec_name)``,
        else ``design.kind``.
    spec_name : str, optional
        Folder name under ``out_dir`` and the spec named in the header; default ``name``.
    spec_sha256 : str, optional
        Hash of the spec text, written into the header.
    law_lines : tuple of str
        The control law in words (the family's ``display.law``), written into the header.

    Returns
    -------
    LawCode
        The files written and the exported functions with their inputs and outputs.

    Raises
    ------
    SpecError
        ``name`` not a C identifier, ``spec_name`` not a folder name, or ``out_dir`` not
        writable (path ``"out_dir"``); nothing is written.
    """
    name = check_name(name if name is not None else c_identifier(spec_name) if spec_name else design.kind)
    folder = Path(out_dir) / _check_folder(spec_name if spec_name is not None else name)

    docs = _port_docs(design, law)
    functions, roles = _functions(design, law, name)
    generated = tuple(GeneratedFunction(role, f.name(), *_ports(f, docs))
                      for role, f in zip(roles, functions, strict=True))
    code = LawCode(directory=folder, source=folder / f"{name}.c", header=folder / f"{name}.h", name=name,
                   kind=design.kind, spec_name=spec_name, spec_sha256=spec_sha256, functions=generated)

    source, header = _generate(functions, name)
    comment = _header_comment(code, design, law, tuple(law_lines))
    guard = f"DESIGNKIT_{name.upper()}_H"
    header_text = (f"{comment}\n#ifndef {guard}\n#define {guard}\n\n{header}\n{_sizes(code, law)}\n"
                   f"#endif /* {guard} */\n")
    source_text = _source_text(design.kind, spec_name, name, source)
    try:
        _write(folder, {f"{name}.c": source_text, f"{name}.h": header_text})
    except OSError as exc:
        raise SpecError("out_dir", f"cannot write the C code to {folder}: {exc.strerror or exc}") from None
    return code
