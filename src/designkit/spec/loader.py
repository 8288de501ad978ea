"""Load a YAML spec into a validated :class:`~designkit.spec.schema.Spec`.

All problems are reported as one :class:`~designkit.errors.SpecError` whose path is the
key path of the offending field (``controller.poles[2]``) and whose message is one line.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

import yaml
from pydantic import ValidationError

from designkit.errors import SpecError
from designkit.spec.schema import Spec


def _union_tags() -> frozenset[str]:
    """Tags pydantic inserts in error locations of the spec's discriminated unions (derived, not listed)."""
    from designkit.families import FAMILIES
    from designkit.spec import plants, sections

    tags = set(FAMILIES)
    for union in (plants.PlantSpec, sections.Nonlinearity, sections.Trajectory):
        for model in union.__origin__.__args__:  # Annotated[Union[...], Field(discriminator)]
            tags.update(model.model_fields["kind"].annotation.__args__)
    return frozenset(tags)


_UNION_TAGS = _union_tags()


@dataclass(frozen=True)
class LoadedSpec:
    """A validated spec with the text it came from.

    Parameters
    ----------
    spec : Spec
        The validated spec.
    text : str
        The YAML source.
    sha256 : str
        Hex digest of the source bytes (written into reports).
    path : str
        Where it was read from (``"<string>"`` for text).
    """

    spec: Spec
    text: str
    sha256: str
    path: str


_UNION_KEYS = frozenset({"plant", "controller", "nonlinearity", "trajectory"})
"""Keys whose value is a discriminated union: pydantic puts the chosen tag right after them."""


def _key_path(loc: tuple[int | str, ...]) -> str:
    parts: list[str] = []
    previous: int | str | None = None
    for item in loc:
        tag = previous in _UNION_KEYS and item in _UNION_TAGS
        previous = item
        if isinstance(item, int):
            parts.append(f"[{item}]")
        elif tag or "[" in str(item) or str(item).startswith("function-"):
            continue  # pydantic's tag for discriminated unions / validator wrappers
        else:
            parts.append(("." if parts else "") + str(item))
    return "".join(parts)


def _message(err: dict) -> str:
    msg = str(err.get("msg", "invalid value"))
    msg = re.sub(r"^(Value error|Assertion failed), ", "", msg)
    if err.get("type") == "extra_forbidden":
        return "unknown key"
    if err.get("type") == "missing":
        return "missing required field"
    if err.get("type") == "union_tag_invalid":
        return msg
    value = err.get("input")
    if isinstance(value, int | float | str | bool) and "got" not in msg:
        return f"{msg}, got {value!r}"
    return msg


def parse_spec(text: str, *, path: str = "<string>") -> LoadedSpec:
    """Validate YAML text as a spec.

    Raises
    ------
    SpecError
        Malformed YAML or any schema violation, with the key path of the first problem.
    """
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise SpecError("", f"malformed YAML: {where}{problem}") from None
    if not isinstance(data, dict):
        raise SpecError("", f"a spec must be a YAML mapping, got {type(data).__name__}")
    try:
        spec = Spec.model_validate(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        key = _key_path(tuple(err.get("loc", ())))
        if err.get("type") in ("union_tag_invalid", "union_tag_not_found"):
            key = f"{key}.kind" if key else "kind"
        msg = _message(err)
        m = re.match(r"^(\[[\w.\[\]]*|[A-Za-z_][\w.\[\]]*): (.*)$", msg)
        if m:
            inner, msg = m.group(1), m.group(2)
            if not key:
                key = inner
            elif inner.startswith("["):
                key = f"{key}{inner}"
            elif not key.endswith(inner):
                key = f"{key}.{inner}"
        raise SpecError(key, msg) from None
    digest = hashlib.sha256(text.encode()).hexdigest()
    return LoadedSpec(spec=spec, text=text, sha256=digest, path=path)


def load_spec(path: str | Path) -> LoadedSpec:
    """Read and validate a spec file.

    Raises
    ------
    SpecError
        Unreadable file, malformed YAML or schema violation.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SpecError("", f"spec file not found: {p}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SpecError("", f"cannot read spec file {p}: {exc}") from None
    return parse_spec(text, path=str(p))
