"""Load a YAML spec into a validated :class:`~designkit.schema.spec.Spec`.

All problems are reported as one :class:`~designkit.errors.SpecError` whose path is the
key path of the offending field (``controller.poles[2]``) and whose message is one line.

The work is bounded before it is done, whatever the input:

* a spec file (or text) larger than :data:`MAX_SPEC_BYTES` (1 MiB) is refused before it is read
  in full;
* the YAML is composed by a loader that counts, *while parsing*, every node including those an
  alias (``*name``) stands for, and refuses a document of more than :data:`MAX_NODES` nodes once
  expanded (an anchor bomb is refused after a few hundred bytes of work) or nested deeper than
  :data:`MAX_DEPTH` levels (no ``RecursionError``);
* only JSON's types are constructed: strings, integers, floats, booleans, null, lists and
  mappings.  Other tags (``!!binary``, ``!!set``, ``!!timestamp``, ``!!python/...``, local tags)
  are refused; an unquoted date is a string; a duplicate key is an error naming its key path;
  a number beyond the floating-point range (a 400-digit integer, ``1e400``) is refused where it
  is written; ``1e-3`` is a float, as in JSON;
* a user value quoted in a message is cut to :data:`~designkit.errors.QUOTE_LIMIT` characters,
  and the ``repr`` of a large input is never built.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from dataclasses import dataclass
from typing import Any

import yaml
from pydantic import ValidationError
from yaml.events import AliasEvent, MappingStartEvent, SequenceStartEvent
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

from designkit import arguments
from designkit.errors import PATH_LIMIT, QUOTE_LIMIT, SpecError, short_repr, shorten
from designkit.schema.comparison import ComparisonSpec
from designkit.schema.spec import Spec

MAX_SPEC_BYTES = 1 << 20
"""Largest spec accepted, in bytes (1 MiB; the example specs are 0.5-2.5 kB)."""

MAX_NODES = 100_000
"""Most YAML nodes (scalars, lists, mappings) in a spec, counting every node an alias stands for."""

MAX_DEPTH = 64
"""Deepest nesting of lists and mappings in a spec (the spec format itself needs 5)."""

MAX_MESSAGE = 300
"""Longest error message (characters); the quoted user values in it are shorter still."""

_FLOAT_MAX_TEXT = "1.798e+308"
_TOO_DEEP = f"lists and mappings nested deeper than {MAX_DEPTH} levels, the limit of a spec"


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
    spec : Spec or ComparisonSpec
        The validated spec: one ``controller``, or a comparison of several (``controllers``,
        :class:`~designkit.schema.comparison.ComparisonSpec`).
    text : str
        The YAML source.
    sha256 : str
        Hex digest of the source bytes (written into reports).
    path : str
        Where it was read from (``"<string>"`` for text, ``"<Spec>"`` for a :class:`Spec` object).
    """

    spec: Spec | ComparisonSpec
    text: str
    sha256: str
    path: str

    @property
    def is_comparison(self) -> bool:
        """True for a spec naming several controllers (``controllers:``)."""
        return isinstance(self.spec, ComparisonSpec)

    def members(self) -> tuple[tuple[str, LoadedSpec], ...]:
        """``(label, LoadedSpec)`` of each controller of a comparison, each the single-controller spec it
        stands for (:meth:`ComparisonSpec.member`): its text is the member's canonical JSON
        (:meth:`from_spec`), its path the comparison's (model files resolve as they do for the comparison).

        Raises
        ------
        SpecError
            The spec names one controller (``controller:``), not several.
        """
        if not isinstance(self.spec, ComparisonSpec):
            raise SpecError("controllers", "this spec names one controller (controller:), not a comparison")
        out = []
        for label, member in self.spec.members():
            canonical = LoadedSpec.from_spec(member)
            out.append((label, LoadedSpec(spec=member, text=canonical.text, sha256=canonical.sha256, path=self.path)))
        return tuple(out)

    @classmethod
    def from_spec(cls, spec: Spec | ComparisonSpec) -> LoadedSpec:
        """Wrap a :class:`Spec` (or :class:`ComparisonSpec`) built in Python; its text is its canonical JSON.

        The canonical JSON is ``spec.model_dump(mode="json")`` with sorted keys and no spaces
        (valid YAML, and a spec that validates to an equal :class:`Spec`); ``sha256`` is the
        digest of that text, so equal specs have equal digests.

        Raises
        ------
        SpecError
            ``spec`` is not a :class:`Spec`.
        """
        if not isinstance(spec, Spec | ComparisonSpec):
            raise SpecError("spec", f"expected a designkit Spec, got {type(spec).__name__}")
        text = json.dumps(spec.model_dump(mode="json"), sort_keys=True, separators=(",", ":"), allow_nan=False)
        return cls(spec=spec, text=text, sha256=hashlib.sha256(text.encode()).hexdigest(), path="<Spec>")


# --------------------------------------------------------------------------------------------
# Bounded YAML: composition with node and depth limits, construction of JSON types only
# --------------------------------------------------------------------------------------------

_TAG = "tag:yaml.org,2002:"
_STR, _INT, _FLOAT, _BOOL, _NULL = (_TAG + t for t in ("str", "int", "float", "bool", "null"))
_SEQ, _MAP, _MERGE = _TAG + "seq", _TAG + "map", _TAG + "merge"

_JSON_INT = re.compile(r"^[-+]?(?:0|[1-9][0-9]*)$")
"""Integers as JSON writes them: decimal, no leading zero (YAML 1.1's ``0x1F``, ``017``, ``1_000``, ``1:30`` are
text)."""

_JSON_FLOAT = re.compile(r"^[-+]?(?:(?:0|[1-9][0-9]*)(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?|\.[0-9]+(?:[eE][-+]?[0-9]+)?"
                         r"|\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$")
"""Floats as JSON writes them (``2.5``, ``1e-3``, ``2.5E4``), plus ``.5`` and YAML's ``.inf`` / ``.nan`` (refused
later as not finite, with the key path)."""


def _resolvers() -> dict[str | None, list[tuple[str, re.Pattern[str]]]]:
    """SafeLoader's implicit resolvers without dates and ``=`` (strings), with numbers only as JSON writes them."""
    table: dict[str | None, list[tuple[str, re.Pattern[str]]]] = {}
    for first, entries in yaml.SafeLoader.yaml_implicit_resolvers.items():
        kept = [(tag, rx) for tag, rx in entries if tag not in (_TAG + "timestamp", _TAG + "value", _INT, _FLOAT)]
        if kept:
            table[first] = kept
    for first in "-+0123456789.":
        table.setdefault(first, []).extend([(_INT, _JSON_INT), (_FLOAT, _JSON_FLOAT)])
    return table


def _key_text(key: object) -> str:
    """A mapping key as it appears in a key path: control characters escaped, cut to the quote limit."""
    text = str(key)
    if not text.isprintable():
        text = repr(text)[1:-1]
    return shorten(text, QUOTE_LIMIT)


def _join(path: str, part: str) -> str:
    if part.startswith("["):
        return path + part
    return f"{path}.{part}" if path else part


class _Bounds:
    """Composer of a loader that counts nodes (aliases expanded) and nesting while it parses.

    Each composed node records ``(size, height)``: the number of nodes it stands for once aliases
    are expanded, and its nesting height.  An alias adds its target's size to the running count,
    so the count is the size of the expanded document, known before anything is expanded.  Mixed
    into a PyYAML loader ahead of its ``Composer``.
    """

    yaml_implicit_resolvers = _resolvers()

    def _init_bounds(self) -> None:
        self.nodes = 0
        self.depth = 0
        self.where: list[str] = []
        self.sizes: dict[int, tuple[int, int]] = {}

    def key_path(self) -> str:
        """Key path of the node being composed (cut to twice the quote limit)."""
        path = ""
        for part in self.where:
            if part:
                path = _join(path, part)
            if len(path) > 2 * QUOTE_LIMIT:
                return shorten(path, 2 * QUOTE_LIMIT)
        return path

    def _count(self, size: int, height: int) -> None:
        self.nodes += size
        if self.nodes > MAX_NODES:
            raise SpecError(self.key_path(), f"the YAML expands to more than {MAX_NODES:,} nodes (aliases "
                            "counted in full), the limit of a spec")
        if self.depth + height > MAX_DEPTH:
            raise SpecError(self.key_path(), _TOO_DEEP)

    def compose_node(self, parent: Node | None, index: Any) -> Node:
        if isinstance(index, int):
            self.where.append(f"[{index}]")
        elif isinstance(index, ScalarNode):
            self.where.append(_key_text(index.value))
        else:
            self.where.append("")
        try:
            if self.check_event(AliasEvent):
                target = self.anchors.get(self.peek_event().anchor)
                if target is not None:  # an undefined alias is the composer's error
                    size = self.sizes.get(id(target))
                    if size is None:
                        raise SpecError(self.key_path(), "an alias inside the node it names (a recursive "
                                        "structure) cannot be a spec value")
                    self._count(*size)
                return super().compose_node(parent, index)
            collection = self.check_event(SequenceStartEvent, MappingStartEvent)
            self._count(1, 1 if collection else 0)
            self.depth += collection
            try:
                node = super().compose_node(parent, index)
            finally:
                self.depth -= collection
            if isinstance(node, SequenceNode):
                children = [self.sizes[id(c)] for c in node.value]
            elif isinstance(node, MappingNode):
                children = [self.sizes[id(c)] for pair in node.value for c in pair]
            else:
                children = []
            self.sizes[id(node)] = (1 + sum(s for s, _ in children), collection + max((h for _, h in children),
                                                                                       default=0))
            return node
        finally:
            self.where.pop()


class _PyLoader(_Bounds, yaml.SafeLoader):
    """The bounded loader on PyYAML's pure-Python scanner and parser."""

    def __init__(self, stream: str) -> None:
        yaml.SafeLoader.__init__(self, stream)
        self._init_bounds()

    def fetch_flow_collection_start(self, TokenClass: type) -> None:  # noqa: N803 (PyYAML's signature)
        # The scanner looks up to 1024 characters ahead for a possible key and checks every open
        # flow level on each token: refuse deep flow nesting here, before that cost grows.
        if self.flow_level >= MAX_DEPTH:
            mark = self.get_mark()
            raise SpecError(self.key_path(), f"line {mark.line + 1}, column {mark.column + 1}: {_TOO_DEEP}")
        super().fetch_flow_collection_start(TokenClass)


_BoundedLoader: type[_Bounds] = _PyLoader
"""The loader used: libyaml's parser (about five times faster) under the same bounded composer when
PyYAML was built with it, else the pure-Python one."""

if yaml.__with_libyaml__:
    from yaml.composer import Composer
    from yaml.constructor import SafeConstructor
    from yaml.cyaml import CParser
    from yaml.resolver import Resolver

    class _CLoader(_Bounds, Composer, CParser, SafeConstructor, Resolver):
        """The bounded loader on libyaml's parser: PyYAML's Python composer pulls libyaml's events lazily."""

        def __init__(self, stream: str) -> None:
            CParser.__init__(self, stream)
            SafeConstructor.__init__(self)
            Resolver.__init__(self)
            Composer.__init__(self)
            self._init_bounds()

    _BoundedLoader = _CLoader


def _out_of_range(what: str) -> str:
    return f"must be within the floating-point range (|x| <= {_FLOAT_MAX_TEXT}), got {what}"


def _scalar(loader: Any, node: ScalarNode, path: str) -> object:
    tag = node.tag
    if tag == _STR:
        return node.value
    if tag == _NULL:
        return None
    if tag == _BOOL:
        try:
            return loader.construct_yaml_bool(node)
        except (KeyError, ValueError):
            raise SpecError(path, f"not a boolean: {short_repr(node.value)}") from None
    if tag == _INT:
        digits = sum(ch.isdigit() for ch in node.value)
        try:
            value = loader.construct_yaml_int(node)
        except (ValueError, IndexError):  # not an integer (or empty), or more digits than Python converts (4300)
            if digits > 300:
                raise SpecError(path, _out_of_range(f"an integer of {digits} digits")) from None
            raise SpecError(path, f"not an integer: {short_repr(node.value)}") from None
        if abs(value) > 1.7976931348623157e308:
            raise SpecError(path, _out_of_range(short_repr(value)))
        return value
    if tag == _FLOAT:
        try:
            value = loader.construct_yaml_float(node)
        except (ValueError, IndexError):
            raise SpecError(path, f"not a number: {short_repr(node.value)}") from None
        if math.isinf(value) and node.value.replace("_", "").lstrip("+-").lower() != ".inf":
            raise SpecError(path, _out_of_range(short_repr(node.value)))
        return value
    raise _tag_error(node, path)


def _tag_error(node: Node, path: str) -> SpecError:
    shown = _key_text("!!" + node.tag[len(_TAG):] if node.tag.startswith(_TAG) else node.tag)
    if node.tag in (_STR, _INT, _FLOAT, _BOOL, _NULL, _SEQ, _MAP):
        kind = {SequenceNode: "a list", MappingNode: "a mapping"}.get(type(node), "a scalar")
        return SpecError(path, f"YAML tag {shown} cannot be put on {kind}")
    return SpecError(path, f"YAML tag {shown} is not allowed: a spec holds only strings, numbers, booleans, null, "
                     "lists and mappings")


def _construct(loader: Any, node: Node, path: str = "") -> object:
    """The Python value of a composed node: JSON types only, duplicate keys refused, key paths in errors."""
    if isinstance(node, ScalarNode):
        return _scalar(loader, node, path)
    if isinstance(node, SequenceNode):
        if node.tag != _SEQ:
            raise _tag_error(node, path)
        return [_construct(loader, item, f"{path}[{k}]") for k, item in enumerate(node.value)]
    if not isinstance(node, MappingNode) or node.tag != _MAP:
        raise _tag_error(node, path)
    out: dict[object, object] = {}
    lines: dict[object, int] = {}
    merged: list[Node] = []
    for key_node, value_node in node.value:
        if key_node.tag == _MERGE:
            merged.append(value_node)
            continue
        if not isinstance(key_node, ScalarNode):
            raise SpecError(path, "a mapping key must be a string or a number, not a list or a mapping")
        key = _scalar(loader, key_node, path)
        here = _join(path, _key_text(key))
        if key in out:
            raise SpecError(here, f"duplicate key (first given on line {lines[key]})")
        lines[key] = key_node.start_mark.line + 1
        out[key] = _construct(loader, value_node, here)
    for source in merged:  # YAML merge keys (<<: *base): explicit keys win, then earlier merges
        for item in source.value if isinstance(source, SequenceNode) else [source]:
            value = _construct(loader, item, path)
            if not isinstance(value, dict):
                raise SpecError(path, "a merge key (<<) must name a mapping or a list of mappings")
            for key, val in value.items():
                out.setdefault(key, val)
    return out


def _load_yaml(text: str, loader_class: type[_Bounds] | None = None) -> object:
    """Parse YAML text within the limits of the spec format; ``SpecError`` for anything else."""
    loader_class = loader_class or _BoundedLoader
    loader = loader_class(text)
    try:
        node = loader.get_single_node()
        return None if node is None else _construct(loader, node)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        if "maximum nesting depth" in problem and loader_class is not _PyLoader:
            # libyaml >= 0.2.5 (PyYAML 6.0.4's wheels) scans a flow collection ahead and stops at its own
            # 1000-level limit before the composer knows where it is: the pure-Python scanner refuses the
            # same text at MAX_DEPTH levels with the key path (cheap: it stops there)
            return _load_yaml(text, _PyLoader)
        raise SpecError("", shorten(f"malformed YAML: {where}{problem}", MAX_MESSAGE)) from None
    finally:
        loader.dispose()


# --------------------------------------------------------------------------------------------
# pydantic errors as one line with a key path
# --------------------------------------------------------------------------------------------

_UNION_KEYS = frozenset({"plant", "controller", "nonlinearity", "trajectory"})
"""Keys whose value is a discriminated union: pydantic puts the chosen tag right after them."""


def _key_path(loc: tuple[int | str, ...]) -> str:
    parts: list[str] = []
    previous: int | str | None = None
    before: int | str | None = None
    for item in loc:
        in_entry = before == "controllers" and isinstance(previous, int)  # controllers[i].<tag>
        tag = item in _UNION_TAGS and (previous in _UNION_KEYS or in_entry)
        before, previous = previous, item
        if isinstance(item, int):
            parts.append(f"[{item}]")
        elif tag or "[" in str(item) or str(item).startswith("function-"):
            continue  # pydantic's tag for discriminated unions / validator wrappers
        else:
            parts.append(("." if parts else "") + _key_text(item))
    return "".join(parts)


def _message(err: dict) -> str:
    msg = str(err.get("msg", "invalid value"))
    msg = re.sub(r"^(Value error|Assertion failed), ", "", msg)
    if err.get("type") == "extra_forbidden":
        return "unknown key"
    if err.get("type") == "missing":
        return "missing required field"
    if err.get("type") == "union_tag_invalid":
        ctx = err.get("ctx") or {}
        return (f"Input tag {short_repr(ctx.get('tag'))} found using {ctx.get('discriminator')} does not match any "
                f"of the expected tags: {ctx.get('expected_tags')}")
    value = err.get("input")
    if isinstance(value, int | float | str | bool) and "got" not in msg:
        return f"{msg}, got {short_repr(value)}"
    return msg


def key_path(loc: tuple[int | str, ...]) -> str:
    """The spec key path of a pydantic error location (``("controller", "poles", 2)`` -> ``controller.poles[2]``)."""
    return _key_path(loc)


def message(err: dict) -> str:
    """The one-line message of a pydantic error (:func:`parse_spec`'s wording)."""
    return _message(err)


def _check_size(size: int, what: str, *, at_least: bool = False) -> None:
    if size > MAX_SPEC_BYTES:
        amount = "more than 1 MiB" if at_least else f"{size / 2**20:.1f} MiB"
        raise SpecError("", f"{what} is {amount}, over the limit of {MAX_SPEC_BYTES // 2**20} MiB "
                        f"({MAX_SPEC_BYTES:,} bytes) for a spec")


def parse_spec(text: str | bytes, *, path: str = "<string>") -> LoadedSpec:
    """Validate YAML text as a spec.

    Parameters
    ----------
    text : str or bytes
        The YAML source; ``bytes`` are decoded as UTF-8.  At most :data:`MAX_SPEC_BYTES`.
    path : str
        Where the text came from, for :attr:`LoadedSpec.path` (relative model files such as a
        URDF are resolved against its folder unless it starts with ``<``).

    Raises
    ------
    SpecError
        Text of the wrong type or over the size limit, malformed YAML or beyond its limits, any
        schema violation, with the key path of the first problem.
    """
    if isinstance(text, bytes | bytearray):
        _check_size(len(text), "the spec text")
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SpecError("text", f"spec bytes are not UTF-8 ({exc.reason} at byte {exc.start})") from None
    if not isinstance(text, str):
        raise SpecError("text", f"expected the YAML text of a spec (str, or UTF-8 bytes), got {type(text).__name__}; "
                        "use load_spec for a file")
    if not isinstance(path, str):
        raise SpecError("path", f"expected a str, got {type(path).__name__}")
    text, path = arguments.text(text, "text"), arguments.text(path, "path")
    _check_size(len(text), "the spec text")
    source = text.encode("utf-8", errors="surrogatepass")
    _check_size(len(source), "the spec text")
    data = _load_yaml(text)
    if not isinstance(data, dict):
        raise SpecError("", f"a spec must be a YAML mapping, got {type(data).__name__}")
    if "controllers" in data and "controller" in data:
        raise SpecError("controllers", "give either controller (one controller) or controllers (a comparison of "
                        "several), not both")
    model = ComparisonSpec if "controllers" in data else Spec
    try:
        spec = model.model_validate(data)
    except ValidationError as exc:
        err = exc.errors(include_url=False, include_context=True)[0]
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
        raise SpecError(key, shorten(msg, MAX_MESSAGE)) from None
    digest = hashlib.sha256(source).hexdigest()
    return LoadedSpec(spec=spec, text=text, sha256=digest, path=path)


def load_spec(path: str | os.PathLike[str]) -> LoadedSpec:
    """Read and validate a spec file.

    Parameters
    ----------
    path : str or os.PathLike
        The file (UTF-8 YAML, at most :data:`MAX_SPEC_BYTES`).  YAML text itself goes to
        :func:`parse_spec`.

    Raises
    ------
    SpecError
        A path of the wrong type, a missing, unreadable or oversized file (refused before it is
        read in full), malformed YAML or a schema violation.
    """
    if isinstance(path, bytes | bytearray):
        raise SpecError("path", f"expected a file path (str or os.PathLike), got {type(path).__name__}; "
                        "for YAML text use parse_spec")
    p = arguments.path(path, "path")
    shown = shorten(str(p), PATH_LIMIT)
    try:
        with p.open("rb") as fh:
            _check_size(os.fstat(fh.fileno()).st_size, f"spec file {shown}")
            data = fh.read(MAX_SPEC_BYTES + 1)  # also bounds what a pipe or device can hand over
            _check_size(len(data), f"spec file {shown}", at_least=True)
    except FileNotFoundError:
        raise SpecError("", f"spec file not found: {shown}") from None
    except OSError as exc:
        raise SpecError("", f"cannot read spec file {shown}: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise SpecError("", f"cannot read spec file {shown}: not UTF-8 ({exc.reason} at byte {exc.start})") from None
    text = text.replace("\r\n", "\n").replace("\r", "\n")  # as text mode reads it
    return parse_spec(text, path=str(p))


def load_yaml(text: str) -> object:
    """YAML text as the spec format reads it, without validating it as a spec: JSON's types only, numbers as JSON
    writes them (``1e7`` and ``2.6e0`` are floats), within the node, depth and range limits (module docstring).

    Raises
    ------
    SpecError
        Malformed YAML or beyond its limits, with the key path where it can be named.
    """
    return _load_yaml(text)
