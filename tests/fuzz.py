"""A seeded mutation fuzzer of specs: what a new user's typos, copy-paste accidents and hostile YAML look like.

:func:`mutants` walks every leaf (and every mapping) of a spec and yields mutated YAML texts:

* values: wrong types (string, boolean, list, mapping, null), non-finite numbers, extreme finite
  numbers (``1e308``, ``5e-324``, ``-1e308``, ``0``, ``-1``), a 400-digit integer, a 20 kB string;
* structure: a key deleted, an unknown key added, a duplicated key, deep nesting;
* YAML features: a non-JSON tag (``!!binary``, ``!!set``, ``!!timestamp``), an alias of another
  node, an anchor bomb.

The mutants are drawn by a seeded generator (``random.Random(seed)``), so a failing mutant is
reproduced by its seed and index.  :func:`outcome` runs one mutant through the CLI in process and
returns what the contract is judged on.  ``tests/test_fuzz.py`` runs a bounded sample in the
suite; ``python -m tests.fuzz N`` runs a larger campaign and prints every violation.
"""

from __future__ import annotations

import copy
import io
import random
import sys
from collections.abc import Iterator
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
SPECS = sorted((ROOT / "specs").glob("*.yaml"))

VALUES: tuple[str, ...] = (
    '"abc"', "true", "yes", "[]", "{}", "null", ".nan", ".inf", "-.inf", "1e308", "-1e308", "5e-324", "1e-308",
    "0", "-1", "1" + "0" * 400, '"' + "x" * 20000 + '"', "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]", "-1e150",
)
"""Replacement values, as YAML text."""

TAGS: tuple[str, ...] = ("!!binary aGVsbG8=", "!!set {a, b}", "!!timestamp 2001-12-14", "!!str 3", "!!float 1")


@dataclass(frozen=True)
class Mutant:
    """One mutated spec: its text and how it was made (spec file, operator, key path)."""

    text: str
    source: str
    operator: str
    path: str


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


def _set(doc: Any, path: tuple[Any, ...], value: Any) -> Any:
    if not path:
        return value
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    return out


def _delete(doc: Any, path: tuple[Any, ...]) -> Any:
    out = copy.deepcopy(doc)
    node = out
    for key in path[:-1]:
        node = node[key]
    del node[path[-1]]
    return out


_MARK = "__FUZZ_VALUE__"


def _with_text(doc: Any, path: tuple[Any, ...], text: str) -> str:
    """The YAML of ``doc`` with the node at ``path`` written as the raw YAML ``text``."""
    dumped = yaml.safe_dump(_set(doc, path, _MARK), sort_keys=False, default_flow_style=None, width=10**6)
    return dumped.replace(_MARK, text, 1)


def _label(path: tuple[Any, ...]) -> str:
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else str(key))
    return out or "<root>"


def mutants(seed: int, count: int, specs: list[Path] | None = None) -> list[Mutant]:
    """``count`` mutants drawn with ``random.Random(seed)`` from the specs (default: every ``specs/*.yaml``)."""
    rng = random.Random(seed)
    sources = [(p.stem, yaml.safe_load(p.read_text())) for p in (specs or SPECS)]
    out: list[Mutant] = []
    while len(out) < count:
        name, doc = rng.choice(sources)
        paths = list(_paths(doc))
        path = rng.choice(paths)
        op = rng.choice(("value", "value", "value", "delete", "extra", "tag", "alias", "duplicate", "nest",
                         "bomb"))
        if op == "value":
            text = _with_text(doc, path, rng.choice(VALUES))
        elif op == "delete" and path:
            text = yaml.safe_dump(_delete(doc, path), sort_keys=False)
        elif op == "extra":
            target = path
            while target and not isinstance(_get(doc, target), dict):  # the nearest mapping holding the path
                target = target[:-1]
            text = yaml.safe_dump(_set(doc, (*target, "surplus_key"), 1.0) if target else {**doc, "surplus_key": 1},
                                  sort_keys=False)
            path = (*target, "surplus_key")
        elif op == "tag":
            text = _with_text(doc, path, rng.choice(TAGS))
        elif op == "alias" and len(path) >= 1:
            text = "base: &a {x: 1}\n" + _with_text(doc, path, "*a")
        elif op == "duplicate" and path and isinstance(path[-1], str):
            line = yaml.safe_dump({path[-1]: _get(doc, path)}, default_flow_style=True, width=10**6).strip()[1:-1]
            parent = path[:-1]
            text = _with_text(doc, parent, "{" + line + ", " + line + "}") if parent else \
                yaml.safe_dump(doc, sort_keys=False) + line + "\n"
        elif op == "nest":
            depth = rng.choice((50, 3000))
            text = _with_text(doc, path, "[" * depth + "1" + "]" * depth)
        elif op == "bomb":
            levels = rng.choice((6, 9))
            bomb = ["a0: &a0 [1, 1, 1, 1, 1, 1, 1, 1, 1]"]
            bomb += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, levels)]
            text = "\n".join(bomb) + "\n" + _with_text(doc, path, f"*a{levels - 1}")
        else:
            continue
        out.append(Mutant(text, name, op, _label(path)))
    return out


def _get(doc: Any, path: tuple[Any, ...]) -> Any:
    node = doc
    for key in path:
        node = node[key]
    return node


@dataclass(frozen=True)
class Outcome:
    """What ``designkit <command> FILE`` did: exit code, stdout, stderr, the files it wrote and the CPU seconds it
    took (``code`` is :data:`STOPPED` when the case was stopped at its CPU bound)."""

    code: int
    out: str
    err: str
    written: tuple[str, ...]
    cpu: float = 0.0


STOPPED = -1
"""The exit code recorded for a case stopped at its CPU-time bound."""


class _CaseTimeout(BaseException):
    """Raised by the CPU-time alarm (a BaseException: the CLI's catch-all of internal errors lets it through)."""


def _alarm(signum: int, frame: Any) -> None:
    raise _CaseTimeout


def outcome(text: str, folder: Path, command: str = "verify", extra: tuple[str, ...] = (),
            cpu: float | None = None) -> Outcome:
    """Run ``designkit verify FILE --json``, ``designkit synth FILE --out DIR`` or ``designkit codegen FILE --out DIR``
    in process on ``text``, with the further options ``extra`` (e.g. ``--budget 4``); with ``cpu``, stopped after
    that many CPU seconds (SIGPROF)."""
    import signal
    import time

    from designkit.cli import main

    folder.mkdir(parents=True, exist_ok=True)
    spec = folder / "spec.yaml"
    spec.write_text(text)
    out_dir = folder / "out"
    argv = {"verify": ["verify", str(spec), "--json"], "synth": ["synth", str(spec), "--out", str(out_dir)],
            "codegen": ["codegen", str(spec), "--out", str(out_dir)]}[command]
    argv += list(extra)
    stdout, stderr = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGPROF, _alarm) if cpu else None
    start = time.process_time()
    with redirect_stdout(stdout), redirect_stderr(stderr):
        try:
            if cpu:
                signal.setitimer(signal.ITIMER_PROF, cpu)
            code = main(argv)
        except SystemExit as exc:  # argparse
            code = int(exc.code or 0)
        except _CaseTimeout:
            code = STOPPED
        finally:
            if cpu:
                signal.setitimer(signal.ITIMER_PROF, 0)
                signal.signal(signal.SIGPROF, previous)
    used = time.process_time() - start
    written = tuple(sorted(str(p.relative_to(out_dir)) for p in out_dir.rglob("*"))) if out_dir.exists() else ()
    return Outcome(code, stdout.getvalue(), stderr.getvalue(), written, used)


def violations(result: Outcome) -> list[str]:
    """How ``result`` breaks the bad-input contract (empty: it holds)."""
    bad = []
    if result.code == STOPPED:
        bad.append(f"still running after {result.cpu:.1f} s of CPU time (stopped)")
    elif result.code not in (0, 1, 2):
        bad.append(f"exit {result.code}")
    if result.code == 2:
        lines = result.err.splitlines()
        if len(lines) != 1 or not lines[0].startswith("designkit: error: "):
            bad.append(f"stderr is not one error line: {result.err[:300]!r}")
        if "Traceback" in result.err:
            bad.append("traceback")
        if result.written:
            bad.append(f"wrote {result.written[:3]}")
    return bad


if __name__ == "__main__":  # python -m tests.fuzz [N] [SEED] [fields]
    import tempfile

    n = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    fields = len(sys.argv) > 3 and sys.argv[3] == "fields"
    with tempfile.TemporaryDirectory() as tmp:
        if fields:
            from tests.fuzz_fields import CASE_BUDGET, CASE_CPU, field_mutants

            corpus = field_mutants(seed, n, Path(tmp) / "files")
            options: tuple[str, ...] = ("--jobs", "1", "--budget", f"{CASE_BUDGET:g}")
        else:
            corpus, options, CASE_CPU = mutants(seed, n), (), None
        for k, m in enumerate(corpus):
            res = outcome(m.text, Path(tmp) / str(k), extra=options, cpu=CASE_CPU)
            bad = violations(res)
            if bad or res.code != 2 or fields:
                print(f"{k:4d} {m.source:36s} {m.operator:9s} {m.path:40s} exit {res.code} {res.cpu:5.1f} s "
                      f"{'; '.join(bad)} {res.err.strip()[:160]}", flush=True)
