"""Schema-driven mutations of every controller family's fields, of comparison specs, of sweeps and of codegen.

:mod:`tests.fuzz` mutates the example specs' leaves with type and YAML accidents, :mod:`tests.fuzz_fields` the
robot-facing fields.  This module reads the spec's JSON Schema (``designkit schema``) and, for each of the
14 families, walks every field of its ``controller`` section (nested sections such as ``modification``,
``reference_model`` or ``nominal`` included) and of the ``requirements``, ``simulation`` and ``numerics``
sections, and draws values from the field's own schema: its bounds and just past them, the other end of an
enumeration, a list one too short or too long, the base value scaled by 1e±6, negated or repeated (repeated
poles), ``.nan``, the wrong type.  A mutant is one field changed in a small base spec of that family (a short
simulation), so an accepted mutant runs in about a second.

Besides ``designkit verify`` (:func:`tests.fuzz.outcome`), a mutant may go through:

* ``designkit codegen SPEC --out DIR`` (the design and its C code);
* ``designkit.sweep(SPEC, samples, engine="process")`` (:func:`sweep_outcome`: a few samples in this process,
  the spec given an uncertainty box and a ``sweep:`` section whose fields are mutated too), mapped to the
  command line's exit codes (a :class:`~designkit.errors.DesignkitError` is 2, any other exception 3);
* comparison specs (``controllers:``, from ``specs/robel.yaml`` and ``specs/mrac-vs-selftune.yaml``): one
  controller's field mutated, labels duplicated or invalid, the list emptied or overfilled.

:func:`family_mutants` draws them with ``random.Random(seed)``; ``python -m tests.fuzz_families N SEED`` runs a
campaign and prints every case that breaks the contract, with the command that reproduces it.
"""

from __future__ import annotations

import copy
import io
import json
import math
import random
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import yaml

from tests.fuzz import STOPPED, Outcome, _alarm, _CaseTimeout, outcome, violations

ROOT = Path(__file__).resolve().parents[1]
SPECS = ROOT / "specs"

FAMILY_BASES: dict[str, str] = {
    "adaptive_computed_torque": "adaptive-ct-simnog-slotine-li",
    "computed_torque": "simnog-computed-torque",
    "decentralized_pid": "simnog-decentralized-pid",
    "ilc": "ilc-simnog",
    "mrac": "mrac-link",
    "pid_servo": "posspeed-link",
    "pid_sliding_mode": "pid-sm-link",
    "pid_tracking": "tracking-pid",
    "resolved_acceleration": "puma560-resolved-acceleration-dls",
    "self_tuning": "selftune-position",
    "sliding_mode": "sliding-mode-link",
    "sliding_mode_identification": "smid-link",
    "state_regulator": "state-regulator-elastic-joint",
    "vsc": "vsc-link",
}
"""The example spec each family's mutants start from (``specs/<name>.yaml``)."""

COMPARISONS = ("robel", "mrac-vs-selftune")
"""The comparison specs whose controllers are mutated."""

SWEEP_BASE = "posspeed-perturbation"
"""A link spec with an uncertainty box: the base of the sweep mutants."""

DURATION = 0.5
"""Simulated seconds of every base (a trajectory longer than that is shortened with it)."""
CASE_BUDGET = 2.0
"""Estimated seconds of work a mutant may ask for (``--budget``)."""
CASE_CPU = 30.0
"""CPU seconds after which a case is stopped and counted as a violation."""
SWEEP_SAMPLES = 3
"""Samples of a sweep mutant."""

COMMANDS = ("verify", "codegen", "sweep")


@dataclass(frozen=True)
class Case:
    """One mutant: the spec text, its base, the key path changed, the value, and the command it goes through."""

    text: str
    base: str
    path: str
    value: str
    command: str


# ------------------------------------------------------------------------------------------------ the schema


@cache
def schema() -> dict[str, Any]:
    """The JSON Schema of a spec with one controller or several (``designkit schema --form any``)."""
    from designkit.schema.comparison import json_schema

    return json_schema("any")


def _defs() -> dict[str, Any]:
    return schema().get("$defs", {})


def _resolve(node: dict[str, Any]) -> dict[str, Any]:
    while "$ref" in node:
        node = _defs()[node["$ref"].rsplit("/", 1)[-1]]
    return node


def family_schema(kind: str) -> dict[str, Any]:
    """The schema of family ``kind``'s ``controller`` section."""
    for node in _defs().values():
        if node.get("properties", {}).get("kind", {}).get("const") == kind and "Comparison" not in node.get(
                "title", "") and "label" not in node.get("properties", {}):
            return node
    raise KeyError(kind)


def _branches(node: dict[str, Any]) -> list[dict[str, Any]]:
    node = _resolve(node)
    if "anyOf" in node or "oneOf" in node:
        return [_resolve(b) for b in node.get("anyOf", node.get("oneOf", [])) if b.get("type") != "null"]
    return [node]


def fields(node: dict[str, Any], prefix: str = "", depth: int = 0) -> list[tuple[str, dict[str, Any]]]:
    """``(key path, schema)`` of every field below ``node`` (objects opened to three levels; ``kind`` left alone)."""
    out = []
    for name, sub in _resolve(node).get("properties", {}).items():
        if name == "kind":
            continue
        path = f"{prefix}.{name}" if prefix else name
        out.append((path, sub))
        if depth < 2:
            for branch in _branches(sub):
                if branch.get("type") == "object" and "properties" in branch:
                    out += fields(branch, path, depth + 1)
    return out


# ------------------------------------------------------------------------------------------------ the values


_WRONG = ("abc", True, [], {}, None, ".nan", ".inf", "1e400")
_EXTREME = (0, -1, 1, 1e-12, -1e-12, 1e12, -1e12, 1e300, -1e300, 5e-324, 1e-300, 2.3e-308)


def _number_values(node: dict[str, Any]) -> list[Any]:
    out: list[Any] = list(_EXTREME)
    for key in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        if key in node:
            b = float(node[key])
            out += [b, b * (1 + 1e-9) + 1e-300, b * (1 - 1e-9) - 1e-300, -b]
    if node.get("type") == "integer":
        out = [int(v) if math.isfinite(v) and abs(v) < 1e18 else v for v in out] + [1.5, 10**20, 2, 3, 100]
    return out


def _scaled(value: Any, rng: random.Random) -> Any:
    """``value`` (a number, numeric string or list of them) scaled, negated, perturbed or repeated."""
    if isinstance(value, list):
        if value and rng.random() < 0.3:
            return [value[0]] * len(value)  # repeated values: repeated poles
        if value and rng.random() < 0.2:
            return value[:-1] if rng.random() < 0.5 else [*value, value[-1]]
        k = rng.randrange(len(value)) if value else 0
        return [(_scaled(v, rng) if i == k else v) for i, v in enumerate(value)]
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        return value
    try:
        number = complex(str(value).replace(" ", "")) if isinstance(value, str) else value
    except ValueError:
        return value
    factor = rng.choice((1e6, 1e-6, -1.0, 1e12, 1e-12, 0.0, 1 + 1e-12, 2.0))
    out = number * factor
    if isinstance(out, complex):
        return f"{out.real:g}{out.imag:+g}j" if out.imag else f"{out.real:g}"
    return out


def values(node: dict[str, Any], base: Any, rng: random.Random) -> list[Any]:
    """Candidate values of a field with schema ``node`` and base value ``base``."""
    out: list[Any] = list(_WRONG)
    if base is not None:
        out += [_scaled(base, rng) for _ in range(6)]
    for branch in _branches(node):
        kind = branch.get("type")
        if "enum" in branch or "const" in branch:
            out += [*branch.get("enum", [branch.get("const")]), "nope"]
        elif kind in ("number", "integer"):
            out += _number_values(branch)
        elif kind == "boolean":
            out += [True, False, "yes", 1]
        elif kind == "array":
            item = _branches(branch.get("items", {}))[0] if branch.get("items") else {}
            low, high = branch.get("minItems", 0), branch.get("maxItems", 4)
            pool = _number_values(item) if item.get("type") in ("number", "integer") else (
                ["-1", "-1e-12", "-3+4j", "-3-4j", "0", "-1e12", "1e400", -2, -2] if item.get("type") == "string"
                else [[1, 0], [0, 1], [-1, -2], [1e12, 0]])
            for n in {0, 1, 2, 3, low, max(low - 1, 0), min(high + 1, 1001), high if high < 200 else 7}:
                out.append([rng.choice(pool) for _ in range(n)])
        elif kind == "object" and "properties" not in branch:
            out += [{"x": 1}, {}, {"m2": [1, 2]}]
        elif kind == "string":
            out += ["", "x" * 300, "-1", "a\0b", "\ud800"]
    return out


# ------------------------------------------------------------------------------------------------ the specs


@cache
def _load(name: str) -> dict[str, Any]:
    return yaml.safe_load((SPECS / f"{name}.yaml").read_text())


def _short(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with a short simulation and no studies."""
    doc = copy.deepcopy(doc)
    doc.pop("studies", None)
    sim = doc.setdefault("simulation", {})
    sim["duration"] = min(float(sim.get("duration", DURATION)), DURATION)
    traj = sim.get("trajectory")
    if isinstance(traj, dict) and isinstance(traj.get("duration"), int | float):
        traj["duration"] = min(traj["duration"], sim["duration"])
    learning = doc.get("controller", {}).get("learning")
    if isinstance(learning, dict) and "trials" in learning:
        learning["trials"] = min(int(learning["trials"]), 3)
    return doc


def base(kind: str) -> dict[str, Any]:
    """The short base spec of family ``kind``."""
    return _short(_load(FAMILY_BASES[kind]))


def _get(doc: Any, path: list[Any]) -> Any:
    for key in path:
        if isinstance(doc, dict) and key in doc or isinstance(doc, list) and isinstance(key, int) and key < len(doc):
            doc = doc[key]
        else:
            return None
    return doc


def _keys(path: str) -> list[Any]:
    return [int(k) if k.isdigit() else k for k in path.replace("[", ".").replace("]", "").split(".")]


def _put(doc: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    out = copy.deepcopy(doc)
    keys = _keys(path)
    node = out
    for key in keys[:-1]:
        nxt = node[key] if isinstance(node, list) else node.get(key)
        if not isinstance(nxt, dict | list):
            nxt = {}
            node[key] = nxt
        node = nxt
    node[keys[-1]] = value
    return out


def _dump(doc: dict[str, Any]) -> str:
    text = yaml.safe_dump(doc, sort_keys=False, width=10**6, allow_unicode=True)
    return text.replace("'.nan'", ".nan").replace("'.inf'", ".inf").replace("'1e400'", "1e400")


_SECTIONS = ("Requirements", "Simulation", "Numerics")


def _section_fields() -> list[tuple[str, dict[str, Any]]]:
    out = []
    for section, name in zip(("requirements", "simulation", "numerics"), _SECTIONS, strict=True):
        out += fields(_defs()[name], section)
    return out


def _mutate(doc: dict[str, Any], where: str, field_list: list[tuple[str, dict[str, Any]]],
            rng: random.Random) -> tuple[str, Any, dict[str, Any]]:
    path, node = rng.choice(field_list)
    full = f"{where}.{path}" if where else path
    value = rng.choice(values(node, _get(doc, _keys(full)), rng))
    return full, value, _put(doc, full, value)


def _family_case(kind: str, rng: random.Random) -> tuple[str, str, Any, dict[str, Any]]:
    doc = base(kind)
    if rng.random() < 0.75:
        path, value, doc = _mutate(doc, "controller", fields(family_schema(kind)), rng)
    else:
        path, value, doc = _mutate(doc, "", _section_fields(), rng)
    return FAMILY_BASES[kind], path, value, doc


def _comparison_case(rng: random.Random) -> tuple[str, str, Any, dict[str, Any]]:
    name = rng.choice(COMPARISONS)
    doc = _short(_load(name))
    entries = doc["controllers"]
    op = rng.randrange(6)
    if op <= 2:  # one controller's field
        k = rng.randrange(len(entries))
        path, value, doc = _mutate(doc, f"controllers[{k}]", fields(family_schema(entries[k]["kind"])), rng)
        return name, path, value, doc
    if op == 3:
        value = rng.choice(("", "x" * 41, "a/b", "..", entries[0].get("label", entries[0]["kind"]), "ok-label", 7))
        k = rng.randrange(len(entries))
        return name, f"controllers[{k}].label", value, _put(doc, f"controllers[{k}].label", value)
    if op == 4:
        n = rng.choice((0, 1, 9, 50))
        value = [copy.deepcopy(entries[i % len(entries)]) for i in range(n)]
        return name, "controllers", f"{n} entries", _put(doc, "controllers", value)
    value = rng.choice(({"kind": "nope"}, {"kind": "pid_servo"}, {}, "pid_servo", None))
    k = rng.randrange(len(entries))
    return name, f"controllers[{k}]", value, _put(doc, f"controllers[{k}]", value)


_SWEEP_VALUES: dict[str, tuple[Any, ...]] = {
    "distribution": ("uniform", "normal", "corners", "gauss", 3),
    "cut": (0.5, 10, 0.49, 10.1, ".nan", 0, "abc"),
    "parameters": ({"Km": [1.5, 2.5]}, {"Km": [2.5, 1.5]}, {"Km": [-1, 1]}, {"nope": [1, 2]}, {"Km": [1e6, 1e6]},
                   {"Km": [0, 0]}, {"tau": [1e-6, 1e6]}, {"Km": [1]}, {}),
    "initial_position": ([[-0.1], [0.1]], [[0.1, 0.2]], [[100, 100]], [[-100], [100]], [], [[1]], [[0], [0]]),
    "payload": ({"mass": [0, 1]}, {"mass": [1, 0]}, {"mass": [0, 1e4], "link": 1}, {"mass": [0, 1], "link": 2},
                {"mass": [1]}),
    "noise": (True, False, "yes"),
}


def _sweep_case(rng: random.Random) -> tuple[str, str, Any, dict[str, Any]]:
    doc = _short(_load(SWEEP_BASE))
    if rng.random() < 0.6:
        key = rng.choice(sorted(_SWEEP_VALUES))
        value = rng.choice(_SWEEP_VALUES[key])
        return SWEEP_BASE, f"sweep.{key}", value, _put(doc, f"sweep.{key}", value)
    path, value, doc = _mutate(doc, "plant", fields(_defs()["Uncertainty"], "uncertainty"), rng) \
        if rng.random() < 0.5 else _mutate(doc, "controller", fields(family_schema("pid_servo")), rng)
    return SWEEP_BASE, path, value, doc


def family_mutants(seed: int, count: int) -> list[Case]:
    """``count`` mutants drawn with ``random.Random(seed)``: the 14 families in turn (each field mutant through
    ``verify``, one in six through ``codegen``), every seventh a comparison spec and every ninth a sweep."""
    from designkit.families import FAMILIES

    rng = random.Random(seed)
    kinds = sorted(FAMILIES)
    out: list[Case] = []
    turn = 0
    for k in range(count):
        if k % 9 == 8:
            name, path, value, doc = _sweep_case(rng)
            command = "sweep"
        elif k % 7 == 6:
            name, path, value, doc = _comparison_case(rng)
            command = "verify"
        else:
            name, path, value, doc = _family_case(kinds[turn % len(kinds)], rng)
            turn += 1
            command = "codegen" if rng.random() < 1 / 6 else "verify"
        out.append(Case(_dump(doc), name, path, repr(value)[:60], command))
    return out


# ------------------------------------------------------------------------------------------------ running


def sweep_outcome(text: str, folder: Path, samples: int = SWEEP_SAMPLES, cpu: float | None = CASE_CPU) -> Outcome:
    """``designkit.sweep`` of ``text`` in this process (``engine="process"``, no falsification or report) into
    ``folder/out``, as the command line would answer it: 0 every sample passed, 1 some failed, 2 and one
    ``designkit: error:`` line for a :class:`~designkit.errors.DesignkitError`, 3 for any other exception."""
    import signal

    import designkit as dk

    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "spec.yaml"
    spec.write_text(text)
    out_dir = folder / "out"
    stderr = io.StringIO()
    previous = signal.signal(signal.SIGPROF, _alarm) if cpu else None
    start = time.process_time()
    try:
        if cpu:
            signal.setitimer(signal.ITIMER_PROF, cpu)
        with redirect_stdout(io.StringIO()), redirect_stderr(stderr):
            result = dk.sweep(spec, samples, engine="process", out=out_dir, falsification=False, report=False)
        code = 0 if bool(result.passed.all()) else 1
    except _CaseTimeout:
        code = STOPPED
    except dk.DesignkitError as exc:
        code = 2
        stderr.write(f"designkit: error: {' '.join(str(exc).split())}\n")
    except Exception as exc:  # noqa: BLE001 - the contract: anything else is a bug, reported as exit 3
        code = 3
        stderr.write(f"designkit: internal error: {type(exc).__name__}: {exc}\n")
    finally:
        if cpu:
            signal.setitimer(signal.ITIMER_PROF, 0)
            signal.signal(signal.SIGPROF, previous)
    written = tuple(sorted(str(p.relative_to(out_dir)) for p in out_dir.rglob("*"))) if out_dir.exists() else ()
    return Outcome(code, "", stderr.getvalue(), written, time.process_time() - start)


def run_case(case: Case, folder: Path, cpu: float | None = CASE_CPU) -> Outcome:
    """Run ``case`` through its command (:data:`COMMANDS`) in ``folder``."""
    if case.command == "sweep":
        return sweep_outcome(case.text, folder, cpu=cpu)
    if case.command == "codegen":
        return outcome(case.text, folder, "codegen", cpu=cpu)
    return outcome(case.text, folder, "verify", ("--jobs", "1", "--budget", f"{CASE_BUDGET:g}"), cpu=cpu)


def repro(case: Case) -> str:
    """A shell line that reproduces ``case`` (the spec written by a here-document)."""
    command = {"verify": f"designkit verify spec.yaml --jobs 1 --budget {CASE_BUDGET:g}",
               "codegen": "designkit codegen spec.yaml --out /tmp/codegen-out",
               "sweep": (f"python -c \"import designkit as dk; dk.sweep('spec.yaml', {SWEEP_SAMPLES}, "
                         "engine='process', falsification=False, report=False)\"")}[case.command]
    return f"cat > spec.yaml <<'EOF'\n{case.text}EOF\n{command}"


def _main(argv: list[str]) -> int:  # python -m tests.fuzz_families [N] [SEED] [--all]
    import tempfile

    n = int(argv[0]) if argv else 200
    seed = int(argv[1]) if len(argv) > 1 else 0
    show_all = "--all" in argv
    counts: dict[tuple[str, int], int] = {}
    bad_cases = 0
    start = time.monotonic()
    with tempfile.TemporaryDirectory() as tmp:
        for k, case in enumerate(family_mutants(seed, n)):
            res = run_case(case, Path(tmp) / str(k))
            bad = violations(res)
            counts[(case.command, res.code)] = counts.get((case.command, res.code), 0) + 1
            if k % 100 == 99:
                print(f"# {k + 1} cases, {bad_cases} violations, {time.monotonic() - start:.0f} s", file=sys.stderr,
                      flush=True)
            if bad or show_all:
                bad_cases += bool(bad)
                print(f"#{k} seed {seed} {case.command} {case.base} {case.path} = {case.value}: exit {res.code} "
                      f"{res.cpu:.1f} s {'; '.join(bad)} {res.err.strip()[:300]}", flush=True)
                if bad:
                    print(repro(case), flush=True)
    print(json.dumps({"cases": n, "seed": seed, "violations": bad_cases, "seconds": round(time.monotonic() - start),
                      "exits": {f"{c} {e}": v for (c, e), v in sorted(counts.items())}}))
    return 1 if bad_cases else 0


if __name__ == "__main__":
    sys.exit(_main(sys.argv[1:]))
